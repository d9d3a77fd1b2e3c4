// The dashboard's HTTP server: Boost.Beast on one Asio thread, asynchronous per connection
// (the pattern of Beast's example/http/server/async). HTTP parsing is Beast's: a browser, curl or a
// script talk to it, and a hand-written parser is where malformed requests crash servers.
#include <fmt/format.h>

#include <atomic>
#include <boost/asio/dispatch.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <charconv>
#include <chrono>
#include <memory>
#include <optional>
#include <thread>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/log.hpp"
#include "twinwatch/ui/dashboard.hpp"

namespace twinwatch::ui {

namespace beast = boost::beast;
namespace http = beast::http;
namespace net = boost::asio;
using tcp = net::ip::tcp;

namespace {
// a request is a GET line and a few headers: anything larger is not a browser's or a script's
constexpr std::uint32_t kHeaderLimit = 16 * 1024, kBodyLimit = 4 * 1024;
// an idle keep-alive connection is closed after this (a page polls every fraction of a second)
constexpr auto kIdleTimeout = std::chrono::seconds(30);

// ?since=N of a target "/api/state?since=N"; false: the parameter is there but no whole number
bool parse_since(std::string_view query, std::uint64_t& since, std::string& why) {
  since = 0;
  size_t at = 0;
  while (at <= query.size()) {
    const size_t amp = std::min(query.find('&', at), query.size());
    const std::string_view kv = query.substr(at, amp - at);
    if (kv.substr(0, 6) == "since=") {
      const std::string_view v = kv.substr(6);
      const auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), since);
      if (ec != std::errc() || p != v.data() + v.size() || v.empty()) {
        why = fmt::format("since must be a whole number >= 0 (the cursor of the last answer), got '{}'", v);
        return false;
      }
    }
    at = amp + 1;
  }
  return true;
}

class Session : public std::enable_shared_from_this<Session> {
 public:
  Session(tcp::socket&& socket, const DashboardFeed& feed, std::atomic<long>& requests)
      : stream_(std::move(socket)), feed_(feed), requests_(requests) {}
  void run() { net::dispatch(stream_.get_executor(), beast::bind_front_handler(&Session::read, shared_from_this())); }

 private:
  void read() {
    parser_.emplace();
    parser_->header_limit(kHeaderLimit);
    parser_->body_limit(kBodyLimit);
    stream_.expires_after(kIdleTimeout);
    http::async_read(stream_, buffer_, *parser_, beast::bind_front_handler(&Session::on_read, shared_from_this()));
  }

  void on_read(beast::error_code ec, std::size_t) {
    if (ec == http::error::end_of_stream || ec == beast::error::timeout || ec == net::error::operation_aborted ||
        ec == net::error::connection_reset || ec == net::error::eof)
      return close();
    if (ec) {
      // a request Beast cannot parse (or one too large): said in a 400, then the connection closes
      answer(http::status::bad_request, "text/plain; charset=utf-8", fmt::format("bad request: {}\n", ec.message()), false, 11);
      return;
    }
    const auto& req = parser_->get();
    ++requests_;
    const bool keep = req.keep_alive();
    const int version = req.version();
    if (req.method() != http::verb::get && req.method() != http::verb::head) {
      answer(http::status::method_not_allowed, "text/plain; charset=utf-8",
             fmt::format("{} is not served: the dashboard answers GET and HEAD\n", std::string(req.method_string())), keep, version,
             req.method() == http::verb::head, "GET, HEAD");
      return;
    }
    const bool head = req.method() == http::verb::head;
    const std::string_view target(req.target().data(), req.target().size());
    const size_t q = target.find('?');
    const std::string_view path = target.substr(0, q), query = q == std::string_view::npos ? std::string_view() : target.substr(q + 1);
    if (path == "/" || path == "/index.html") {
      answer(http::status::ok, "text/html; charset=utf-8", dashboard_page(), keep, version, head);
    } else if (path == "/api/state") {
      std::uint64_t since = 0;
      std::string why;
      if (!parse_since(query, since, why)) answer(http::status::bad_request, "text/plain; charset=utf-8", why + "\n", keep, version, head);
      else answer(http::status::ok, "application/json", feed_.json_since(since), keep, version, head);
    } else {
      answer(http::status::not_found, "text/plain; charset=utf-8",
             fmt::format("{} is not served: / is the page, /api/state?since=N its data (JSON)\n", path), keep, version, head);
    }
  }

  void answer(http::status status, const char* type, std::string body, bool keep, int version, bool head = false, const char* allow = nullptr) {
    auto res = std::make_shared<http::response<http::string_body>>(status, version);
    res->set(http::field::server, "twinwatch");
    res->set(http::field::content_type, type);
    res->set(http::field::cache_control, "no-store");
    if (allow) res->set(http::field::allow, allow);
    res->keep_alive(keep);
    const size_t size = body.size();
    if (!head) res->body() = std::move(body);
    res->prepare_payload();
    if (head) res->content_length(size);
    http::async_write(stream_, *res, [self = shared_from_this(), res, keep](beast::error_code ec, std::size_t) {
      if (ec || !keep) return self->close();
      self->read();
    });
  }

  void close() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  const DashboardFeed& feed_;
  std::atomic<long>& requests_;
};

}  // namespace

struct DashboardServer::Impl {
  net::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  const DashboardFeed& feed;
  std::atomic<long> requests{0};
  std::thread thread;
  std::atomic<bool> stopped{false};
  unsigned short port = 0;

  explicit Impl(const DashboardFeed& f) : feed(f) {}

  void accept() {
    acceptor.async_accept(net::make_strand(ioc), [this](beast::error_code ec, tcp::socket socket) {
      if (ec == net::error::operation_aborted || !acceptor.is_open()) return;
      if (!ec) std::make_shared<Session>(std::move(socket), feed, requests)->run();
      // (an accept that failed, e.g. too many open files, is not the end of serving)
      else log::warn(fmt::format("dashboard: a connection could not be accepted: {}", ec.message()));
      accept();
    });
  }
};

DashboardServer::DashboardServer(const DashboardFeed& feed, const std::string& host, unsigned short port)
    : impl_(std::make_unique<Impl>(feed)) {
  const std::string where = fmt::format("{}:{}", host, port);
  beast::error_code ec;
  tcp::resolver resolver(impl_->ioc);
  const auto found = resolver.resolve(host, std::to_string(port), tcp::resolver::passive | tcp::resolver::numeric_service, ec);
  if (ec || found.empty())
    throw PathError(fmt::format("dashboard: cannot listen on {}: {} is not an address of this machine ({})", where, host,
                                ec ? ec.message() : "no address"));
  const tcp::endpoint endpoint = found.begin()->endpoint();
  auto& a = impl_->acceptor;
  // open, reuse (a restart within TIME_WAIT of the last run), bind, listen: the first error is said
  a.open(endpoint.protocol(), ec);
  if (!ec) a.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(endpoint, ec);
  if (!ec) a.listen(net::socket_base::max_listen_connections, ec);
  if (ec)
    throw PathError(fmt::format("dashboard: cannot listen on {}: {}{}", where, ec.message(),
                                ec == net::error::address_in_use ? " (another program serves that port: choose another with --listen HOST:PORT)"
                                : ec == net::error::access_denied ? " (ports below 1024 need privileges: choose one above)"
                                                                   : ""));
  impl_->port = a.local_endpoint().port();
  impl_->accept();
  impl_->thread = std::thread([i = impl_.get()] {
    // a handler that throws (out of memory) must not take the monitoring down with it
    for (;;) {
      try {
        i->ioc.run();
        return;
      } catch (const std::exception& e) {
        log::warn(fmt::format("dashboard: {}", e.what()));
      }
    }
  });
}

DashboardServer::~DashboardServer() { stop(); }

unsigned short DashboardServer::port() const { return impl_->port; }

long DashboardServer::requests() const { return impl_->requests.load(); }

void DashboardServer::stop() {
  if (impl_->stopped.exchange(true)) return;
  impl_->ioc.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
  // (the loop's thread has ended: the acceptor is closed here, so the port is free at once)
  beast::error_code ec;
  impl_->acceptor.close(ec);
}

}  // namespace twinwatch::ui

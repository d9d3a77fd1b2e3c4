// libFuzzer target for the RTDE packet parser: every byte string is a TCP stream that either a
// client sent to the virtual controller or a controller sent to the client.
//
//   - ServerSession: the stream fed in two chunks (split where the first byte says), replies
//     checked to be well-framed packages themselves;
//   - Framer + every decoder with both protocol versions (as the client's handshake does);
//   - data packages decoded against a 30-field recipe, v2 and v1.
// Anything but a ProtocolError escaping, a sanitizer report, or a broken invariant is a finding;
// scripts/fuzz.sh runs it, and findings go to fuzz/regressions/rtde/ (replayed by ctest).
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <vector>

#include "twinwatch/device/rtde_protocol.hpp"
#include "twinwatch/device/rtde_server.hpp"

namespace rtde = twinwatch::device::rtde;

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "invariant broken: %s\n", what);
    std::abort();
  }
}

const rtde::OutputRecipe& recipe(int protocol) {
  static const auto make = [](int p) {
    std::vector<std::string> names, types;
    for (const auto& f : rtde::output_fields()) {
      if (names.size() == 30) break;
      names.push_back(f.name);
      types.emplace_back(rtde::type_name(f.type));
    }
    return rtde::OutputRecipe::from_reply(names, {1, types}, p);
  };
  static const rtde::OutputRecipe r2 = make(2), r1 = make(1);
  return protocol == 2 ? r2 : r1;
}

void decode_all(const rtde::Package& p) {
  static std::vector<double> values(2000);
  for (int protocol : {1, 2}) {
    try { rtde::decode_request_protocol_version(p); } catch (const rtde::ProtocolError&) {}
    try { rtde::decode_accepted_reply(p); } catch (const rtde::ProtocolError&) {}
    try { rtde::decode_urcontrol_version_reply(p); } catch (const rtde::ProtocolError&) {}
    try { rtde::decode_setup_outputs(p, protocol); } catch (const rtde::ProtocolError&) {}
    try { rtde::decode_setup_inputs(p); } catch (const rtde::ProtocolError&) {}
    try {
      const rtde::SetupReply r = rtde::decode_setup_reply(p, protocol);
      std::vector<std::string> names(r.types.size(), "x");
      try { rtde::OutputRecipe::from_reply(names, r, protocol); } catch (const rtde::ProtocolError&) {}
    } catch (const rtde::ProtocolError&) {}
    try { rtde::decode_text_message(p, protocol); } catch (const rtde::ProtocolError&) {}
    try { rtde::decode_data_package(p, recipe(protocol), values.data()); } catch (const rtde::ProtocolError&) {}
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // 1. as a stream into the framer: every package is within the input and within limits
  {
    rtde::Framer f;
    f.feed(data, size);
    rtde::Package p;
    std::size_t consumed = 0;
    try {
      while (f.next(p)) {
        check(p.payload.size() + 3 <= rtde::kMaxPackageSize, "package within kMaxPackageSize");
        consumed += p.payload.size() + 3;
        check(consumed <= size, "packages within the input");
        decode_all(p);
      }
    } catch (const rtde::ProtocolError&) {
    }
  }
  // 2. as a client's bytes to the virtual controller, in two chunks
  {
    rtde::ServerSession s({5, 23, 0, 0}, 500.0);
    const std::size_t cut = size ? data[0] % (size + 1) : 0;
    rtde::Bytes out;
    try {
      s.on_bytes(data, cut, out);
      s.on_bytes(data + cut, size - cut, out);
    } catch (const rtde::ProtocolError&) {
    }
    std::vector<double> frame(static_cast<std::size_t>(rtde::frame_scalars()), 1.0);
    for (int k = 0; k < 3; ++k) s.on_cycle(frame.data(), out);
    // the replies themselves are a valid package stream
    rtde::Framer f;
    f.feed(out.data(), out.size());
    rtde::Package p;
    std::size_t n = 0;
    while (f.next(p)) n += p.payload.size() + 3;
    check(n == out.size(), "server replies are well framed");
  }
  return 0;
}

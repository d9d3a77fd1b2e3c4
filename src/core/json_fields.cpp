#include "twinwatch/core/json_fields.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <limits>
#include <optional>
#include <set>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/numbers.hpp"

namespace twinwatch {

namespace {

// a value longer than this is named by its type in messages, not printed
constexpr size_t kBriefChars = 80;

// SAX pass that stops at the first key an object already holds, and keeps its path: nlohmann's
// DOM parser keeps the last of two equal keys without a word, so a file edited by hand can carry a
// value that is silently ignored
class DuplicateKeys {
 public:
  using json = nlohmann::json;
  std::string duplicate;  // path of the repeated key ("" if none)

  bool null() { return value(); }
  bool boolean(bool) { return value(); }
  bool number_integer(json::number_integer_t) { return value(); }
  bool number_unsigned(json::number_unsigned_t) { return value(); }
  bool number_float(json::number_float_t, const json::string_t&) { return value(); }
  bool string(json::string_t&) { return value(); }
  bool binary(json::binary_t&) { return value(); }
  bool start_object(std::size_t) {
    frames_.push_back({true, child(), {}, {}, 0});
    return true;
  }
  bool key(json::string_t& k) {
    Frame& f = frames_.back();
    if (!f.keys.insert(k).second) {
      duplicate = json_member(f.path, k);
      return false;
    }
    f.key = k;
    return true;
  }
  bool end_object() { return end(); }
  bool start_array(std::size_t) {
    frames_.push_back({false, child(), {}, {}, 0});
    return true;
  }
  bool end_array() { return end(); }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) { return false; }

 private:
  struct Frame {
    bool object;
    std::string path;
    std::set<std::string> keys;  // objects: the keys so far
    std::string key;             // objects: the key of the value being read
    size_t index;                // arrays: the element being read
  };
  std::vector<Frame> frames_;

  // the path of the value that starts now
  std::string child() const {
    if (frames_.empty()) return "";
    const Frame& f = frames_.back();
    return f.object ? json_member(f.path, f.key) : json_element(f.path, f.index);
  }
  // a value is complete: an array moves on to its next element
  bool value() {
    if (!frames_.empty() && !frames_.back().object) ++frames_.back().index;
    return true;
  }
  bool end() {
    frames_.pop_back();
    return value();
  }
};

}  // namespace

nlohmann::json parse_json(const std::string& text, const std::string& origin, const std::string& field) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw ParseError(origin, 0, field, fmt::format("not valid JSON: {}", e.what()));
  } catch (const nlohmann::json::out_of_range& e) {  // a number beyond a double ("1e400")
    throw ParseError(origin, 0, field, fmt::format("expected numbers within the range of a double: {}", e.what()));
  }
  // the text is valid JSON: the second pass only looks for a repeated key
  require_unique_keys(text, origin, field);
  return j;
}

void require_unique_keys(const std::string& text, const std::string& origin, const std::string& field) {
  DuplicateKeys keys;
  nlohmann::json::sax_parse(text, &keys);
  if (!keys.duplicate.empty())
    throw ParseError(origin, 0, field.empty() ? keys.duplicate : json_member(field, keys.duplicate),
                     "the key appears twice in its object, expected once (a JSON reader would keep only one of the values)");
}

std::string json_brief(const nlohmann::json& v) {
  const std::string s = v.dump();
  if (s.size() <= kBriefChars) return s;
  if (v.is_array()) return fmt::format("an array of {} values", v.size());
  if (v.is_object()) return fmt::format("an object of {} keys", v.size());
  return fmt::format("a {} of {} characters", v.type_name(), s.size());
}

std::string json_member(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : fmt::format("{}.{}", path, key);
}

std::string json_element(const std::string& path, size_t i) { return fmt::format("{}[{}]", path, i); }

double json_number(const nlohmann::json& v, const std::string& origin, const std::string& field) {
  if (!v.is_number()) throw ParseError(origin, 0, field, fmt::format("expected a number, got {}", json_brief(v)));
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw ParseError(origin, 0, field, fmt::format("expected a finite number, got {}", x));
  return x;
}

JsonFields::JsonFields(const nlohmann::json& j, std::string origin, std::string path)
    : j_(j), origin_(std::move(origin)), path_(std::move(path)) {
  if (!j_.is_object()) throw ParseError(origin_, 0, path_, fmt::format("expected an object, got {}", json_brief(j_)));
}

const nlohmann::json& JsonFields::need(const char* key) const {
  if (!j_.contains(key)) fail(key, "missing required field");
  return j_.at(key);
}

JsonFields JsonFields::object(const char* key) const { return JsonFields(need(key), origin_, field(key)); }

double JsonFields::number(const char* key) const { return json_number(need(key), origin_, field(key)); }

double JsonFields::positive(const char* key) const {
  const double x = number(key);
  if (!(x > 0.0)) fail(key, fmt::format("expected a number > 0, got {}", x));
  return x;
}

double JsonFields::nonnegative(const char* key) const {
  const double x = number(key);
  if (!(x >= 0.0)) fail(key, fmt::format("expected a number >= 0, got {}", x));
  return x;
}

int JsonFields::whole(const char* key) const {
  const nlohmann::json& v = need(key);
  const std::optional<int> x = v.is_number() ? whole_int(v.get<double>()) : std::nullopt;
  if (!x) fail(key, fmt::format("expected a whole number within +-{}, got {}", std::numeric_limits<int>::max(), json_brief(v)));
  return *x;
}

bool JsonFields::boolean(const char* key) const {
  const nlohmann::json& v = need(key);
  if (!v.is_boolean()) fail(key, fmt::format("expected true or false, got {}", json_brief(v)));
  return v.get<bool>();
}

std::string JsonFields::text(const char* key) const {
  const nlohmann::json& v = need(key);
  if (!v.is_string()) fail(key, fmt::format("expected a string, got {}", json_brief(v)));
  return v.get<std::string>();
}

std::vector<std::string> JsonFields::texts(const char* key) const {
  const nlohmann::json& a = need(key);
  if (!a.is_array()) fail(key, fmt::format("expected an array of strings, got {}", json_brief(a)));
  std::vector<std::string> out;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!a[i].is_string()) throw ParseError(origin_, 0, json_element(field(key), i), fmt::format("expected a string, got {}", json_brief(a[i])));
    out.push_back(a[i].get<std::string>());
  }
  return out;
}

std::vector<double> JsonFields::numbers(const char* key, size_t size) const {
  const nlohmann::json& a = need(key);
  if (!a.is_array()) fail(key, fmt::format("expected an array of numbers, got {}", json_brief(a)));
  if (size > 0 && a.size() != size) fail(key, fmt::format("expected {} values, got {}", size, a.size()));
  std::vector<double> out;
  out.reserve(a.size());
  for (size_t i = 0; i < a.size(); ++i) out.push_back(json_number(a[i], origin_, json_element(field(key), i)));
  return out;
}

void JsonFields::only(std::initializer_list<std::string_view> known) const {
  for (const auto& [k, v] : j_.items()) {
    bool ok = false;
    for (std::string_view n : known) ok = ok || n == k;
    if (!ok) fail(k, fmt::format("unknown key, expected one of: {}", fmt::join(known, ", ")));
  }
}

void JsonFields::fail(std::string_view key, const std::string& what) const { throw ParseError(origin_, 0, field(key), what); }

}  // namespace twinwatch

#pragma once
/// @file json_fields.hpp
/// Checked reading of the JSON files users hand the program (the twin file and its blocks, the
/// scenario labels). Every error is a ParseError naming the file and the field's JSON path
/// ("joints[2].c_gen", "monitor.dynamic[1].rho") with the expected and the actual value; a missing
/// field is "missing required field", a key the format does not have is named with the keys it
/// does have.
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace twinwatch {

/// Parses JSON text. Throws ParseError(origin, 0, field, ...) for text that is not JSON, a number
/// beyond a double ("1e400"), or an object holding the same key twice (a JSON reader keeps one of
/// them silently), naming the key's path below `field`.
nlohmann::json parse_json(const std::string& text, const std::string& origin, const std::string& field = "");

/// The duplicate-key half of parse_json, for a reader that parses the (valid JSON) text itself:
/// throws ParseError(origin, 0, path of the repeated key below `field`, ...) for a key given twice.
void require_unique_keys(const std::string& text, const std::string& origin, const std::string& field = "");

/// A value as it reads in a message: itself when short (-1, "x", null, [1, 2]), else its type.
std::string json_brief(const nlohmann::json& v);

/// The path of member `key` of the object at `path` ("a.b"; "b" at the root).
std::string json_member(const std::string& path, std::string_view key);
/// The path of element `i` of the array at `path` ("a[3]").
std::string json_element(const std::string& path, size_t i);

/// One JSON object of a file and its path; the accessors check the type and range of a field and
/// throw ParseError naming the file, the field's path, the expected and the actual value.
/// Holds a reference: `j` must outlive it.
class JsonFields {
 public:
  /// Throws ParseError when `j` is not an object.
  JsonFields(const nlohmann::json& j, std::string origin, std::string path);

  const nlohmann::json& json() const { return j_; }
  const std::string& origin() const { return origin_; }
  const std::string& path() const { return path_; }
  /// The path of member `key`.
  std::string field(std::string_view key) const { return json_member(path_, key); }

  bool has(const char* key) const { return j_.contains(key); }
  /// The value at `key`; "missing required field" when absent.
  const nlohmann::json& need(const char* key) const;
  /// The object at `key`.
  JsonFields object(const char* key) const;
  /// A finite number.
  double number(const char* key) const;
  /// A finite number > 0.
  double positive(const char* key) const;
  /// A finite number >= 0.
  double nonnegative(const char* key) const;
  /// A whole number within int's range.
  int whole(const char* key) const;
  bool boolean(const char* key) const;
  std::string text(const char* key) const;
  /// An array of strings.
  std::vector<std::string> texts(const char* key) const;
  /// An array of finite numbers (`size` > 0: exactly that many).
  std::vector<double> numbers(const char* key, size_t size = 0) const;

  /// Throws ParseError naming the first key that is not one of `known`, and listing them.
  void only(std::initializer_list<std::string_view> known) const;
  /// Throws ParseError(origin, 0, field(key), what).
  [[noreturn]] void fail(std::string_view key, const std::string& what) const;

 private:
  const nlohmann::json& j_;
  std::string origin_;
  std::string path_;
};

/// A finite number at path `field` of `origin` (an array element, say); ParseError otherwise.
double json_number(const nlohmann::json& v, const std::string& origin, const std::string& field);

}  // namespace twinwatch

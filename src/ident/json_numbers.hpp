#pragma once
// Whole numbers from the twin file's JSON (twin_model.cpp, learned_model.cpp, mlp.cpp): a field that
// is not a whole number within int's range is a ParseError naming the file and field.
#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/numbers.hpp"

namespace twinwatch::ident {

inline int json_whole(const nlohmann::json& v, const std::string& origin, const std::string& field) {
  const std::optional<int> x = v.is_number() ? whole_int(v.get<double>()) : std::nullopt;
  if (!x) throw ParseError(origin, 0, field, fmt::format("expected a whole number, got {}", v.dump()));
  return *x;
}

inline std::vector<int> json_wholes(const nlohmann::json& a, const std::string& origin, const std::string& field) {
  if (!a.is_array()) throw ParseError(origin, 0, field, fmt::format("expected an array of whole numbers, got {}", a.type_name()));
  std::vector<int> v;
  for (size_t i = 0; i < a.size(); ++i) v.push_back(json_whole(a[i], origin, fmt::format("{}[{}]", field, i)));
  return v;
}

}  // namespace twinwatch::ident

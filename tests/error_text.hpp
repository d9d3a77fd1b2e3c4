#pragma once
// The message of the exception of type E that `f` throws, or "no error": the tests of a parser's or
// a validator's messages compare it (every bad input must name its file, field, expected and actual).
#include <string>

namespace twinwatch::test {

template <class E, class F>
std::string error_text(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace twinwatch::test

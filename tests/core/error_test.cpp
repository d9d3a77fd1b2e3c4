#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "twinwatch/core/error.hpp"

namespace twinwatch {
namespace {

TEST(ParseError, MessageNamesFileLineAndField) {
  const ParseError e("rec.csv", 12, "actual_q_3", "expected a number, got 'abc'");
  EXPECT_STREQ(e.what(), "rec.csv:12: field 'actual_q_3': expected a number, got 'abc'");
  EXPECT_EQ(e.line(), 12);
  EXPECT_EQ(e.field(), "actual_q_3");
}

TEST(CheckSize, MismatchThrowsWithHint) {
  EXPECT_NO_THROW(check_size("q", 6, 6));
  try {
    check_size("q", 5, 6, "model.n_dof");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "q has size 5, expected 6 (model.n_dof)");
  }
}

}  // namespace
}  // namespace twinwatch

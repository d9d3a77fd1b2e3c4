#include "twinwatch/core/file_io.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace twinwatch {
namespace {

namespace fs = std::filesystem;

std::string content(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// one directory per test: ctest runs the test cases as parallel processes
fs::path dir() {
  const fs::path d = fs::path(::testing::TempDir()) / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// validate writes its predictions as they come: a run that fails part-way (a recording found
// changed while it was read) must leave what the file held, and no temporary beside it
TEST(ReplacingFile, AnOutputIsPutInPlaceOnlyWhenCommitted) {
  const fs::path d = dir(), p = d / "pred.csv";
  std::ofstream(p) << "the last good run\n";
  {
    ReplacingFile out(p.string());
    out.stream() << "half of a run";
  }  // (not committed: the run failed)
  EXPECT_EQ(content(p), "the last good run\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(d), fs::directory_iterator{}), 1) << "a temporary was left beside it";
  {
    ReplacingFile out(p.string());
    out.stream() << "a whole run\n";
    EXPECT_EQ(content(p), "the last good run\n") << "replaced before the commit";
    out.commit();
  }
  EXPECT_EQ(content(p), "a whole run\n");
  // a new file appears only with its commit
  const fs::path q = d / "new.csv";
  {
    ReplacingFile out(q.string());
    out.stream() << "x";
  }
  EXPECT_FALSE(fs::exists(q));
  // a link stays a link: what it points to is replaced
  const fs::path target = d / "target.csv", link = d / "link.csv";
  std::ofstream(target) << "old\n";
  fs::create_symlink(target, link);
  {
    ReplacingFile out(link.string());
    out.stream() << "new\n";
    out.commit();
  }
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(content(target), "new\n");
  {
    ReplacingFile out(link.string());
    out.stream() << "part";
  }
  EXPECT_TRUE(fs::is_symlink(link)) << "a failed run removed the link";
  EXPECT_EQ(content(target), "new\n");
  EXPECT_THROW(ReplacingFile((d / "no_such_dir" / "x.csv").string()), PathError);
}

}  // namespace
}  // namespace twinwatch

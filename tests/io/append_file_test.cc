// A file written as a program runs (io/append_file.h): appends land whole and in order,
// a full disk is an error naming the file.
#include "io/append_file.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

TEST(AppendFile, AppendsLandInOrderAndAnEarlierFileIsEmptied) {
  const std::string d = testing::TempDir("append_file");
  testing::WriteText(d + "/log.csv", "an earlier run's file\n");
  {
    AppendFile f(d + "/sub/log.csv");  // a missing folder is made
    f.Append("a,b\n");
    f.Append("1,2\n");
    EXPECT_EQ(testing::ReadText(d + "/sub/log.csv"), "a,b\n1,2\n") << "each append is in the file at once";
  }
  AppendFile again(d + "/log.csv");
  again.Append("x\n");
  EXPECT_EQ(testing::ReadText(d + "/log.csv"), "x\n");
}

TEST(AppendFile, AFullDiskIsAnErrorNamingTheFile) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full here";
  AppendFile full("/dev/full");
  try {
    full.Append("a line\n");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/full"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace twinsim

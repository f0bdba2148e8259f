#include "io/output_files.h"

#include <gtest/gtest.h>

#include "test_util.h"

namespace twinsim {
namespace {

TEST(OutputFiles, WritesIntoTheFolderAndListsEveryFileInOrder) {
  const std::string dir = testing::TempDir("output_files") + "/out";
  OutputFiles files(dir);
  files.Write("a.csv", "x\n1\n");
  files.WritePng("b.png", RgbaImage(2, 3, 0x112233ff));
  files.Add("c.json");  // written by another writer
  EXPECT_EQ(testing::ReadText(dir + "/a.csv"), "x\n1\n");
  const RgbaImage back = ReadPng(dir + "/b.png");
  EXPECT_EQ(back.width, 2);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(files.written(), (std::vector<std::string>{dir + "/a.csv", dir + "/b.png", dir + "/c.json"}));
  EXPECT_EQ(files.WroteList(), "wrote:\n  " + dir + "/a.csv\n  " + dir + "/b.png\n  " + dir + "/c.json\n");
}

TEST(OutputFiles, WithoutAFolderNamesArePaths) {
  const std::string dir = testing::TempDir("output_files_paths");
  OutputFiles files;
  EXPECT_EQ(files.Path(dir + "/m.yaml"), dir + "/m.yaml");
  files.Write(dir + "/m.yaml", "name: m\n");
  EXPECT_EQ(testing::ReadText(dir + "/m.yaml"), "name: m\n");
  EXPECT_EQ(files.WroteList(), "wrote:\n  " + dir + "/m.yaml\n");
  EXPECT_EQ(OutputFiles().WroteList(), "wrote:\n");
}

}  // namespace
}  // namespace twinsim

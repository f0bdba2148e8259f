// serve/cpu_time.h: a CPU's stolen and interrupt ticks read from its /proc/stat line.
#include "serve/cpu_time.h"

#include <gtest/gtest.h>
#include <unistd.h>

namespace twinsim {
namespace {

TEST(CpuTime, ReadsTheStolenAndInterruptTicksOfTheLineAsked) {
  const std::string text =
      "cpu  9123510 171153 502440 3315906 12467 11 6807 1418 0 0\n"
      "cpu0 4479714 92291 235234 1750645 5530 4 1662 713 0 0\n"
      "cpu1 4643796 78862 267205 1565260 6936 7 5145 705 0 0\n"
      "intr 123 4 5\n";
  const CpuTicks zero = CpuTime::Parse(text, 0), one = CpuTime::Parse(text, 1);
  EXPECT_EQ(zero.cpu, 0);
  EXPECT_EQ(zero.steal, 713);
  EXPECT_EQ(zero.interrupts, 4 + 1662);
  EXPECT_EQ(one.cpu, 1);
  EXPECT_EQ(one.steal, 705);
  EXPECT_EQ(one.interrupts, 7 + 5145);
  // A line that is not there, cut short by the read, or short of fields reads as unknown.
  EXPECT_EQ(CpuTime::Parse(text, 7).cpu, -1);
  EXPECT_EQ(CpuTime::Parse(text.substr(0, text.find("cpu1") + 30), 1).cpu, -1);
  EXPECT_EQ(CpuTime::Parse("cpu3 1 2 3\n", 3).cpu, -1);
  EXPECT_EQ(CpuTime::Parse("cpu13 1 2 3 4 5 6 7 8 9 10\n", 1).cpu, -1);  // not cpu1
  EXPECT_EQ(CpuTime::Parse("cpu1 1 2 3 4 5 6 7 8 9 10\n", 1).steal, 8);   // the first line
  // This machine's own (where /proc/stat can be read): counters that never go back.
  const CpuTime cpu;
  if (!cpu.ok()) GTEST_SKIP() << "no /proc/stat";
  const CpuTicks a = cpu.Now(), b = cpu.Now();
  ASSERT_GE(a.cpu, 0);
  if (a.cpu != b.cpu) GTEST_SKIP() << "moved to another CPU between the readings";
  EXPECT_GE(b.steal, a.steal);
  EXPECT_GE(b.interrupts, a.interrupts);
  EXPECT_DOUBLE_EQ(cpu.Seconds(100), 100 / static_cast<double>(sysconf(_SC_CLK_TCK)));
}

}  // namespace
}  // namespace twinsim

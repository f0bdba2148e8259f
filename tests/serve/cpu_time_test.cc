// serve/cpu_time.h: a CPU's stolen and interrupt ticks read from /proc/stat's lines.
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
  const CpuTicks all = CpuTime::Parse(text, "cpu"), one = CpuTime::Parse(text, "cpu1");
  EXPECT_EQ(all.steal, 1418);
  EXPECT_EQ(all.interrupts, 11 + 6807);
  EXPECT_EQ(one.steal, 705);
  EXPECT_EQ(one.interrupts, 7 + 5145);
  // A line that is not there, or cut short, reads as nothing.
  EXPECT_EQ(CpuTime::Parse(text, "cpu7").steal, 0);
  EXPECT_EQ(CpuTime::Parse("cpu3 1 2 3\n", "cpu3").steal, 0);
  // This machine's own (where /proc/stat can be read): counters that never go back.
  const CpuTime cpu(-1);
  if (!cpu.ok()) GTEST_SKIP() << "no /proc/stat";
  const CpuTicks a = cpu.Now(), b = cpu.Now();
  EXPECT_GE(b.steal, a.steal);
  EXPECT_GE(b.interrupts, a.interrupts);
  EXPECT_DOUBLE_EQ(cpu.Seconds(100), 100 / static_cast<double>(sysconf(_SC_CLK_TCK)));
}

}  // namespace
}  // namespace twinsim

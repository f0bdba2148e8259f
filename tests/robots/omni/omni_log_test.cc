#include "robots/omni/omni_log.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/math_constants.h"
#include "core/pose.h"

namespace twinsim {
namespace {

std::string ErrorOf(const std::string& csv) {
  try {
    ParseOmniLog(csv, "log.csv");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const char* kHeader = "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd\n";

TEST(OmniLog, ReadsAndUnwrapsTheta) {
  const std::string csv = std::string(kHeader) + "0,0,0,3.1,0,0,0\n0.0333333,0,0,-3.1,0,0,0\n0.0666667,1,2,-3.0,1,0,0\n";
  OmniLog log = ParseOmniLog(csv, "log.csv");
  ASSERT_EQ(log.rows.size(), 3u);
  EXPECT_NEAR(log.rows[1].pose.theta, 2 * kPi - 3.1, 1e-9);
  EXPECT_NEAR(log.frame_period, 1.0 / 30, 1e-6);
  EXPECT_EQ(log.line_of[2], 4);
}

TEST(OmniLog, ExtraColumnsAndDroppedFramesAreFine) {
  const std::string csv = "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd,quality\n0,0,0,0,0,0,0,1\n0.1,0,0,0,0,0,0,1\n"
                          "0.3,0,0,0,0,0,0,1\n0.4,0,0,0,0,0,0,1\n";
  OmniLog log = ParseOmniLog(csv, "log.csv");
  EXPECT_EQ(log.FrameIndex(2), 3);
}

TEST(OmniLog, ExtraTextColumnsAreIgnored) {
  // CONTRACT.md: extra columns, numeric or not (a robot id, a note), are ignored.
  const std::string csv = "robot,t,x,y,theta,vx_cmd,vy_cmd,omega_cmd,note\nblue0,0,0,0,0,0,0,0,start\n"
                          "blue0,0.0333333,0.01,0,0,0,0,0,\nblue0,0.0666667,0.02,0,0,1,0,0,go fast\n";
  const OmniLog log = ParseOmniLog(csv, "log.csv");
  ASSERT_EQ(log.rows.size(), 3u);
  EXPECT_EQ(log.rows[2].pose.x, 0.02);
  EXPECT_EQ(log.rows[2].command.vx, 1);
  // Text in a column the log needs is still an error with its place.
  EXPECT_EQ(ErrorOf("t,x,y,theta,vx_cmd,vy_cmd,omega_cmd,note\n0,0,0,0,0,0,0,a\n0.03,0,zero,0,0,0,0,b\n"),
            "log.csv:3:8: column 'y': expected a number, got 'zero'");
}

// A logger that quotes its text as RFC 4180 does: a note holding a comma or a quote,
// quoted column names, a quoted robot id. What a reader that split at every comma took
// is still taken, as Python's csv module reads it: text after a closing quote, a quote
// inside a field (5", it's), a quote left open.
TEST(OmniLog, QuotedFieldsAreReadAsRfc4180WritesThem) {
  const std::string csv = "\"robot\",\"t\",x,y,theta,vx_cmd,vy_cmd,omega_cmd,\"note\"\n"
                          "\"blue0\",0,0,0,0,0,0,0,\"start, slowly\"\n"
                          "blue0,0.0333333,0.01,0,0,0,0,0, \"a \"\"quoted\"\" word\" \n"
                          "\"blue0\",\" 0.0666667\",0.02,0,0,1,0,0,\"\"\n"
                          "blue0,0.1,0.03,0,0,1,0,0,\"Fast\" run\n"
                          "blue0,0.1333333,0.04,0,0,1,0,0,5\" it's\n"
                          "blue0,0.1666667,0.05,0,0,1,0,0,\"open\n";
  const OmniLog log = ParseOmniLog(csv, "log.csv");
  ASSERT_EQ(log.rows.size(), 6u);
  EXPECT_EQ(log.rows[2].t, 0.0666667);
  EXPECT_EQ(log.rows[2].pose.x, 0.02);
  EXPECT_EQ(log.rows[2].command.vx, 1);
  EXPECT_EQ(log.rows[5].pose.x, 0.05);
  // A quote left open where a number belongs is still not a number.
  EXPECT_EQ(ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.1,0,0,0,0,0,\"0\n"),
            "log.csv:3:15: column 'omega_cmd': expected a number, got '\"0'");
}

TEST(OmniLog, MissingColumn) {
  const std::string e = ErrorOf("t,x,y,theta,vx_cmd,vy_cmd\n0,0,0,0,0,0\n0.1,0,0,0,0,0\n");
  EXPECT_NE(e.find("log.csv:1: missing column 'omega_cmd' (have: t, x, y, theta, vx_cmd, vy_cmd)"), std::string::npos) << e;
}

TEST(OmniLog, TextInANumber) {
  const std::string e = ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.1,abc,0,0,0,0,0\n");
  EXPECT_NE(e.find("log.csv:3:5: column 'x': expected a number, got 'abc'"), std::string::npos) << e;
}

TEST(OmniLog, ColumnCountsCharactersIncludingSpaces) {
  const std::string e = ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.1,  0.5 , x1,0,0,0,0\n");
  EXPECT_NE(e.find("log.csv:3:13: column 'y': expected a number, got 'x1'"), std::string::npos) << e;
}

TEST(OmniLog, NaN) {
  const std::string e = ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.1,0,nan,0,0,0,0\n");
  EXPECT_NE(e.find("log.csv:3:"), std::string::npos) << e;
  EXPECT_NE(e.find("column 'y': value is nan, not a finite number"), std::string::npos) << e;
}

TEST(OmniLog, TimeGoingBackwards) {
  const std::string e = ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.1,0,0,0,0,0,0\n0.05,0,0,0,0,0,0\n");
  EXPECT_NE(e.find("log.csv:4:1: time goes backwards"), std::string::npos) << e;
}

TEST(OmniLog, WrongFieldCount) {
  const std::string e = ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.1,0,0,0,0,0\n");
  EXPECT_NE(e.find("log.csv:3: expected 7 fields like the header, got 6"), std::string::npos) << e;
}

TEST(OmniLog, IrregularFrameTime) {
  // Two rows 0.04 s apart in a 0.1 s log are not two camera frames.
  const std::string e = ErrorOf(std::string(kHeader) +
                                "0,0,0,0,0,0,0\n0.1,0,0,0,0,0,0\n0.2,0,0,0,0,0,0\n0.24,0,0,0,0,0,0\n0.34,0,0,0,0,0,0\n");
  EXPECT_NE(e.find("log.csv:5:1: irregular frame time"), std::string::npos) << e;
}

TEST(OmniLog, TooShortAndEmpty) {
  EXPECT_NE(ErrorOf("").find("log.csv:1: empty file"), std::string::npos);
  EXPECT_NE(ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n").find("at least 2 rows"), std::string::npos);
}

TEST(OmniLog, WriteReadRoundTripIsExactToNanometres) {
  std::vector<OmniLogRow> rows = {{0, {1.25, -0.5, 0.1}, {1, 0, 0}}, {1.0 / 30, {1.2500001, -0.5, 0.2}, {0, 1, -2}}};
  OmniLog back = ParseOmniLog(FormatOmniLog(rows), "x.csv");
  EXPECT_NEAR(back.rows[1].pose.x, 1.2500001, 1e-9);
  EXPECT_NEAR(back.rows[1].command.omega, -2, 1e-12);
  EXPECT_EQ(FormatOmniLog(rows), FormatOmniLog(rows));
}

}  // namespace
}  // namespace twinsim

namespace twinsim {
namespace {

// CONTRACT.md, "Measured logs": real cameras miss frames.
TEST(OmniLogMissedFrames, EmptyPoseCellsAreAFrameWithoutMeasurement) {
  const std::string csv = std::string(kHeader) + "0,0,0,0,1,0,0\n0.0166667,0.01,0,0,1,0,0\n0.0333333,,,,1,0,0\n"
                          "0.05,0.03,0.003,0.03,1,0,0\n";
  const OmniLog log = ParseOmniLog(csv, "log.csv");
  ASSERT_EQ(log.rows.size(), 4u);
  EXPECT_FALSE(log.rows[2].measured);
  EXPECT_TRUE(log.rows[3].measured);
  EXPECT_EQ(log.num_measured(), 3);
  // Its pose is interpolated between the measured frames around it, never a standstill.
  EXPECT_NEAR(log.rows[2].pose.x, 0.02, 1e-6);
  EXPECT_NEAR(log.rows[2].pose.y, 0.0015, 1e-6);
  EXPECT_NEAR(log.rows[2].pose.theta, 0.015, 1e-6);
  EXPECT_EQ(log.rows[2].command.vx, 1);  // the command was sent all the same
}

TEST(OmniLogMissedFrames, ARepeatedPoseIsNotARobotStandingStill) {
  const std::string csv = std::string(kHeader) + "0,0,0,0,1,0,0\n0.016,0.01,0,0,1,0,0\n0.0335,0.01,0,0,1,0,0\n"
                          "0.0505,0.03,0,0,1,0,0\n0.067,0.04,0,0,1,0,0\n";  // and jittered frame times
  const OmniLog log = ParseOmniLog(csv, "log.csv");
  EXPECT_FALSE(log.rows[2].measured);
  EXPECT_EQ(log.rows[2].pose.x, 0.01);  // what the camera sent, flagged: nothing invented
  EXPECT_NEAR(log.frame_period, 0.0167, 0.0005);
  EXPECT_EQ(log.FrameIndex(4), 4);
  // Written back, the frame has empty pose cells.
  EXPECT_NE(FormatOmniLog(log.rows).find("\n0.0335,,,,1,0,0\n"), std::string::npos) << FormatOmniLog(log.rows);
}

TEST(OmniLogMissedFrames, PartlyEmptyPoseAndNaNAreErrors) {
  EXPECT_EQ(ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.0333333,1,,0,0,0,0\n0.0666667,1,1,1,0,0,0\n"),
            "log.csv:3: column 'y' is empty but the row's other pose cells are not: x, y and theta are all empty (a "
            "frame without a measurement) or all numbers");
  EXPECT_NE(ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.0333333,nan,nan,nan,0,0,0\n").find("log.csv:3:11: column 'x'"),
            std::string::npos);
  EXPECT_NE(ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.0333333,1,1,1,,0,0\n").find("column 'vx_cmd': empty cell"),
            std::string::npos);
  EXPECT_NE(ErrorOf(std::string(kHeader) + "0,,,,0,0,0\n0.0333333,,,,0,0,0\n").find("no row holds a pose"),
            std::string::npos);
}

const char* kTwoTeams =
    "t,robot_id,team,x,y,theta,vx_cmd,vy_cmd,omega_cmd\n"
    "0,3,blue,0,0,0,1,0,0\n0,3,yellow,5,5,0,0,1,0\n0,1,blue,-1,-1,0,0,0,1\n"
    "0.0166667,3,blue,0.01,0,0,1,0,0\n0.0166667,3,yellow,5,5.01,0,0,1,0\n0.0166667,1,blue,-1,-1,0.01,0,0,1\n"
    "0.0333333,3,blue,0.02,0,0,1,0,0\n0.0333333,3,yellow,5,5.02,0,0,1,0\n0.0333333,1,blue,-1,-1,0.02,0,0,1\n";

TEST(OmniLogSeveralRobots, ASelectorPicksOneRobot) {
  OmniLogSelector select;
  select.robot = "3";
  select.team = "Yellow";
  const OmniLog log = ParseOmniLog(kTwoTeams, "game.csv", select);
  ASSERT_EQ(log.rows.size(), 3u);
  EXPECT_EQ(log.rows[2].pose.y, 5.02);
  EXPECT_EQ(log.line_of[2], 9);
  EXPECT_EQ(log.robot, "yellow 3");
  select.team = "";
  select.robot = "1.0";  // ids compare as numbers
  EXPECT_NEAR(ParseOmniLog(kTwoTeams, "game.csv", select).rows[1].pose.theta, 0.01, 1e-12);
}

TEST(OmniLogSeveralRobots, WithoutOneTheReaderSaysWhichThereAre) {
  try {
    ParseOmniLog(kTwoTeams, "game.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "game.csv:2: the log holds 3 robots (blue 3, yellow 3, blue 1): choose one with --robot ID (and --team "
              "TEAM where ids repeat)");
  }
  OmniLogSelector select;
  select.robot = "3";  // two teams have a robot 3
  EXPECT_THROW(ParseOmniLog(kTwoTeams, "game.csv", select), InputError);
  select.robot = "7";
  try {
    ParseOmniLog(kTwoTeams, "game.csv", select);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), "game.csv:1: no rows for robot '7' (the log holds: blue 3, yellow 3, blue 1)");
  }
  select.robot = "1";
  EXPECT_THROW(ParseOmniLog(std::string(kHeader) + "0,0,0,0,0,0,0\n0.0333333,1,1,1,0,0,0\n", "one.csv", select),
               InputError);
}

}  // namespace
}  // namespace twinsim

namespace twinsim {
namespace {

// Issue 63, "real clocks": a logger that stalls resumes off the beat. The hole reads as
// frames without a measurement; the rows around it keep their frames.
TEST(OmniLogClockHoles, AHoleOffTheBeatReadsAsMissingFrames) {
  std::string csv = kHeader;
  const double period = 0.0315;
  double t = 0;
  for (int i = 0; i < 10; ++i, t += period) csv += std::to_string(t) + "," + std::to_string(0.01 * i) + ",0,0,0.3,0,0\n";
  t += 5.39 * period;  // the logger stalled: 6.39 periods between two rows
  for (int i = 0; i < 10; ++i, t += period) csv += std::to_string(t) + "," + std::to_string(0.2 + 0.01 * i) + ",0,0,0.3,0,0\n";
  const OmniLog log = ParseOmniLog(csv, "log.csv");
  ASSERT_EQ(log.rows.size(), 20u);
  ASSERT_EQ(log.holes.size(), 1u);
  EXPECT_EQ(log.holes[0].row, 10u);
  EXPECT_EQ(log.holes[0].frames, 5);  // 6.39 periods: five frames without a row
  EXPECT_NEAR(log.holes[0].seconds, 6.39 * period, 1e-5);
  EXPECT_EQ(log.FrameIndex(9), 9);
  EXPECT_EQ(log.FrameIndex(10), 15);  // round(15.39)
  EXPECT_EQ(log.FrameIndex(19), 24);
  const std::string said = DescribeClockHoles(log);
  EXPECT_NE(said.find("log.csv: the clock has 1 hole(s)"), std::string::npos) << said;
  EXPECT_NE(said.find("5 frame(s) in all"), std::string::npos) << said;
  EXPECT_NE(said.find("line 12"), std::string::npos) << said;  // the header is line 1
  // A slice keeps the holes inside it, renumbered, and drops the others.
  EXPECT_EQ(SliceOmniLog(log, 5, 20).holes.at(0).row, 5u);
  EXPECT_TRUE(SliceOmniLog(log, 10, 20).holes.empty());
  EXPECT_EQ(DescribeClockHoles(SliceOmniLog(log, 0, 10)), "");
}

TEST(OmniLogClockHoles, AJitteringClockCountsFramesGapByGap) {
  // A real logger's clock (the Robotino's: 0.7 to 1.66 periods between rows). Counted
  // from the first row, 1.4 + 1.4 periods would put rows 2 and 3 three frames apart
  // after one; counted gap by gap each is one frame, and 1.6 is a missed frame.
  const std::string csv = std::string(kHeader) + "0,0,0,0,0,0,0\n0.1,0,0,0,0,0,0\n0.24,0,0,0,0,0,0\n0.38,0,0,0,0,0,0\n"
                          "0.54,0,0,0,0,0,0\n0.64,0,0,0,0,0,0\n0.74,0,0,0,0,0,0\n0.84,0,0,0,0,0,0\n0.94,0,0,0,0,0,0\n";
  const OmniLog log = ParseOmniLog(csv, "log.csv");
  ASSERT_NEAR(log.frame_period, 0.1, 1e-12);
  EXPECT_EQ(log.FrameIndex(2), 2);
  EXPECT_EQ(log.FrameIndex(3), 3);
  EXPECT_EQ(log.FrameIndex(4), 5);  // 1.6 periods: one frame without a row
  ASSERT_EQ(log.holes.size(), 1u);
  EXPECT_EQ(log.holes[0].frames, 1);
  for (std::size_t i = 1; i < log.rows.size(); ++i) EXPECT_GT(log.FrameIndex(i), log.FrameIndex(i - 1));
}

// A robot spinning at 6 rad/s turns 4.8 rad (more than half a turn) in a 0.8 s stall of
// the logger, and 1.6 rad in 8 lost frames: the nearest branch would count one turn too
// few across the stall; the heading stays on the turn extrapolated from before the gap,
// either way round, while a pose repeated right after the gap is never taken as a turn.
TEST(OmniLogClockHoles, AFastSpinKeepsItsTurnsAcrossHolesAndLostFrames) {
  const double period = 1.0 / 30;
  for (const double omega : {6.0, -6.0}) {
    std::string csv = kHeader;
    std::vector<double> truth;  // the unwrapped heading of each row written
    auto row = [&](double t, bool lost) {
      const double theta = omega * t;
      if (!lost) truth.push_back(theta);
      if (lost) truth.push_back(std::nan(""));
      const std::string pose = lost ? ",,," : "0,0," + std::to_string(WrapAngle(theta)) + ",";
      csv += std::to_string(t) + "," + pose + "0,0," + std::to_string(omega) + "\n";
    };
    int f = 0;
    for (; f < 10; ++f) row(f * period, false);
    f += 24;  // the stall: 0.8 s without a row
    for (int k = 0; k < 10; ++k, ++f) row(f * period, false);
    for (int k = 0; k < 8; ++k, ++f) row(f * period, true);  // lost: empty pose cells
    for (int k = 0; k < 10; ++k, ++f) row(f * period, false);
    const OmniLog log = ParseOmniLog(csv, "log.csv");
    ASSERT_EQ(log.rows.size(), truth.size());
    ASSERT_EQ(log.holes.size(), 1u);
    for (std::size_t i = 0; i < truth.size(); ++i) {
      if (std::isnan(truth[i])) continue;
      EXPECT_NEAR(log.rows[i].pose.theta, truth[i], 1e-5) << "omega " << omega << ", row " << i;
    }
  }
  // A camera that repeats its last pose after a gap: the repeat keeps the heading.
  const std::string repeated = std::string(kHeader) + "0,0,0,0,0,0,6\n0.0333333,0,0,0.2,0,0,6\n"
                               "0.0666667,0,0,0.4,0,0,6\n0.3,0,0,0.4,0,0,6\n0.3333333,0,0,2.0,0,0,6\n";
  const OmniLog log = ParseOmniLog(repeated, "log.csv");
  EXPECT_FALSE(log.rows[3].measured);
  EXPECT_NEAR(log.rows[3].pose.theta, 0.4, 1e-12);
  EXPECT_NEAR(log.rows[4].pose.theta, 2.0, 1e-12);  // 1.6 rad in 0.27 s: the nearest branch
}

TEST(OmniLogClockHoles, AHoleLongerThanTheObserverBridgesIsAnError) {
  const std::string e =
      ErrorOf(std::string(kHeader) + "0,0,0,0,0,0,0\n0.1,0,0,0,0,0,0\n0.2,0,0,0,0,0,0\n6.2,0,0,0,0,0,0\n6.3,0,0,0,0,0,0\n");
  EXPECT_NE(e.find("log.csv:5:1: a hole of 6 s in the clock"), std::string::npos) << e;
  EXPECT_NE(e.find("split it here"), std::string::npos) << e;
}

}  // namespace
}  // namespace twinsim

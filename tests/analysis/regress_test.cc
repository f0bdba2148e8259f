// `twinsim regress` and analysis/regress.h: what counts as moved, what is written where,
// and the exit codes, on small synthetic result folders.
#include "analysis/regress.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>

#include "core/error.h"
#include "io/png_image.h"
#include "robots/omni/omni_log.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::ReadText;
using testing::RunTwinsim;
using testing::TempDir;
using testing::WriteText;
namespace fs = std::filesystem;

constexpr double kFps = 30;  // Hz
constexpr int kRows = 121;   // 4 s

// A straight diagonal drive of 4 s at 30 fps, turning slowly; `edit` may change row i.
std::vector<OmniLogRow> Drive(const std::function<void(int, OmniLogRow&)>& edit = {}) {
  std::vector<OmniLogRow> rows;
  for (int i = 0; i < kRows; ++i) {
    const double t = i / kFps;
    OmniLogRow r{t, Pose2{-1 + 0.5 * t, -1 + 0.5 * t, 0.2 * t}, Twist2{0.7, 0, 0.2}};
    if (edit) edit(i, r);
    rows.push_back(r);
  }
  return rows;
}

// A 160 x 120 plot: white, a blue diagonal, a grey frame.
RgbaImage Plot() {
  RgbaImage image(160, 120, 0xffffffff);
  for (int x = 0; x < 160; ++x) {
    std::uint8_t* p = image.at(x, x * 119 / 159);
    p[0] = 0, p[1] = 0x72, p[2] = 0xb2;
    image.at(x, 0)[0] = image.at(x, 0)[1] = image.at(x, 0)[2] = 0x80;
  }
  return image;
}

// A result folder as `twinsim run` writes it, with a plot.
std::string MakeRun(const std::string& dir, const std::vector<OmniLogRow>& truth, const RgbaImage& plot = Plot()) {
  WriteOmniLog(dir + "/trajectory.csv", Drive());
  WriteOmniLog(dir + "/truth.csv", truth);
  WritePng(dir + "/path.png", plot);
  return dir;
}

std::string Regress(const std::string& golden, const std::string& candidate, const std::string& more = "") {
  return "regress --golden " + golden + " --candidate " + candidate + (more.empty() ? "" : " " + more);
}

std::vector<OmniLogRow> MovedAtFrame40(double metres) {
  return Drive([metres](int i, OmniLogRow& r) {
    if (i == 40) r.pose.y += metres;  // t = 1.333 s
  });
}

bool HasHighlight(const RgbaImage& image, int x, int y) {
  const std::uint8_t* p = image.at(x, y);
  const std::uint32_t rgba =
      (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
  return rgba == kRegressHighlight;
}

TEST(Regress, IdenticalFoldersPassAndNothingMoved) {
  const std::string dir = TempDir("regress_same");
  const std::string golden = MakeRun(dir + "/golden", Drive()), candidate = MakeRun(dir + "/candidate", Drive());
  auto r = RunTwinsim(Regress(golden, candidate));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("nothing moved"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("truth.csv"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("path.png"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ok: 2 trajectories within 5.000 mm (nothing moved), 1 image unchanged"), std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(candidate + "/regress"));
}

TEST(Regress, OneCentimetreMoveIsARegressionNamingFileTimeAndSize) {
  const std::string dir = TempDir("regress_1cm");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  const std::string candidate = MakeRun(dir + "/candidate", MovedAtFrame40(0.010));
  auto r = RunTwinsim(Regress(golden, candidate));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("truth.csv moved 10.000 mm at t = 1.333 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("max 10.000 mm at t = 1.333 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("MOVED"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("beyond 5.000 mm at 1 of 121 frames"), std::string::npos) << r.out;
  // The RMS over 121 frames of a single 10 mm move: 10 / sqrt(121) = 0.909 mm.
  EXPECT_NE(r.out.find("0.909"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(candidate + "/regress/truth.csv.png")) << r.out;
  EXPECT_NE(r.out.find(candidate + "/regress/truth.csv.png"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(candidate + "/regress/trajectory.csv.png"));
}

TEST(Regress, OneMillimetreMoveIsReportedButPassesTheDefaultTolerance) {
  const std::string dir = TempDir("regress_1mm");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  const std::string candidate = MakeRun(dir + "/candidate", MovedAtFrame40(0.001));
  auto r = RunTwinsim(Regress(golden, candidate));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("max 1.000 mm at t = 1.333 s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("within tolerance"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("largest move 1.000 mm, truth.csv"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(candidate + "/regress"));
}

TEST(Regress, ToleranceChangesTheVerdict) {
  const std::string dir = TempDir("regress_tolerance");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  const std::string moved_1mm = MakeRun(dir + "/mm", MovedAtFrame40(0.001));
  const std::string moved_1cm = MakeRun(dir + "/cm", MovedAtFrame40(0.010));
  EXPECT_EQ(RunTwinsim(Regress(golden, moved_1mm, "--tolerance 0.0005")).exit_code, 1);
  EXPECT_EQ(RunTwinsim(Regress(golden, moved_1mm, "--tolerance 0.0015")).exit_code, 0);
  EXPECT_EQ(RunTwinsim(Regress(golden, moved_1cm, "--tolerance 0.0099")).exit_code, 1);
  EXPECT_TRUE(fs::exists(moved_1cm + "/regress/truth.csv.png"));
  EXPECT_EQ(RunTwinsim(Regress(golden, moved_1cm, "--tolerance 0.02")).exit_code, 0);
  // Passing again removes the stale highlight of the failed comparison.
  EXPECT_FALSE(fs::exists(moved_1cm + "/regress"));
}

TEST(Regress, HeadingIsReportedAndRegressesOnlyWithAHeadingTolerance) {
  const std::string dir = TempDir("regress_heading");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  const std::string candidate = MakeRun(dir + "/candidate", Drive([](int i, OmniLogRow& r) {
                                          if (i == 60) r.pose.theta += 0.05;  // rad, 2.865 deg
                                        }));
  auto r = RunTwinsim(Regress(golden, candidate));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("2.865"), std::string::npos) << r.out;
  auto strict = RunTwinsim(Regress(golden, candidate, "--heading-tolerance 0.01"));
  EXPECT_EQ(strict.exit_code, 1) << strict.out << strict.err;
  EXPECT_NE(strict.out.find("TURNED"), std::string::npos) << strict.out;
}

TEST(Regress, HeadingDifferenceIsWrapped) {
  OmniLog golden, candidate;
  golden.frame_period = candidate.frame_period = 1 / kFps;
  golden.rows = {{0, Pose2{0, 0, 3.1}, {}}, {1 / kFps, Pose2{0, 0, 3.1}, {}}};
  candidate.rows = {{0, Pose2{0, 0, -3.1}, {}}, {1 / kFps, Pose2{0, 0, 3.1 + 4 * kPi}, {}}};
  const TrajectoryDiff d = CompareTrajectories("t.csv", golden, candidate, RegressOptions{});
  EXPECT_NEAR(d.max_heading, 2 * kPi - 6.2, 1e-9);
  EXPECT_EQ(d.max_heading_t, 0);
  EXPECT_EQ(d.verdict, RegressVerdict::kWithin);
}

TEST(Regress, MissingGoldenFileIsARegressionAndANewOneIsNot) {
  const std::string dir = TempDir("regress_missing");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  const std::string candidate = MakeRun(dir + "/candidate", Drive());
  WriteOmniLog(candidate + "/truth_yellow1.csv", Drive());
  auto extra = RunTwinsim(Regress(golden, candidate));
  EXPECT_EQ(extra.exit_code, 0) << extra.out << extra.err;
  EXPECT_NE(extra.out.find("truth_yellow1.csv"), std::string::npos) << extra.out;
  EXPECT_NE(extra.out.find("new in the candidate"), std::string::npos) << extra.out;

  fs::remove(candidate + "/trajectory.csv");
  auto missing = RunTwinsim(Regress(golden, candidate));
  EXPECT_EQ(missing.exit_code, 1) << missing.out << missing.err;
  EXPECT_NE(missing.out.find("REGRESSION: trajectory.csv missing"), std::string::npos) << missing.out;

  fs::remove(candidate + "/path.png");
  fs::copy_file(golden + "/trajectory.csv", candidate + "/trajectory.csv");
  auto no_plot = RunTwinsim(Regress(golden, candidate));
  EXPECT_EQ(no_plot.exit_code, 1) << no_plot.out << no_plot.err;
  EXPECT_NE(no_plot.out.find("path.png missing"), std::string::npos) << no_plot.out;
}

TEST(Regress, LostFramesRegressAndExtraFramesAreReported) {
  const std::string dir = TempDir("regress_frames");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  std::vector<OmniLogRow> lost = Drive();
  lost.erase(lost.begin() + 90, lost.end());
  auto r = RunTwinsim(Regress(golden, MakeRun(dir + "/lost", lost)));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("121/90"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("31 golden frame(s) missing from the candidate, the first at t = 3.000 s"), std::string::npos)
      << r.out;

  // A path recorded half a frame later matches no golden frame at all.
  auto late =
      RunTwinsim(Regress(golden, MakeRun(dir + "/late", Drive([](int, OmniLogRow& row) { row.t += 0.5 / kFps; }))));
  EXPECT_EQ(late.exit_code, 1) << late.out;
  EXPECT_NE(late.out.find("121 golden frame(s) missing"), std::string::npos) << late.out;

  std::vector<OmniLogRow> longer = Drive();
  for (int i = kRows; i < kRows + 15; ++i) longer.push_back({i / kFps, longer.back().pose, {}});
  auto extra = RunTwinsim(Regress(golden, MakeRun(dir + "/longer", longer)));
  EXPECT_EQ(extra.exit_code, 0) << extra.out << extra.err;
  EXPECT_NE(extra.out.find("15 frame(s) only in the candidate"), std::string::npos) << extra.out;
}

TEST(Regress, FewChangedPixelsAreReportedAndHighlighted) {
  const std::string dir = TempDir("regress_png");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  RgbaImage changed = Plot();
  const int spots[5][2] = {{10, 50}, {11, 50}, {100, 20}, {150, 110}, {80, 60}};
  for (const auto& s : spots) {  // on white: a change of 255 in green and blue
    std::uint8_t* p = changed.at(s[0], s[1]);
    p[0] = 200, p[1] = p[2] = 0;
  }
  const std::string candidate = MakeRun(dir + "/candidate", Drive(), changed);
  // By default changed pixels are reported and highlighted, never a regression.
  auto r = RunTwinsim(Regress(golden, candidate));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("path.png  160x120                 5      0.0260          255  changed (reported only)"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("1 image, 1 changed (reported only)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("differing pixels within x 10..150, y 20..110"), std::string::npos) << r.out;

  const std::string highlight = candidate + "/regress/path.png";
  ASSERT_TRUE(fs::exists(highlight)) << r.out;
  const RgbaImage h = ReadPng(highlight);
  ASSERT_EQ(h.width, 160);
  ASSERT_EQ(h.height, 120);
  for (const auto& s : spots) EXPECT_TRUE(HasHighlight(h, s[0], s[1])) << s[0] << "," << s[1];
  int highlighted = 0;
  for (int y = 0; y < h.height; ++y)
    for (int x = 0; x < h.width; ++x) highlighted += HasHighlight(h, x, y);
  EXPECT_EQ(highlighted, 5);
  // The rest is the candidate dimmed to grey: white stays white, the blue line is light grey.
  const std::uint8_t* background = h.at(40, 100);
  EXPECT_EQ(background[0], 255);
  const std::uint8_t* line = h.at(40, 40 * 119 / 159);
  EXPECT_EQ(line[0], line[1]);
  EXPECT_EQ(line[1], line[2]);
  EXPECT_GT(line[0], 150);
  EXPECT_LT(line[0], 255);

  // 5 of 19200 pixels (0.026 %) is within a pixel tolerance of 0.1 %, not of 0.01 %.
  auto within = RunTwinsim(Regress(golden, candidate, "--pixel-tolerance 0.001"));
  EXPECT_EQ(within.exit_code, 0) << within.out;
  EXPECT_NE(within.out.find("changed, within tolerance"), std::string::npos) << within.out;
  auto strict = RunTwinsim(Regress(golden, candidate, "--pixel-tolerance 0.0001"));
  EXPECT_EQ(strict.exit_code, 1) << strict.out;
  EXPECT_NE(strict.out.find("REGRESSION: path.png changed 0.03% of its pixels (pixel tolerance 0.01%)"),
            std::string::npos)
      << strict.out;
  // Below the channel threshold, the change does not count.
  auto lenient = RunTwinsim(Regress(golden, candidate, "--pixel-threshold 255"));
  EXPECT_EQ(lenient.exit_code, 0) << lenient.out;
  EXPECT_NE(lenient.out.find("within channel threshold"), std::string::npos) << lenient.out;
  EXPECT_FALSE(fs::exists(highlight));
}

TEST(Regress, RedrawnOrResizedPlotIsARegression) {
  const std::string dir = TempDir("regress_png_big");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  RgbaImage shifted(160, 120, 0xffffffff);
  for (int x = 0; x < 160; ++x)
    for (int y = 30; y < 40; ++y) shifted.at(x, y)[1] = 0;
  const std::string redrawn = MakeRun(dir + "/shifted", Drive(), shifted);
  auto reported = RunTwinsim(Regress(golden, redrawn));
  EXPECT_EQ(reported.exit_code, 0) << reported.out;
  EXPECT_NE(reported.out.find("changed (reported only)"), std::string::npos) << reported.out;
  auto r = RunTwinsim(Regress(golden, redrawn, "--pixel-tolerance 0.001"));
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("CHANGED"), std::string::npos) << r.out;

  auto resized = RunTwinsim(Regress(golden, MakeRun(dir + "/resized", Drive(), RgbaImage(160, 121, 0xffffffff))));
  EXPECT_EQ(resized.exit_code, 1) << resized.out;
  EXPECT_NE(resized.out.find("160x120 -> 160x121"), std::string::npos) << resized.out;
  EXPECT_NE(resized.out.find("SIZE CHANGED"), std::string::npos) << resized.out;
  EXPECT_TRUE(fs::exists(dir + "/resized/regress/path.png"));
}

TEST(Regress, CompareImagesCountsPixelsBeyondTheThreshold) {
  RgbaImage a(10, 10, 0x808080ff), b = a;
  b.at(1, 1)[0] += 8;  // at the threshold: the same
  b.at(2, 2)[1] += 9;  // beyond
  b.at(3, 4)[3] = 0;   // alpha counts too
  RegressOptions options;
  const ImageDiff d = CompareImages("x.png", a, b, options);
  EXPECT_EQ(d.differing_pixels, 2);
  EXPECT_DOUBLE_EQ(d.fraction, 0.02);
  EXPECT_EQ(d.max_channel_difference, 255);
  EXPECT_EQ(d.box[0], 2);
  EXPECT_EQ(d.box[1], 2);
  EXPECT_EQ(d.box[2], 3);
  EXPECT_EQ(d.box[3], 4);
  EXPECT_EQ(d.verdict, RegressVerdict::kWithin);  // reported only
  options.pixel_tolerance = 0.001;
  EXPECT_EQ(CompareImages("x.png", a, b, options).verdict, RegressVerdict::kRegressed);
  options.pixel_tolerance = 0.02;
  EXPECT_EQ(CompareImages("x.png", a, b, options).verdict, RegressVerdict::kWithin);
}

TEST(Regress, BadInputIsExitTwoWithAMessage) {
  const std::string dir = TempDir("regress_bad");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  const std::string candidate = MakeRun(dir + "/candidate", Drive());

  auto missing = RunTwinsim(Regress(golden, dir + "/nope"));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find(dir + "/nope: no such folder (--candidate)"), std::string::npos) << missing.err;
  auto missing_golden = RunTwinsim(Regress(dir + "/nada", candidate));
  EXPECT_EQ(missing_golden.exit_code, 2);
  EXPECT_NE(missing_golden.err.find(dir + "/nada: no such folder (--golden)"), std::string::npos) << missing_golden.err;

  fs::create_directories(dir + "/empty");
  auto empty = RunTwinsim(Regress(dir + "/empty", candidate));
  EXPECT_EQ(empty.exit_code, 2);
  EXPECT_NE(empty.err.find(dir + "/empty: nothing to compare"), std::string::npos) << empty.err;

  auto negative = RunTwinsim(Regress(golden, candidate, "--tolerance -0.001"));
  EXPECT_EQ(negative.exit_code, 2);
  EXPECT_NE(negative.err.find("tolerance must be a finite distance >= 0 m, got -0.001"), std::string::npos)
      << negative.err;
  auto text = RunTwinsim(Regress(golden, candidate, "--tolerance abc"));
  EXPECT_EQ(text.exit_code, 2);
  EXPECT_NE(text.err.find("--tolerance"), std::string::npos) << text.err;
  EXPECT_EQ(RunTwinsim(Regress(golden, candidate, "--pixel-tolerance -0.5")).exit_code, 2);

  // Every corrupt file is named with its line and column, and nothing is written.
  WriteText(candidate + "/truth.csv", "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd\n0,0,0,0,0,0,0\n0.0333,abc,0,0,0,0,0\n");
  WriteText(candidate + "/path.png", "not a png");
  WriteOmniLog(dir + "/candidate/trajectory.csv", MovedAtFrame40(0.05));
  auto corrupt = RunTwinsim(Regress(golden, candidate));
  EXPECT_EQ(corrupt.exit_code, 2) << corrupt.out;
  EXPECT_NE(corrupt.err.find(candidate + "/truth.csv:3:8: column 'x': expected a number, got 'abc'"), std::string::npos)
      << corrupt.err;
  EXPECT_NE(corrupt.err.find(candidate + "/path.png: cannot read PNG"), std::string::npos) << corrupt.err;
  EXPECT_FALSE(fs::exists(candidate + "/regress"));

  try {
    RegressOptions options;
    options.tolerance = std::nan("");
    RegressFolders(golden, golden, options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("tolerance must be a finite distance"), std::string::npos) << e.what();
  }
}

TEST(Regress, SummaryReportsEndWithTheBriefLine) {
  const std::string dir = TempDir("regress_summary");
  const std::string golden = MakeRun(dir + "/golden", Drive());
  const std::string candidate = MakeRun(dir + "/candidate", MovedAtFrame40(0.02));
  RegressOptions options;
  options.write_images = false;
  const RegressSummary s = RegressFolders(golden, candidate, options);
  EXPECT_TRUE(s.regression);
  ASSERT_EQ(s.trajectories.size(), 2u);
  EXPECT_EQ(s.trajectories[1].name, "truth.csv");
  EXPECT_NEAR(s.trajectories[1].max_distance, 0.02, 1e-9);
  EXPECT_NEAR(s.trajectories[1].max_distance_t, 40 / kFps, 1e-9);
  EXPECT_EQ(s.trajectories[1].frames_over, 1);
  EXPECT_EQ(s.BriefReport(), "REGRESSION: truth.csv moved 20.000 mm at t = 1.333 s (tolerance 5.000 mm)");
  const std::string full = s.FullReport();
  EXPECT_EQ(full.substr(full.size() - s.BriefReport().size() - 1), s.BriefReport() + "\n");
  EXPECT_TRUE(s.written.empty());
  EXPECT_FALSE(fs::exists(candidate + "/regress"));
}

}  // namespace
}  // namespace twinsim

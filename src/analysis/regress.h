// Regression of result folders (`twinsim regress`): does a candidate run still produce
// the paths and the plots of a golden one?
//
// Only the top level of each folder is looked at (subfolders such as regress/ are not):
// - trajectories: every trajectory*.csv and truth*.csv (the omni log of CONTRACT.md).
//   Rows are matched by frame: a candidate row matches a golden row whose time is
//   within a quarter of the golden frame period. Over the matched frames: the max and
//   RMS position distance, the max heading difference (wrapped to [-pi, pi)), when the
//   max happened and the frames where the distance exceeds the tolerance.
// - images: every *.png present in both: the pixels where some RGBA channel changed by
//   more than a threshold, their fraction of the image, the largest channel change.
//
// A regression (`RegressSummary::regression`, exit 1 in the command) is any of:
// - a golden trajectory whose path moved more than `tolerance` at some matched frame
//   (or turned more than `heading_tolerance`, when one is set);
// - a golden frame that the candidate's file lacks (the path is not there to compare);
// - a golden file (trajectory or PNG) missing from the candidate;
// - a PNG whose size changed;
// - a PNG whose differing pixels exceed `pixel_tolerance`, when one is set.
// Files only in the candidate, frames only in the candidate and differences within the
// tolerances are reported, never a regression. Changed pixels are not a regression by
// default: a path that moves within the tolerance still moves a line by a pixel or two,
// which changes thousands of pixels of a plot; the trajectories decide. Where the paths
// are not expected to move at all (the golden set on the analytic backend), a pixel
// tolerance catches a plot that changed on its own (a lost legend, a swapped colour).
//
// Highlights go to CANDIDATE/regress/ (old PNGs there are removed first): for a PNG with
// differing pixels, the same file name showing the candidate dimmed to light grey with
// the differing pixels in kRegressHighlight; for a trajectory that moved beyond the
// tolerance, NAME.csv.png with both paths and the distance over time.
//
//   RegressOptions options;
//   options.tolerance = 0.01;  // m
//   RegressSummary s = RegressFolders("tests/golden/drive45", "out/drive45", options);
//   std::puts(s.FullReport().c_str());
//   return s.regression ? kExitCheckFailed : kExitOk;
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/pose.h"
#include "io/png_image.h"
#include "robots/omni/omni_log.h"

namespace twinsim {

// The colour of differing pixels in a highlight image and of moved frames in a path
// diagnostic (RGBA, magenta: it is in no plot's palette and stands out on grey).
inline constexpr std::uint32_t kRegressHighlight = 0xff00ffff;

struct RegressOptions {
  double tolerance = 0.005;                                            // m, how far a path may move at any frame
  double heading_tolerance = std::numeric_limits<double>::infinity();  // rad; infinite: reported only
  int pixel_threshold = 8;  // channel levels (of 255) a pixel may change by and count as the same
  // Fraction of an image's pixels that may differ; infinite: reported only.
  double pixel_tolerance = std::numeric_limits<double>::infinity();
  bool write_images = true;  // highlights into CANDIDATE/regress/

  // True when every option is in range; otherwise false with every problem in *error.
  bool IsValid(std::string* error) const;
};

enum class RegressVerdict {
  kIdentical,  // no difference at all
  kWithin,     // differs, within the tolerances
  kRegressed,  // moved, turned, changed or lost frames beyond the tolerances
  kMissing,    // in the golden folder only: a regression
  kNew,        // in the candidate folder only: reported
};

// One trajectory file compared frame by frame.
struct TrajectoryDiff {
  std::string name;  // file name, e.g. "truth_blue1.csv"
  RegressVerdict verdict = RegressVerdict::kIdentical;
  int golden_rows = 0;
  int candidate_rows = 0;
  int matched_rows = 0;
  int missing_frames = 0;      // golden rows without a candidate row at their time
  double first_missing_t = 0;  // s, the first of them
  int extra_frames = 0;        // candidate rows without a golden row at their time
  double max_time_offset = 0;  // s, between matched rows
  double max_distance = 0;     // m, position distance
  double rms_distance = 0;     // m
  double max_distance_t = 0;   // s, golden time of the max distance
  Pose2 golden_at_max;         // the poses there
  Pose2 candidate_at_max;
  double max_heading = 0;    // rad, |wrapped heading difference|
  double max_heading_t = 0;  // s
  int frames_over = 0;       // matched frames farther apart than the tolerance
  double first_over_t = 0;   // s, the first and last of them
  double last_over_t = 0;    // s
  std::string image;         // the diagnostic PNG written, or empty
};

// One PNG compared pixel by pixel.
struct ImageDiff {
  std::string name;  // file name, e.g. "path.png"
  RegressVerdict verdict = RegressVerdict::kIdentical;
  int golden_width = 0, golden_height = 0;  // px
  int width = 0, height = 0;                // px, the candidate's
  long differing_pixels = 0;                // channel change above the threshold, or outside the other image
  double fraction = 0;                      // differing_pixels over the pixels of the larger extent
  int max_channel_difference = 0;           // 0..255, over every pixel
  int box[4] = {0, 0, -1, -1};              // x0, y0, x1, y1 (inclusive) around the differing pixels
  std::string image;                        // the highlight PNG written, or empty
};

struct RegressSummary {
  std::string golden;  // folders as given
  std::string candidate;
  RegressOptions options;
  std::vector<TrajectoryDiff> trajectories;  // golden files by name, then new ones
  std::vector<ImageDiff> images;             // likewise
  std::vector<std::string> not_compared;     // other files: "name (golden)", "name (candidate)"
  std::vector<std::string> written;          // highlight and diagnostic PNGs
  bool regression = false;

  // One line: "ok: ..." or "REGRESSION: ..." naming the worst offenders.
  std::string BriefReport() const;
  // The tables of trajectories and images, what moved where, what was written, and the
  // brief report as the last line.
  std::string FullReport() const;
};

// Compares two logs frame by frame; `name` labels the result. The verdict is kIdentical,
// kWithin or kRegressed.
TrajectoryDiff CompareTrajectories(const std::string& name, const OmniLog& golden, const OmniLog& candidate,
                                   const RegressOptions& options);

// Compares two images pixel by pixel over the larger extent; the verdict is kIdentical,
// kWithin or kRegressed (a size change always regresses).
ImageDiff CompareImages(const std::string& name, const RgbaImage& golden, const RgbaImage& candidate,
                        const RegressOptions& options);

// The candidate (over the larger extent) dimmed to light grey, a box in blue around the
// differing pixels and those pixels in kRegressHighlight.
RgbaImage HighlightDifferences(const RgbaImage& golden, const RgbaImage& candidate, const RegressOptions& options);

// Both paths seen from above (golden dark grey, candidate blue, frames beyond the
// tolerance joined in kRegressHighlight, a ring at the max) over a strip of the distance
// against time with the tolerance dashed in orange. No text: docs/regression.md says
// what is what.
RgbaImage DrawMovedPaths(const OmniLog& golden, const OmniLog& candidate, const TrajectoryDiff& diff,
                         const RegressOptions& options);

// Compares every trajectory and PNG of `golden` with `candidate` and writes the
// highlights. Reads and checks everything before writing anything. Throws InputError
// for invalid options, a folder that does not exist, a golden folder with nothing to
// compare, and every unreadable or corrupt file ("path:line:column: ...", all at once).
RegressSummary RegressFolders(const std::string& golden, const std::string& candidate,
                              const RegressOptions& options = {});

}  // namespace twinsim

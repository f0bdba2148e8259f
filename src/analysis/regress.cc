#include "analysis/regress.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "core/error.h"
#include "io/printf_number.h"
#include "render/raster.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;

// Rows whose times differ by less than this many golden frame periods are one frame.
constexpr double kFrameMatch = 0.25;
// Times closer than this are the same (CSV files keep 1e-9 s).
constexpr double kTimeNoise = 1e-9;  // s

constexpr std::uint32_t kWhitePixel = 0xffffffff;
constexpr std::uint32_t kGoldenGrey = 0x555555ff;
constexpr std::uint32_t kCandidateBlue = 0x0072b2ff;    // Okabe-Ito blue
constexpr std::uint32_t kToleranceOrange = 0xe69f00ff;  // Okabe-Ito orange
constexpr std::uint32_t kFrameGrey = 0xccccccff;

std::string Mm(double metres) { return PrintfNumber("%.3f", metres * 1000); }
std::string Deg(double radians) { return PrintfNumber("%.3f", radians * 180 / kPi); }
std::string Sec(double seconds) { return PrintfNumber("%.3f", seconds); }

bool EndsWith(const std::string& s, const std::string& end) {
  return s.size() >= end.size() && s.compare(s.size() - end.size(), end.size(), end) == 0;
}
bool StartsWith(const std::string& s, const std::string& start) { return s.rfind(start, 0) == 0; }
std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

enum class FileKind { kTrajectory, kImage, kOther };

FileKind KindOf(const std::string& name) {
  if (EndsWith(name, ".csv") && (StartsWith(name, "trajectory") || StartsWith(name, "truth")))
    return FileKind::kTrajectory;
  if (EndsWith(Lower(name), ".png")) return FileKind::kImage;
  return FileKind::kOther;
}

// The regular files at the top of a folder, by name; hidden files (half-written
// temporaries among them) left out.
std::vector<std::string> ListFiles(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || name[0] == '.' || !entry.is_regular_file()) continue;
    names.push_back(name);
  }
  if (ec) throw InputError(SourceLocation{dir}, "cannot list folder: " + ec.message());
  std::sort(names.begin(), names.end());
  return names;
}

void CheckFolder(const std::string& dir, const std::string& option, ErrorList* errors) {
  std::error_code ec;
  if (dir.empty())
    errors->Add(option + ": empty folder name");
  else if (!fs::exists(dir, ec))
    errors->Add(SourceLocation{dir}, "no such folder (" + option + ")");
  else if (!fs::is_directory(dir, ec))
    errors->Add(SourceLocation{dir}, "not a folder (" + option + ")");
}

std::string Join(const std::string& dir, const std::string& name) { return (fs::path(dir) / name).string(); }

bool Inside(const RgbaImage& image, int x, int y) { return x < image.width && y < image.height; }

// The largest channel change at (x, y); 256 where only one image has the pixel.
int PixelDifference(const RgbaImage& golden, const RgbaImage& candidate, int x, int y) {
  if (Inside(golden, x, y) != Inside(candidate, x, y)) return 256;
  const std::uint8_t* g = golden.at(x, y);
  const std::uint8_t* c = candidate.at(x, y);
  int d = 0;
  for (int k = 0; k < 4; ++k) d = std::max(d, std::abs(static_cast<int>(g[k]) - static_cast<int>(c[k])));
  return d;
}

std::string VerdictText(const TrajectoryDiff& d, const RegressOptions& options) {
  switch (d.verdict) {
    case RegressVerdict::kIdentical:
      return "identical";
    case RegressVerdict::kWithin:
      return d.extra_frames > 0 ? "within tolerance, extra frames" : "within tolerance";
    case RegressVerdict::kMissing:
      return "MISSING from the candidate";
    case RegressVerdict::kNew:
      return "new in the candidate";
    case RegressVerdict::kRegressed:
      break;
  }
  std::string s;
  auto add = [&s](const std::string& what) { s += (s.empty() ? "" : ", ") + what; };
  if (d.max_distance > options.tolerance) add("MOVED");
  if (d.max_heading > options.heading_tolerance) add("TURNED");
  if (d.missing_frames > 0) add("FRAMES MISSING");
  return s;
}

std::string VerdictText(const ImageDiff& d, const RegressOptions& options) {
  switch (d.verdict) {
    case RegressVerdict::kIdentical:
      return "identical";
    case RegressVerdict::kWithin:
      if (d.differing_pixels == 0) return "within channel threshold";
      return std::isfinite(options.pixel_tolerance) ? "changed, within tolerance" : "changed (reported only)";
    case RegressVerdict::kMissing:
      return "MISSING from the candidate";
    case RegressVerdict::kNew:
      return "new in the candidate";
    case RegressVerdict::kRegressed:
      break;
  }
  if (d.width != d.golden_width || d.height != d.golden_height) return "SIZE CHANGED";
  return "CHANGED";
}

// A table with left-aligned first column and right-aligned numbers, the last column
// (the verdict) left-aligned and unpadded.
std::string Table(const std::vector<std::vector<std::string>>& rows) {
  std::vector<std::size_t> width;
  for (const auto& r : rows)
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (width.size() <= i) width.push_back(0);
      width[i] = std::max(width[i], r[i].size());
    }
  std::string out;
  for (const auto& r : rows) {
    std::string line = "  ";
    for (std::size_t i = 0; i < r.size(); ++i) {
      const std::string pad(width[i] - r[i].size(), ' ');
      if (i == 0)
        line += r[i] + pad;
      else if (i + 1 == r.size())
        line += "  " + r[i];
      else
        line += "  " + pad + r[i];
    }
    out += line + "\n";
  }
  return out;
}

}  // namespace

bool RegressOptions::IsValid(std::string* error) const {
  std::vector<std::string> messages;
  if (!(tolerance >= 0) || !std::isfinite(tolerance))
    messages.push_back("tolerance must be a finite distance >= 0 m, got " + PrintfNumber("%g", tolerance));
  if (!(heading_tolerance >= 0))
    messages.push_back("heading tolerance must be >= 0 rad, got " + PrintfNumber("%g", heading_tolerance));
  if (pixel_threshold < 0 || pixel_threshold > 255)
    messages.push_back("pixel threshold must be within 0..255 channel levels, got " + std::to_string(pixel_threshold));
  if (!(pixel_tolerance >= 0) || (pixel_tolerance > 1 && std::isfinite(pixel_tolerance)))  // inf: no image check
    messages.push_back("pixel tolerance must be a fraction in [0, 1], got " + PrintfNumber("%g", pixel_tolerance));
  if (error) {
    error->clear();
    for (std::size_t i = 0; i < messages.size(); ++i) *error += (i ? "\n" : "") + messages[i];
  }
  return messages.empty();
}

TrajectoryDiff CompareTrajectories(const std::string& name, const OmniLog& golden, const OmniLog& candidate,
                                   const RegressOptions& options) {
  TrajectoryDiff d;
  d.name = name;
  d.golden_rows = static_cast<int>(golden.rows.size());
  d.candidate_rows = static_cast<int>(candidate.rows.size());
  const double match = kFrameMatch * golden.frame_period;
  double sum_squares = 0;
  bool first_over = true, first_missing = true;
  std::size_t i = 0, j = 0;
  while (i < golden.rows.size() || j < candidate.rows.size()) {
    const bool have_g = i < golden.rows.size(), have_c = j < candidate.rows.size();
    const double tg = have_g ? golden.rows[i].t : 0, tc = have_c ? candidate.rows[j].t : 0;
    if (have_g && have_c && std::abs(tg - tc) <= match) {
      const Pose2& g = golden.rows[i].pose;
      const Pose2& c = candidate.rows[j].pose;
      const double dist = std::hypot(c.x - g.x, c.y - g.y);
      const double heading = std::abs(WrapAngle(c.theta - g.theta));
      sum_squares += dist * dist;
      d.max_time_offset = std::max(d.max_time_offset, std::abs(tg - tc));
      if (d.matched_rows == 0 || dist > d.max_distance) {
        d.max_distance = dist;
        d.max_distance_t = tg;
        d.golden_at_max = g;
        d.candidate_at_max = c;
      }
      if (d.matched_rows == 0 || heading > d.max_heading) {
        d.max_heading = heading;
        d.max_heading_t = tg;
      }
      if (dist > options.tolerance) {
        ++d.frames_over;
        if (first_over) d.first_over_t = tg;
        first_over = false;
        d.last_over_t = tg;
      }
      ++d.matched_rows;
      ++i;
      ++j;
    } else if (have_g && (!have_c || tg < tc)) {
      ++d.missing_frames;
      if (first_missing) d.first_missing_t = tg;
      first_missing = false;
      ++i;
    } else {
      ++d.extra_frames;
      ++j;
    }
  }
  if (d.matched_rows > 0) d.rms_distance = std::sqrt(sum_squares / d.matched_rows);

  if (d.max_distance > options.tolerance || d.max_heading > options.heading_tolerance || d.missing_frames > 0)
    d.verdict = RegressVerdict::kRegressed;
  else if (d.max_distance > 0 || d.max_heading > 0 || d.extra_frames > 0 || d.max_time_offset > kTimeNoise)
    d.verdict = RegressVerdict::kWithin;
  else
    d.verdict = RegressVerdict::kIdentical;
  return d;
}

ImageDiff CompareImages(const std::string& name, const RgbaImage& golden, const RgbaImage& candidate,
                        const RegressOptions& options) {
  ImageDiff d;
  d.name = name;
  d.golden_width = golden.width;
  d.golden_height = golden.height;
  d.width = candidate.width;
  d.height = candidate.height;
  const int w = std::max(golden.width, candidate.width), h = std::max(golden.height, candidate.height);
  int x0 = w, y0 = h, x1 = -1, y1 = -1;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int diff = PixelDifference(golden, candidate, x, y);
      if (diff == 0) continue;
      d.max_channel_difference = std::max(d.max_channel_difference, std::min(diff, 255));
      if (diff <= options.pixel_threshold) continue;
      ++d.differing_pixels;
      x0 = std::min(x0, x);
      y0 = std::min(y0, y);
      x1 = std::max(x1, x);
      y1 = std::max(y1, y);
    }
  if (d.differing_pixels > 0) {
    d.box[0] = x0;
    d.box[1] = y0;
    d.box[2] = x1;
    d.box[3] = y1;
  }
  const double total = static_cast<double>(w) * h;
  d.fraction = total > 0 ? d.differing_pixels / total : 0;
  const bool resized = golden.width != candidate.width || golden.height != candidate.height;
  if (resized || d.fraction > options.pixel_tolerance)
    d.verdict = RegressVerdict::kRegressed;
  else if (d.max_channel_difference > 0)
    d.verdict = RegressVerdict::kWithin;
  else
    d.verdict = RegressVerdict::kIdentical;
  return d;
}

RgbaImage HighlightDifferences(const RgbaImage& golden, const RgbaImage& candidate, const RegressOptions& options) {
  const int w = std::max(golden.width, candidate.width), h = std::max(golden.height, candidate.height);
  // The candidate as light grey, so that any colour on top stands out.
  RgbaImage out = raster::FadedGrey(candidate, w, h, 0.3);
  // A box around the differing pixels helps to find a few of them in a large plot.
  int x0 = w, y0 = h, x1 = -1, y1 = -1;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (PixelDifference(golden, candidate, x, y) > options.pixel_threshold) {
        x0 = std::min(x0, x);
        y0 = std::min(y0, y);
        x1 = std::max(x1, x);
        y1 = std::max(y1, y);
      }
  if (x1 >= 0) raster::Outline(out, x0 - 4, y0 - 4, x1 + 4, y1 + 4, kCandidateBlue);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (PixelDifference(golden, candidate, x, y) > options.pixel_threshold) raster::Put(out, x, y, kRegressHighlight);
  return out;
}

RgbaImage DrawMovedPaths(const OmniLog& golden, const OmniLog& candidate, const TrajectoryDiff& diff,
                         const RegressOptions& options) {
  constexpr int kWidth = 900, kPathHeight = 700, kStripHeight = 200, kMargin = 24, kInset = 260;
  const double match = kFrameMatch * golden.frame_period;
  // The matched frames: (golden row, candidate row).
  std::vector<std::pair<const OmniLogRow*, const OmniLogRow*>> matched;
  for (std::size_t i = 0, j = 0; i < golden.rows.size() && j < candidate.rows.size();) {
    if (std::abs(golden.rows[i].t - candidate.rows[j].t) <= match)
      matched.emplace_back(&golden.rows[i++], &candidate.rows[j++]);
    else if (golden.rows[i].t < candidate.rows[j].t)
      ++i;
    else
      ++j;
  }

  // Both paths from above in a panel centred on (cx, cy) m at `scale` px/m, y up.
  auto draw_paths = [&](int width, int height, double cx, double cy, double scale) {
    RgbaImage panel(width, height, kWhitePixel);
    auto px = [&](double x) { return width / 2.0 + (x - cx) * scale; };
    auto py = [&](double y) { return height / 2.0 - (y - cy) * scale; };
    auto draw = [&](const OmniLog& log, int radius, std::uint32_t colour) {
      for (std::size_t i = 1; i < log.rows.size(); ++i)
        raster::Line(panel, px(log.rows[i - 1].pose.x), py(log.rows[i - 1].pose.y), px(log.rows[i].pose.x),
                     py(log.rows[i].pose.y), radius, colour);
      if (!log.rows.empty())
        raster::Dot(panel, static_cast<int>(std::lround(px(log.rows[0].pose.x))),
                    static_cast<int>(std::lround(py(log.rows[0].pose.y))), radius + 3, colour);
    };
    draw(golden, 2, kGoldenGrey);
    draw(candidate, 0, kCandidateBlue);
    // Frames beyond the tolerance: the golden and the candidate pose joined.
    for (const auto& [g, c] : matched)
      if (std::hypot(c->pose.x - g->pose.x, c->pose.y - g->pose.y) > options.tolerance) {
        raster::Line(panel, px(g->pose.x), py(g->pose.y), px(c->pose.x), py(c->pose.y), 0, kRegressHighlight);
        raster::Dot(panel, static_cast<int>(std::lround(px(c->pose.x))), static_cast<int>(std::lround(py(c->pose.y))),
                    2, kRegressHighlight);
      }
    raster::Ring(panel, px(diff.candidate_at_max.x), py(diff.candidate_at_max.y), std::min(14.0, width / 8.0), 1,
                 kRegressHighlight);
    raster::Outline(panel, 0, 0, width - 1, height - 1, kFrameGrey);
    return panel;
  };

  RgbaImage image(kWidth, kPathHeight + kStripHeight, kWhitePixel);
  double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300;
  for (const OmniLog* log : {&golden, &candidate})
    for (const auto& r : log->rows) {
      min_x = std::min(min_x, r.pose.x);
      max_x = std::max(max_x, r.pose.x);
      min_y = std::min(min_y, r.pose.y);
      max_y = std::max(max_y, r.pose.y);
    }
  const double span_x = std::max(max_x - min_x, 0.1), span_y = std::max(max_y - min_y, 0.1);             // m
  const double scale = std::min((kWidth - 2 * kMargin) / span_x, (kPathHeight - 2 * kMargin) / span_y);  // px/m
  const double cx = 0.5 * (min_x + max_x), cy = 0.5 * (min_y + max_y);
  raster::Paste(image, draw_paths(kWidth, kPathHeight, cx, cy, scale), 0, 0);

  // A move of millimetres is invisible at field scale: an inset magnifies the
  // neighbourhood of the max, in the corner the paths cross least.
  const double zoom_half = std::max(4 * diff.max_distance, 0.01);  // m, half the inset's width
  const double zoom_scale = kInset / (2 * zoom_half);
  if (zoom_scale > 2 * scale) {
    const int corners[4][2] = {{8, 8},
                               {kWidth - kInset - 8, 8},
                               {8, kPathHeight - kInset - 8},
                               {kWidth - kInset - 8, kPathHeight - kInset - 8}};
    int best = 0;
    long best_count = -1;
    for (int k = 0; k < 4; ++k) {
      long count = 0;
      for (const OmniLog* log : {&golden, &candidate})
        for (const auto& r : log->rows) {
          const double x = kWidth / 2.0 + (r.pose.x - cx) * scale, y = kPathHeight / 2.0 - (r.pose.y - cy) * scale;
          if (x >= corners[k][0] && x < corners[k][0] + kInset && y >= corners[k][1] && y < corners[k][1] + kInset)
            ++count;
        }
      if (best_count < 0 || count < best_count) {
        best = k;
        best_count = count;
      }
    }
    const Pose2 centre{0.5 * (diff.golden_at_max.x + diff.candidate_at_max.x),
                       0.5 * (diff.golden_at_max.y + diff.candidate_at_max.y), 0};
    RgbaImage inset = draw_paths(kInset, kInset, centre.x, centre.y, zoom_scale);
    raster::Outline(inset, 0, 0, kInset - 1, kInset - 1, kGoldenGrey);
    raster::Paste(image, inset, corners[best][0], corners[best][1]);
  }

  // Bottom: distance against time, the tolerance dashed.
  const int top = kPathHeight + 8, bottom = kPathHeight + kStripHeight - 8;
  raster::Outline(image, 0, kPathHeight, kWidth - 1, kPathHeight + kStripHeight - 1, kFrameGrey);
  const double t0 = golden.rows.front().t, t1 = std::max(golden.rows.back().t, t0 + 1e-9);  // s
  const double d_top = 1.1 * std::max({diff.max_distance, options.tolerance, 1e-6});        // m
  auto sx = [&](double t) { return kMargin + (t - t0) / (t1 - t0) * (kWidth - 2 * kMargin); };
  auto sy = [&](double d) { return bottom - std::min(d, d_top) / d_top * (bottom - top); };
  raster::Line(image, kMargin, bottom, kWidth - kMargin, bottom, 0, kGoldenGrey);
  raster::Line(image, kMargin, sy(options.tolerance), kWidth - kMargin, sy(options.tolerance), 0, kToleranceOrange, 6);
  double prev_t = 0, prev_d = 0;
  for (std::size_t k = 0; k < matched.size(); ++k) {
    const auto [g, c] = matched[k];
    const double d = std::hypot(c->pose.x - g->pose.x, c->pose.y - g->pose.y);
    const std::uint32_t colour = d > options.tolerance ? kRegressHighlight : kCandidateBlue;
    if (k > 0)
      raster::Line(image, sx(prev_t), sy(prev_d), sx(g->t), sy(d), 1, colour);
    else
      raster::Dot(image, static_cast<int>(sx(g->t)), static_cast<int>(sy(d)), 1, colour);
    prev_t = g->t;
    prev_d = d;
  }
  return image;
}

namespace {

// Both folders' file lists, and the files to compare read into memory by name.
struct RegressInputs {
  std::vector<std::string> golden_files, candidate_files;
  std::set<std::string> in_golden, in_candidate;
  std::map<std::string, OmniLog> golden_logs, candidate_logs;
  std::map<std::string, RgbaImage> golden_images, candidate_images;
};

// Lists both folders and reads every file to compare, naming all the corrupt ones at once.
RegressInputs ReadRegressInputs(const std::string& golden, const std::string& candidate) {
  RegressInputs in;
  in.golden_files = ListFiles(golden);
  in.candidate_files = ListFiles(candidate);
  in.in_golden = std::set<std::string>(in.golden_files.begin(), in.golden_files.end());
  in.in_candidate = std::set<std::string>(in.candidate_files.begin(), in.candidate_files.end());
  if (std::none_of(in.golden_files.begin(), in.golden_files.end(),
                   [](const std::string& n) { return KindOf(n) != FileKind::kOther; }))
    throw InputError(
        SourceLocation{golden},
        "nothing to compare: no trajectory*.csv, truth*.csv or *.png (is it a 'twinsim run' output folder?)");

  // Read every file first, so that all corrupt ones are named at once and nothing is
  // written for a comparison that cannot be made.
  ErrorList errors;
  auto read_log = [](const std::string& path) { return ReadOmniLog(path); };
  auto read = [&errors](const std::string& path, auto reader, auto& into, const std::string& name) {
    try {
      into.emplace(name, reader(path));
    } catch (const InputError& e) {
      errors.Add(e.what());
    }
  };
  for (const auto& name : in.golden_files) {
    if (KindOf(name) == FileKind::kTrajectory) read(Join(golden, name), read_log, in.golden_logs, name);
    if (!in.in_candidate.count(name)) continue;
    if (KindOf(name) == FileKind::kTrajectory) {
      read(Join(candidate, name), read_log, in.candidate_logs, name);
    } else if (KindOf(name) == FileKind::kImage) {
      read(Join(golden, name), ReadPng, in.golden_images, name);
      read(Join(candidate, name), ReadPng, in.candidate_images, name);
    }
  }
  errors.ThrowIfAny();
  return in;
}

// Compares the golden files by name, then lists the candidate's new ones, and marks a regression.
void CompareRegressFiles(const RegressInputs& in, const RegressOptions& options, RegressSummary* s) {
  for (const auto& name : in.golden_files) {
    const FileKind kind = KindOf(name);
    if (kind == FileKind::kOther) {
      s->not_compared.push_back(name + " (golden)");
    } else if (!in.in_candidate.count(name)) {
      if (kind == FileKind::kTrajectory) {
        TrajectoryDiff d;
        d.name = name;
        d.verdict = RegressVerdict::kMissing;
        d.golden_rows = static_cast<int>(in.golden_logs.at(name).rows.size());
        s->trajectories.push_back(d);
      } else {
        ImageDiff d;
        d.name = name;
        d.verdict = RegressVerdict::kMissing;
        s->images.push_back(d);
      }
    } else if (kind == FileKind::kTrajectory) {
      s->trajectories.push_back(
          CompareTrajectories(name, in.golden_logs.at(name), in.candidate_logs.at(name), options));
    } else {
      s->images.push_back(CompareImages(name, in.golden_images.at(name), in.candidate_images.at(name), options));
    }
  }
  for (const auto& name : in.candidate_files) {
    if (in.in_golden.count(name)) continue;
    const FileKind kind = KindOf(name);
    if (kind == FileKind::kTrajectory) {
      TrajectoryDiff d;
      d.name = name;
      d.verdict = RegressVerdict::kNew;
      s->trajectories.push_back(d);
    } else if (kind == FileKind::kImage) {
      ImageDiff d;
      d.name = name;
      d.verdict = RegressVerdict::kNew;
      s->images.push_back(d);
    } else {
      s->not_compared.push_back(name + " (candidate)");
    }
  }
  for (const auto& d : s->trajectories)
    if (d.verdict == RegressVerdict::kRegressed || d.verdict == RegressVerdict::kMissing) s->regression = true;
  for (const auto& d : s->images)
    if (d.verdict == RegressVerdict::kRegressed || d.verdict == RegressVerdict::kMissing) s->regression = true;
}

// Writes the candidate's regress/ folder afresh: each differing image highlighted, each regressed path drawn.
void WriteRegressImages(const RegressInputs& in, const std::string& candidate, const RegressOptions& options,
                        RegressSummary* s) {
  // Old highlights would mislead: regress/ shows this comparison only.
  const fs::path out_dir = fs::path(candidate) / "regress";
  std::error_code ec;
  if (fs::is_directory(out_dir, ec)) {
    for (const auto& name : ListFiles(out_dir.string()))
      if (KindOf(name) == FileKind::kImage) fs::remove(out_dir / name, ec);
    fs::remove(out_dir, ec);  // only when now empty
  }
  for (auto& d : s->images) {
    if (d.differing_pixels == 0) continue;
    d.image = (out_dir / d.name).string();
    WritePng(d.image, HighlightDifferences(in.golden_images.at(d.name), in.candidate_images.at(d.name), options));
    s->written.push_back(d.image);
  }
  for (auto& d : s->trajectories) {
    if (d.verdict != RegressVerdict::kRegressed || d.matched_rows == 0 || d.frames_over == 0) continue;
    d.image = (out_dir / (d.name + ".png")).string();
    WritePng(d.image, DrawMovedPaths(in.golden_logs.at(d.name), in.candidate_logs.at(d.name), d, options));
    s->written.push_back(d.image);
  }
}

}  // namespace

RegressSummary RegressFolders(const std::string& golden, const std::string& candidate, const RegressOptions& options) {
  std::string invalid;
  if (!options.IsValid(&invalid)) throw InputError(invalid);
  ErrorList errors;
  CheckFolder(golden, "--golden", &errors);
  CheckFolder(candidate, "--candidate", &errors);
  errors.ThrowIfAny();

  RegressSummary s;
  s.golden = golden;
  s.candidate = candidate;
  s.options = options;
  const RegressInputs in = ReadRegressInputs(golden, candidate);
  CompareRegressFiles(in, options, &s);
  if (options.write_images) WriteRegressImages(in, candidate, options, &s);
  return s;
}

std::string RegressSummary::BriefReport() const {
  std::vector<std::string> offenders;
  bool trajectory_offenders = false, image_offenders = false;
  double largest = 0;
  std::string largest_name;
  int compared_t = 0, compared_i = 0, changed_i = 0;
  for (const auto& d : trajectories) {
    if (d.verdict != RegressVerdict::kNew && d.verdict != RegressVerdict::kMissing) ++compared_t;
    if (d.matched_rows > 0 && (largest_name.empty() || d.max_distance > largest)) {
      largest = d.max_distance;
      largest_name = d.name;
    }
    if (d.verdict == RegressVerdict::kMissing) {
      offenders.push_back(d.name + " missing");
    } else if (d.verdict == RegressVerdict::kRegressed) {
      std::string what;
      if (d.max_distance > options.tolerance)
        what = d.name + " moved " + Mm(d.max_distance) + " mm at t = " + Sec(d.max_distance_t) + " s";
      else if (d.max_heading > options.heading_tolerance)
        what = d.name + " turned " + Deg(d.max_heading) + " deg at t = " + Sec(d.max_heading_t) + " s";
      else
        what = d.name + " lost " + std::to_string(d.missing_frames) + " frame(s)";
      offenders.push_back(what);
      trajectory_offenders = true;
    }
  }
  for (const auto& d : images) {
    if (d.verdict != RegressVerdict::kNew && d.verdict != RegressVerdict::kMissing) ++compared_i;
    if (d.differing_pixels > 0) ++changed_i;
    if (d.verdict == RegressVerdict::kMissing) offenders.push_back(d.name + " missing");
    if (d.verdict != RegressVerdict::kRegressed) continue;
    const bool resized = d.width != d.golden_width || d.height != d.golden_height;
    offenders.push_back(
        d.name + (resized ? " changed size" : " changed " + PrintfNumber("%.2f", 100 * d.fraction) + "% of its pixels"));
    image_offenders = true;
  }
  const std::string tolerance = Mm(options.tolerance) + " mm";
  if (regression) {
    std::string out = "REGRESSION: ";
    for (std::size_t i = 0; i < offenders.size() && i < 3; ++i) out += (i ? "; " : "") + offenders[i];
    if (offenders.size() > 3) out += "; and " + std::to_string(offenders.size() - 3) + " more";
    std::string limits;
    if (trajectory_offenders) limits = "tolerance " + tolerance;
    if (image_offenders && std::isfinite(options.pixel_tolerance))
      limits += (limits.empty() ? "" : ", ") + std::string("pixel tolerance ") +
                PrintfNumber("%g", 100 * options.pixel_tolerance) + "%";
    return out + (limits.empty() ? "" : " (" + limits + ")");
  }
  std::string out =
      "ok: " + std::to_string(compared_t) + " trajector" + (compared_t == 1 ? "y" : "ies") + " within " + tolerance;
  if (largest > 0)
    out += " (largest move " + Mm(largest) + " mm, " + largest_name + ")";
  else if (compared_t > 0)
    out += " (nothing moved)";
  if (compared_i > 0) {
    out += ", " + std::to_string(compared_i) + " image" + (compared_i == 1 ? "" : "s");
    if (changed_i == 0)
      out += " unchanged";
    else
      out += ", " + std::to_string(changed_i) + " changed" +
             (std::isfinite(options.pixel_tolerance) ? " within tolerance" : " (reported only)");
  }
  return out;
}

std::string RegressSummary::FullReport() const {
  std::string out = "regress: golden " + golden + ", candidate " + candidate + "\n";
  out += "tolerance " + Mm(options.tolerance) + " mm, heading ";
  out += std::isfinite(options.heading_tolerance) ? Deg(options.heading_tolerance) + " deg" : "reported only";
  out += "; a pixel differs beyond " + std::to_string(options.pixel_threshold) + " of 255 levels, changed pixels ";
  out += std::isfinite(options.pixel_tolerance)
             ? "regress beyond " + PrintfNumber("%g", 100 * options.pixel_tolerance) + "% of an image\n"
             : "reported only\n";

  if (!trajectories.empty()) {
    out += "\ntrajectories (frame by frame; rows golden/candidate where they differ):\n";
    std::vector<std::vector<std::string>> rows = {{"file", "rows", "max mm", "RMS mm", "max heading deg", "verdict"}};
    for (const auto& d : trajectories) {
      const bool compared = d.verdict != RegressVerdict::kMissing && d.verdict != RegressVerdict::kNew;
      std::string n = std::to_string(d.golden_rows);
      if (d.verdict == RegressVerdict::kNew)
        n = "-";
      else if (compared && d.candidate_rows != d.golden_rows)
        n += "/" + std::to_string(d.candidate_rows);
      rows.push_back({d.name, n, compared ? Mm(d.max_distance) : "-", compared ? Mm(d.rms_distance) : "-",
                      compared ? Deg(d.max_heading) : "-", VerdictText(d, options)});
    }
    out += Table(rows);

    std::string moved;
    for (const auto& d : trajectories) {
      if (d.verdict != RegressVerdict::kWithin && d.verdict != RegressVerdict::kRegressed) continue;
      if (d.matched_rows > 0 && (d.max_distance > 0 || d.max_heading > 0)) {
        moved += "  " + d.name + ": max " + Mm(d.max_distance) + " mm at t = " + Sec(d.max_distance_t) +
                 " s: golden (" + PrintfNumber("%.4f", d.golden_at_max.x) + ", " + PrintfNumber("%.4f", d.golden_at_max.y) +
                 ") m, candidate (" + PrintfNumber("%.4f", d.candidate_at_max.x) + ", " +
                 PrintfNumber("%.4f", d.candidate_at_max.y) + ") m\n";
        if (d.max_heading > 0)
          moved += "    heading up to " + Deg(d.max_heading) + " deg at t = " + Sec(d.max_heading_t) + " s\n";
      }
      if (d.frames_over > 0)
        moved += "    beyond " + Mm(options.tolerance) + " mm at " + std::to_string(d.frames_over) + " of " +
                 std::to_string(d.matched_rows) + " frames, from t = " + Sec(d.first_over_t) + " to " +
                 Sec(d.last_over_t) + " s\n";
      if (d.missing_frames > 0)
        moved += "  " + d.name + ": " + std::to_string(d.missing_frames) +
                 " golden frame(s) missing from the candidate, the first at t = " + Sec(d.first_missing_t) + " s\n";
      if (d.extra_frames > 0)
        moved += "  " + d.name + ": " + std::to_string(d.extra_frames) + " frame(s) only in the candidate\n";
      if (d.max_time_offset > kTimeNoise)
        moved +=
            "  " + d.name + ": matched frames' times differ by up to " + PrintfNumber("%.3g", d.max_time_offset) + " s\n";
    }
    out += moved.empty() ? "nothing moved\n" : "what moved:\n" + moved;
  }

  if (!images.empty()) {
    out += "\nimages (pixel by pixel):\n";
    std::vector<std::vector<std::string>> rows = {
        {"file", "size", "differing pixels", "fraction %", "max channel", "verdict"}};
    for (const auto& d : images) {
      const bool compared = d.verdict != RegressVerdict::kMissing && d.verdict != RegressVerdict::kNew;
      std::string size = "-";
      if (compared) {
        size = std::to_string(d.width) + "x" + std::to_string(d.height);
        if (d.width != d.golden_width || d.height != d.golden_height)
          size = std::to_string(d.golden_width) + "x" + std::to_string(d.golden_height) + " -> " + size;
      }
      rows.push_back({d.name, size, compared ? std::to_string(d.differing_pixels) : "-",
                      compared ? PrintfNumber("%.4f", 100 * d.fraction) : "-",
                      compared ? std::to_string(d.max_channel_difference) : "-", VerdictText(d, options)});
    }
    out += Table(rows);
    for (const auto& d : images)
      if (d.differing_pixels > 0)
        out += "  " + d.name + ": differing pixels within x " + std::to_string(d.box[0]) + ".." +
               std::to_string(d.box[2]) + ", y " + std::to_string(d.box[1]) + ".." + std::to_string(d.box[3]) + "\n";
  }

  if (!not_compared.empty()) {
    out += "\nnot compared:";
    for (const auto& n : not_compared) out += " " + n;
    out += "\n";
  }
  if (!written.empty()) {
    out += "\nwrote:\n";
    for (const auto& w : written) out += "  " + w + "\n";
  }
  out += "\n" + BriefReport() + "\n";
  return out;
}

}  // namespace twinsim

#include "scene/camera_layout.h"

#include <algorithm>
#include <cmath>

#include "core/math_constants.h"
#include "core/rng.h"

namespace twinsim {
namespace {

// The nominal camera's image (serve/vision_packets.cc): a listed camera's focal length
// makes the farthest corner of its area land on that image's edge.
constexpr double kImageHalfWidth = 390, kImageHalfHeight = 290;  // pixel
// The staggered cameras' first frame numbers: a camera started at some time before the
// match, as SSL-Vision's are.
constexpr std::uint64_t kCameraClockStream = 0x636c6b00;  // "clk"
constexpr std::uint32_t kFirstFrameRange = 100000;

// The grids `layout:` names (camera_layout.h).
struct NamedLayout {
  const char* name;
  CameraGrid grid;
};
constexpr NamedLayout kLeagueLayouts[] = {{"division_a", {4, 2, 0.4, 6}}, {"division_b", {2, 2, 0.4, 4}}};

}  // namespace

std::optional<CameraGrid> LeagueCameraLayout(const std::string& name) {
  for (const NamedLayout& l : kLeagueLayouts)
    if (name == l.name) return l.grid;
  return std::nullopt;
}

const std::vector<std::string>& LeagueCameraLayoutNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const NamedLayout& l : kLeagueLayouts) n.emplace_back(l.name);
    return n;
  }();
  return names;
}

std::vector<CameraView> CameraViews(const CameraGrid& grid, const FieldModel& field) {
  std::vector<CameraView> views;
  const double cell_x = field.length / grid.columns, cell_y = field.width / grid.rows;
  const double x0 = -field.length / 2, y0 = -field.width / 2, half = grid.overlap / 2;
  for (int row = 0; row < grid.rows; ++row) {
    for (int column = 0; column < grid.columns; ++column) {
      CameraView v;
      v.id = row * grid.columns + column;
      const double left = x0 + column * cell_x, bottom = y0 + row * cell_y;
      v.position = Eigen::Vector3d(left + cell_x / 2, bottom + cell_y / 2, grid.height);
      // Widened on the inner sides only: nothing outside the walls to see.
      v.low = Eigen::Vector2d(column > 0 ? left - half : x0, row > 0 ? bottom - half : y0);
      v.high = Eigen::Vector2d(column + 1 < grid.columns ? left + cell_x + half : -x0,
                               row + 1 < grid.rows ? bottom + cell_y + half : -y0);
      views.push_back(v);
    }
  }
  return views;
}

CameraView PlacedCamera(const CameraPlacement& placement, const FieldModel& field) {
  CameraView v;
  v.position = Eigen::Vector3d(placement.position.x(), placement.position.y(), placement.height);
  Eigen::Vector2d low = placement.area_low, high = placement.area_high;
  if (placement.field_of_view) {
    const Eigen::Vector2d half(placement.height * std::tan(placement.field_of_view->x() * kPi / 360),
                               placement.height * std::tan(placement.field_of_view->y() * kPi / 360));
    low = placement.position - half;
    high = placement.position + half;
  }
  // The farthest the area reaches from below the camera, on each axis.
  const Eigen::Vector2d reach = (high - placement.position).cwiseMax(placement.position - low);
  v.focal_length = std::min(kImageHalfWidth * placement.height / std::max(reach.x(), 1e-3),
                            kImageHalfHeight * placement.height / std::max(reach.y(), 1e-3));
  const Eigen::Vector2d walls(field.length / 2, field.width / 2);
  v.low = low.cwiseMax(-walls);
  v.high = high.cwiseMin(walls);
  return v;
}

std::vector<CameraView> CameraViews(const CameraSetup& setup, const FieldModel& field, double frame_rate,
                                    std::uint64_t seed) {
  std::vector<CameraView> views;
  if (setup.placements.empty()) {
    views = CameraViews(setup.grid, field);
  } else {
    for (std::size_t i = 0; i < setup.placements.size(); ++i) {
      views.push_back(PlacedCamera(setup.placements[i], field));
      views.back().id = static_cast<int>(i);
    }
  }
  if (setup.staggered) {
    const double n = static_cast<double>(views.size());
    for (CameraView& v : views) {
      v.capture_lead = v.id / n / frame_rate;
      Rng clock = Rng::Derived(seed, kCameraClockStream + static_cast<std::uint64_t>(v.id));
      v.first_frame = static_cast<std::uint32_t>(clock.Index(kFirstFrameRange));
    }
  }
  return views;
}

double UnseenShare(const std::vector<CameraView>& views, const FieldModel& field) {
  constexpr double kStep = 0.01;  // m
  const int nx = static_cast<int>(std::floor(field.length / kStep)), ny = static_cast<int>(std::floor(field.width / kStep));
  long long unseen = 0;
  for (int i = 0; i <= nx; ++i) {
    const double x = -field.length / 2 + i * kStep;
    for (int j = 0; j <= ny; ++j) {
      const double y = -field.width / 2 + j * kStep;
      bool seen = false;
      for (const CameraView& v : views) seen = seen || v.Sees(x, y);
      unseen += seen ? 0 : 1;
    }
  }
  return static_cast<double>(unseen) / (static_cast<double>(nx + 1) * (ny + 1));
}

}  // namespace twinsim

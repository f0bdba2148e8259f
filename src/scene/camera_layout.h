// The cameras that see a served field (twinsim serve, docs/serve.md "Several cameras";
// the scene's `cameras:`, docs/scenes.md). The league's fields are seen by several
// cameras with overlapping views, each sending its own detection frames; a team's
// vision filter merges them. Three ways to name them:
//
//   cameras: {columns: 2, rows: 2, overlap: 0.4, height: 4}   # a grid (grSim's four)
//   cameras: {layout: division_a}                              # a grid the league's fields use
//   cameras:                                                   # one by one
//     list:
//       - {position: [-2.6, 0], height: 4, field_of_view: [70, 90]}
//       - {position: [2.6, 0], height: 4, area: [-0.2, -3.7, 5.2, 3.7]}
//     capture: staggered
//
// A grid splits the area inside the walls into `columns` x `rows` equal cells, each
// widened by half the `overlap` on its inner sides, one camera above each cell's
// centre; ids run along x first, from -x to +x, then along y from -y to +y. A listed
// camera looks straight down from `position` (x, y) at `height`; it sees the rectangle
// its field of view (degrees across x and y) spans on the floor, or the `area` given
// (x_low, y_low, x_high, y_high), clipped to the walls; ids in list order. An object in
// an overlap is seen by every camera whose area holds it.
//
// `capture: staggered` gives each camera a clock of its own, as real cameras have: of N
// cameras, camera i captures i/N of a frame period before the frame (its pose then is
// the true one interpolated between the two frames around it), and its frame numbers
// start at a number of its own drawn from the scene's seed. `synchronous` (default):
// every camera captures at the frame and numbers frames as the field does.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "engines/omni_engine.h"

namespace twinsim {

struct CameraGrid {
  int columns = 1;
  int rows = 1;
  double overlap = 0.4;  // m that neighbouring cameras both see
  double height = 4;     // m above the floor
};

// The league-like grids `layout:` names: division_b four cameras (2 x 2, 4 m up),
// division_a eight (4 x 2, 6 m up), each with 0.4 m of overlap. nullopt for another name.
std::optional<CameraGrid> LeagueCameraLayout(const std::string& name);
// Their names, for messages.
const std::vector<std::string>& LeagueCameraLayoutNames();

// One camera of a `list:`.
struct CameraPlacement {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // m, field frame
  double height = 4;                                   // m above the floor
  // What it sees: the rectangle its field of view spans (degrees across x and y), or,
  // without one, the `area` (field frame, m) given.
  std::optional<Eigen::Vector2d> field_of_view;
  Eigen::Vector2d area_low = Eigen::Vector2d::Zero(), area_high = Eigen::Vector2d::Zero();
};

struct CameraSetup {
  CameraGrid grid;                          // the cameras when `placements` is empty
  std::vector<CameraPlacement> placements;  // the cameras one by one
  bool staggered = false;                   // `capture: staggered`: each camera its own clock
};

struct CameraView {
  int id = 0;
  Eigen::Vector2d low = Eigen::Vector2d::Zero();   // m, field frame: the area's corner at the smallest x, y
  Eigen::Vector2d high = Eigen::Vector2d::Zero();  // m: at the largest x, y
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m: where the camera hangs
  double focal_length = 0;  // pixel; 0: the nominal camera's (serve/vision_packets.cc)
  double capture_lead = 0;  // s: how long before the frame's time the camera captures
  std::uint32_t first_frame = 0;  // its frame number at the field's frame 0
  // Whether the camera sees the point (x, y) (m, field frame; the area's edges included).
  bool Sees(double x, double y) const { return x >= low.x() && x <= high.x() && y >= low.y() && y <= high.y(); }
};

// What a listed camera sees of the area inside the walls: its rectangle clipped to them
// (the view's low, high and position filled; low beyond high where it sees nothing).
CameraView PlacedCamera(const CameraPlacement& placement, const FieldModel& field);

// The cameras of `setup` over `field` (the area inside its walls), at `frame_rate` (Hz;
// the staggered capture's spacing), their first frame numbers drawn from `seed`.
std::vector<CameraView> CameraViews(const CameraSetup& setup, const FieldModel& field, double frame_rate,
                                    std::uint64_t seed);
// A grid's cameras (synchronous capture).
std::vector<CameraView> CameraViews(const CameraGrid& grid, const FieldModel& field);

// The share of the area inside the walls that no camera sees (0: none unseen), on a
// 1 cm lattice.
double UnseenShare(const std::vector<CameraView>& views, const FieldModel& field);

}  // namespace twinsim

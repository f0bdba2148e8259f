// The cameras that see a served field (twinsim serve, docs/serve.md "Several cameras";
// the scene's `cameras:`, docs/scenes.md). The league's fields are seen by several
// cameras with overlapping views, each sending its own detection frames; a team's
// vision filter merges them. Here the area inside the walls is split into a grid of
// `columns` x `rows` equal cells, each widened by half the `overlap` on its inner
// sides, one camera above each cell's centre: an object in an overlap is seen by
// every camera whose area holds it (two, or four at a corner of four cells).
//
//   cameras: {columns: 2, rows: 2, overlap: 0.4, height: 4}   # grSim's four
//
// Camera ids run along x first, from -x to +x, then along y from -y to +y.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "engines/omni_engine.h"

namespace twinsim {

struct CameraGrid {
  int columns = 1;
  int rows = 1;
  double overlap = 0.4;  // m that neighbouring cameras both see
  double height = 4;     // m above the floor
};

struct CameraView {
  int id = 0;
  Eigen::Vector2d low = Eigen::Vector2d::Zero();   // m, field frame: the area's corner at the smallest x, y
  Eigen::Vector2d high = Eigen::Vector2d::Zero();  // m: at the largest x, y
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m: above the cell's centre
  // Whether the camera sees the point (x, y) (m, field frame; the area's edges included).
  bool Sees(double x, double y) const { return x >= low.x() && x <= high.x() && y >= low.y() && y <= high.y(); }
};

// The cameras of `grid` over `field` (the area inside its walls).
std::vector<CameraView> CameraViews(const CameraGrid& grid, const FieldModel& field);

}  // namespace twinsim

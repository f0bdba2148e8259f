#include "scene/camera_layout.h"

#include <algorithm>

namespace twinsim {

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

}  // namespace twinsim

// 3D path plots: tool paths in space (an arm's end effector, the letters of a writing
// task) and their references, in metres, as an orthographic view with equal scale on
// all three axes.
//
// The view looks at the paths' bounding box from `azimuth_deg` around z (0: from +x,
// 90: from +y) and `elevation_deg` above the floor, like matplotlib's view_init. The box
// is drawn as light grey edges, with light grey grid lines on its three back faces,
// tick labels in metres on two floor edges and one vertical edge, and the axis labels
// "x [m]", "y [m]", "z [m]". Each path has the look of the 2D path plot (plot.h): its
// Okabe-Ito colour and line style, a circle where it starts and a square where it
// ends, and (optionally) a light grey shadow on the floor of the box. A legend goes
// into the emptiest corner (right of the picture when no corner is free of data) and
// the bold title on top. Hidden lines are not removed: the box and the grid are drawn
// first, the shadows over them, then the paths, then the markers.
//
//   Path3DPlot plot;
//   plot.title = "Writing \"ILC\", trial 10";
//   plot.paths.push_back({"reference", reference_points});
//   plot.paths.push_back({"tracked", tool_points});
//   RgbaImage image = RenderPath3DPlot(plot, *MakeDefaultRenderer());
//
// LayoutPath3DPlot() gives the geometry without drawing, and Path3DLayout::ToPixel()
// the world-to-pixel projection (for tests).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "io/png_image.h"
#include "render/renderer.h"

namespace twinsim {

struct Path3D {
  std::string name;                      // legend entry
  std::vector<Eigen::Vector3d> points;   // m; non-finite points break the line
};

struct Path3DPlot {
  std::string title;
  int width = 1200;             // px
  int height = 900;             // px
  double azimuth_deg = -60;     // deg, view direction around z (0: looking from +x towards -x)
  double elevation_deg = 25;    // deg, view direction above the x-y plane, -90..90
  std::vector<Path3D> paths;
  bool show_projection = true;  // a light grey shadow of each path on the floor (z = box minimum)
};

// Where everything lands in the image, and the projection from world to pixels.
struct Path3DLayout {
  int width = 0, height = 0;  // px
  Rect plot_area;    // px, the part of the image for the box, its ticks and labels
  Rect box;          // px, the bounding rectangle of the projected box
  Rect title;        // px, the title's text box (empty without a title)
  Rect legend;       // px, the legend box (empty without paths)
  bool legend_inside = true;  // false: right of the plot area
  Eigen::Vector3d box_min = Eigen::Vector3d::Zero();  // m, the box's corners
  Eigen::Vector3d box_max = Eigen::Vector3d::Ones();  // m
  Eigen::Vector3d step = Eigen::Vector3d::Ones();     // m between ticks on x, y, z
  double scale = 1;            // px per m, along every axis before foreshortening
  double azimuth = 0;          // rad
  double elevation = 0;        // rad
  Point2d origin;              // px, where the world origin projects

  // The screen's right and up directions in world coordinates (unit vectors).
  Eigen::Vector3d Right() const;
  Eigen::Vector3d Up() const;
  // The pixel position of a world point (m): orthographic, x right, y down, pixel (i, j)
  // spans [i, i+1] x [j, j+1]. Equals origin + scale * (p . Right(), -p . Up()).
  Point2d ToPixel(const Eigen::Vector3d& p) const;
};

// Geometry of a 3D path plot. Throws InputError for sizes below 240 x 180 or above
// 8192 px, and for an elevation outside -90..90 degrees.
Path3DLayout LayoutPath3DPlot(const Path3DPlot& plot);

// Draws a 3D path plot; *layout (if given) receives its geometry. Throws what the
// renderer throws (InputError from the null renderer) and what LayoutPath3DPlot() throws.
RgbaImage RenderPath3DPlot(const Path3DPlot& plot, Renderer& renderer, Path3DLayout* layout = nullptr);

}  // namespace twinsim

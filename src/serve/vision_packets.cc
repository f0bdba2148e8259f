#include "serve/vision_packets.h"

#include <cmath>
#include <string>

#include "core/math_constants.h"

namespace twinsim {
namespace {

// The one camera (when the scene names none): above the centre, looking down, its image
// covering the field.
constexpr double kCameraHeight = 4000;  // mm
constexpr double kFocalLength = 390;    // pixel
constexpr int kImageWidth = 780, kImageHeight = 580;  // pixel
// Robots' height as SSL-Vision is configured for them.
constexpr double kRobotHeight = 150;    // mm

// The one camera's view when the scene names none.
CameraView CentreCamera() {
  CameraView v;
  v.position = Eigen::Vector3d(0, 0, kCameraHeight / 1000);
  return v;
}

double FocalLength(const CameraView& camera) { return camera.focal_length > 0 ? camera.focal_length : kFocalLength; }

void Pixel(const CameraView& camera, double x_mm, double y_mm, float* px, float* py) {
  const double h = 1000 * camera.position.z(), f = FocalLength(camera);
  *px = static_cast<float>(kImageWidth / 2.0 + f * (x_mm - 1000 * camera.position.x()) / h);
  *py = static_cast<float>(kImageHeight / 2.0 - f * (y_mm - 1000 * camera.position.y()) / h);
}

void AddCalibration(SSL_GeometryData* g, const CameraView& camera) {
  SSL_GeometryCameraCalibration* c = g->add_calib();
  c->set_camera_id(static_cast<unsigned>(camera.id));
  c->set_focal_length(static_cast<float>(FocalLength(camera)));
  c->set_principal_point_x(kImageWidth / 2.0f);
  c->set_principal_point_y(kImageHeight / 2.0f);
  c->set_distortion(0);
  // A nominal calibration (no real camera): the identity rotation, the camera at
  // (tx, ty, tz), looking straight down.
  c->set_q0(1);
  c->set_q1(0);
  c->set_q2(0);
  c->set_q3(0);
  const Eigen::Vector3d mm = 1000 * camera.position;
  c->set_tx(static_cast<float>(mm.x()));
  c->set_ty(static_cast<float>(mm.y()));
  c->set_tz(static_cast<float>(mm.z()));
  c->set_derived_camera_world_tx(static_cast<float>(mm.x()));
  c->set_derived_camera_world_ty(static_cast<float>(mm.y()));
  c->set_derived_camera_world_tz(static_cast<float>(mm.z()));
  c->set_pixel_image_width(kImageWidth);
  c->set_pixel_image_height(kImageHeight);
}

void AddLine(SSL_GeometryFieldSize* f, const std::string& name, double x1, double y1, double x2, double y2,
             double thickness, SSL_FieldShapeType type) {
  SSL_FieldLineSegment* l = f->add_field_lines();
  l->set_name(name);
  l->mutable_p1()->set_x(static_cast<float>(x1));
  l->mutable_p1()->set_y(static_cast<float>(y1));
  l->mutable_p2()->set_x(static_cast<float>(x2));
  l->mutable_p2()->set_y(static_cast<float>(y2));
  l->set_thickness(static_cast<float>(thickness));
  l->set_type(type);
}

}  // namespace

SSL_WrapperPacket DetectionPacket(const std::vector<Sighting>& seen, std::uint32_t frame_number, double t_capture,
                                  double t_sent, const std::optional<Eigen::Vector3d>& ball, const CameraView* camera) {
  static const CameraView kCentre = CentreCamera();
  const CameraView& view = camera != nullptr ? *camera : kCentre;
  SSL_WrapperPacket packet;
  SSL_DetectionFrame* frame = packet.mutable_detection();
  frame->set_frame_number(frame_number);
  frame->set_t_capture(t_capture);
  frame->set_t_sent(t_sent);
  frame->set_camera_id(static_cast<unsigned>(view.id));
  if (ball) {
    SSL_DetectionBall* b = frame->add_balls();
    const double x = 1000 * ball->x(), y = 1000 * ball->y();
    b->set_confidence(1.0f);
    b->set_x(static_cast<float>(x));
    b->set_y(static_cast<float>(y));
    b->set_z(static_cast<float>(1000 * ball->z()));
    float px, py;
    Pixel(view, x, y, &px, &py);
    b->set_pixel_x(px);
    b->set_pixel_y(py);
  }
  for (const Sighting& s : seen) {
    SSL_DetectionRobot* r =
        s.robot.team == TeamColor::kBlue ? frame->add_robots_blue() : frame->add_robots_yellow();
    const double x = 1000 * s.pose.x, y = 1000 * s.pose.y;
    r->set_confidence(1.0f);
    r->set_robot_id(static_cast<unsigned>(s.robot.id));
    r->set_x(static_cast<float>(x));
    r->set_y(static_cast<float>(y));
    r->set_orientation(static_cast<float>(s.pose.theta));
    float px, py;
    Pixel(view, x, y, &px, &py);
    r->set_pixel_x(px);
    r->set_pixel_y(py);
    r->set_height(static_cast<float>(kRobotHeight));
  }
  packet.set_source(SSL_SOURCE_OTHER);
  return packet;
}

SSL_WrapperPacket GeometryPacket(const FieldModel& field, double boundary, const std::vector<CameraView>& cameras) {
  SSL_WrapperPacket packet;
  SSL_GeometryData* g = packet.mutable_geometry();
  SSL_GeometryFieldSize* f = g->mutable_field();
  const double length = 1000 * (field.length - 2 * boundary), width = 1000 * (field.width - 2 * boundary);
  const double line = 10;  // mm
  f->set_field_length(static_cast<int>(std::lround(length)));
  f->set_field_width(static_cast<int>(std::lround(width)));
  f->set_goal_width(1000);
  f->set_goal_depth(180);
  f->set_boundary_width(static_cast<int>(std::lround(1000 * boundary)));
  f->set_penalty_area_depth(1000);
  f->set_penalty_area_width(2000);
  f->set_center_circle_radius(500);
  f->set_line_thickness(static_cast<int>(line));
  f->set_goal_center_to_penalty_mark(6000);
  f->set_goal_height(155);
  f->set_ball_radius(21.5f);
  f->set_max_robot_radius(90.0f);
  const double hx = length / 2, hy = width / 2;
  AddLine(f, "TopTouchLine", -hx, hy, hx, hy, line, TopTouchLine);
  AddLine(f, "BottomTouchLine", -hx, -hy, hx, -hy, line, BottomTouchLine);
  AddLine(f, "LeftGoalLine", -hx, -hy, -hx, hy, line, LeftGoalLine);
  AddLine(f, "RightGoalLine", hx, -hy, hx, hy, line, RightGoalLine);
  AddLine(f, "HalfwayLine", 0, -hy, 0, hy, line, HalfwayLine);
  AddLine(f, "CenterLine", -hx, 0, hx, 0, line, CenterLine);
  AddLine(f, "LeftPenaltyStretch", -hx + 1000, -1000, -hx + 1000, 1000, line, LeftPenaltyStretch);
  AddLine(f, "RightPenaltyStretch", hx - 1000, -1000, hx - 1000, 1000, line, RightPenaltyStretch);
  SSL_FieldCircularArc* circle = f->add_field_arcs();
  circle->set_name("CenterCircle");
  circle->mutable_center()->set_x(0);
  circle->mutable_center()->set_y(0);
  circle->set_radius(500);
  circle->set_a1(0);
  circle->set_a2(static_cast<float>(2 * kPi));
  circle->set_thickness(static_cast<float>(line));
  circle->set_type(CenterCircle);

  if (cameras.empty()) {
    AddCalibration(g, CentreCamera());
  } else {
    for (const CameraView& camera : cameras) AddCalibration(g, camera);
  }
  packet.set_source(SSL_SOURCE_OTHER);
  return packet;
}

}  // namespace twinsim

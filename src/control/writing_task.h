// The writing task of seed 001 (Bukkems et al., Fig. 6 and 7): the RRR arm's tool
// point writes block letters in a vertical plane in front of it, fast, along straight
// strokes with piecewise-constant accelerations, and the joint reference (q, qd, qdd)
// comes from the arm's closed-form inverse kinematics.
//
// The letters are polylines in a box `height` tall and `width_ratio * height` wide,
// drawn in the plane x = plane_x of the base frame, read by someone standing behind
// the arm and looking along +x (so the text runs from +y to -y). One continuous path
// visits every corner of every letter in turn; the moves between letters are strokes
// too. Along each stroke the tool point speeds up at `acceleration`, cruises at
// `speed` and slows down at `acceleration` (a triangle when the stroke is too short),
// and stops at its end, so the path's acceleration jumps at the start, end and ends of
// cruise of every stroke, as in the seed.
//
// Inverse kinematics (WaistShoulderElbowIk) assumes the RRR structure: a vertical
// waist axis through the base origin, a horizontal shoulder axis on it and a parallel
// elbow axis, the arm stretched along +x at q = 0 with positive shoulder and elbow
// angles raising it (models/rrr.yaml). Then
//   q1 = atan2(y, x),  r = sqrt(x^2 + y^2),  z' = z - z_shoulder,
//   cos q3 = (r^2 + z'^2 - L1^2 - L2^2) / (2 L1 L2),  q3 = -acos(.)   (elbow up),
//   q2 = atan2(z', r) - atan2(L2 sin q3, L1 + L2 cos q3),
// with L1 the shoulder-to-elbow distance (the elbow joint's origin) and L2 the
// elbow-to-tool distance. The velocities and accelerations are exact, not differenced:
//   qd = J^-1 pd,   qdd = J^-1 (pdd - Jd qd),
// with J the tool point's 3 x 3 positional Jacobian and Jd qd its closed form.
//
//   ArmModel arm = LoadArmModel("models/rrr.yaml");
//   ArmReference ref = WritingTaskReference(arm, WritingTaskOptions{});
//   // ref.q.row(k) is the reference at t = ref.t(k) = k * arm.sample_time
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "robots/arm/arm_model.h"

namespace twinsim {

// A sampled joint reference, one row per sample.
struct ArmReference {
  Eigen::VectorXd t;             // N, s: k * sample_time
  Eigen::MatrixXd q, qd, qdd;    // N x dof: rad, rad/s, rad/s^2
  Eigen::MatrixXd p, pd, pdd;    // N x 3: the tool point's path in the base frame, m, m/s, m/s^2
  double sample_time = 0;        // s
};

struct WritingTaskOptions {
  std::string letters = "TUE";   // from WritingTaskLetters(); a space leaves a gap
  double height = 0.25;          // m, letter height
  double width_ratio = 0.6;      // letter width / height
  double gap_ratio = 0.3;        // gap between letters / height
  double plane_x = 0.45;         // m, the writing plane x = plane_x (base frame)
  double center_y = 0;           // m, centre of the text's box
  double center_z = 0.30;        // m
  double speed = 0.8;            // m/s, cruise speed of the tool point along a stroke
  double acceleration = 5;       // m/s^2, the tool point's speed-up and slow-down
  double hold_before = 0.1;      // s at rest at the first point before writing
  double hold_after = 0.1;       // s at rest at the last point after writing
  // m, the tool point in the last link's frame; the RRR arm's forearm end (the last DH
  // row's a = 0.35 m lies beyond the elbow along the link's x axis).
  Eigen::Vector3d tool = Eigen::Vector3d(0.35, 0, 0);
  // s: the reference's sample time; 0 = the model's sample_time.
  double sample_time = 0;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// The letters that have strokes ("AEFHILMNTUVWZ" and the space).
std::string WritingTaskLetters();

// The corners of the path in the base frame (3 x n, m), first to last, for `options`.
// Throws InputError for invalid options.
Eigen::Matrix3Xd WritingTaskCorners(const WritingTaskOptions& options);

// The tool point of `model` at q (base frame, m), `tool` in the last link's frame.
Eigen::Vector3d ToolPoint(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::Vector3d& tool);

// The tool point's positional Jacobian (3 x dof) at q.
Eigen::MatrixXd ToolJacobian(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::Vector3d& tool);

// Jd(q, qd) qd (3, m/s^2): the tool point's acceleration when qdd = 0.
Eigen::Vector3d ToolBiasAcceleration(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                     const Eigen::Vector3d& tool);

// Closed-form elbow-up inverse kinematics of a waist-shoulder-elbow arm: the joint
// angles (rad) putting `tool` at `point` (base frame, m). Throws InputError
// when the model is not such an arm (checked by forward kinematics) or the point is out
// of reach or needs a joint beyond its limits.
Eigen::VectorXd WaistShoulderElbowIk(const ArmModel& model, const Eigen::Vector3d& point,
                                     const Eigen::Vector3d& tool);

// The writing task's joint reference for `model`. Throws InputError for
// invalid options, an arm that is not waist-shoulder-elbow, or a path point out of
// reach or beyond a joint's limits.
ArmReference WritingTaskReference(const ArmModel& model, const WritingTaskOptions& options);

}  // namespace twinsim

// The writing task's path (letters as polylines, trapezoidal speed along each stroke)
// and the RRR arm's closed-form inverse kinematics; see writing_task.h.
#include "control/writing_task.h"

#include <Eigen/LU>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/error.h"
#include "robots/arm/arm_dynamics.h"

namespace twinsim {
namespace {

using Corners = std::vector<std::pair<double, double>>;  // (u, v) in the unit letter box

// Block letters in a unit box: u from the letter's left (0) to its right (1), v from
// its foot (0) to its top (1); one polyline per letter, strokes may retrace.
const std::map<char, Corners>& LetterTable() {
  static const std::map<char, Corners> table = {
      {'A', {{0, 0}, {0.5, 1}, {1, 0}, {0.75, 0.5}, {0.25, 0.5}}},
      {'E', {{1, 1}, {0, 1}, {0, 0.5}, {0.8, 0.5}, {0, 0.5}, {0, 0}, {1, 0}}},
      {'F', {{1, 1}, {0, 1}, {0, 0.5}, {0.8, 0.5}, {0, 0.5}, {0, 0}}},
      {'H', {{0, 1}, {0, 0}, {0, 0.5}, {1, 0.5}, {1, 1}, {1, 0}}},
      {'I', {{0.5, 1}, {0.5, 0}}},
      {'L', {{0, 1}, {0, 0}, {1, 0}}},
      {'M', {{0, 0}, {0, 1}, {0.5, 0.4}, {1, 1}, {1, 0}}},
      {'N', {{0, 0}, {0, 1}, {1, 0}, {1, 1}}},
      {'R', {{0, 0}, {0, 1}, {0.75, 1}, {1, 0.85}, {1, 0.65}, {0.75, 0.5}, {0, 0.5}, {1, 0}}},
      {'T', {{0, 1}, {1, 1}, {0.5, 1}, {0.5, 0}}},
      {'U', {{0, 1}, {0, 0}, {1, 0}, {1, 1}}},
      {'V', {{0, 1}, {0.5, 0}, {1, 1}}},
      {'W', {{0, 1}, {0.25, 0}, {0.5, 0.6}, {0.75, 0}, {1, 1}}},
      {'Z', {{0, 1}, {1, 1}, {0, 0}, {1, 0}}},
  };
  return table;
}

bool PositiveFinite(double x) { return std::isfinite(x) && x > 0; }

// One straight stroke from rest to rest: speed up at a, cruise at v_peak, slow down.
struct Stroke {
  Eigen::Vector3d start, direction;  // m, unit
  double length = 0;                 // m
  double accel = 0;                  // m/s^2
  double v_peak = 0;                 // m/s
  double t_accel = 0, t_cruise = 0;  // s
  double duration() const { return 2 * t_accel + t_cruise; }
};

Stroke MakeStroke(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double speed, double accel) {
  Stroke s;
  s.start = a;
  s.length = (b - a).norm();
  s.direction = (b - a) / s.length;
  s.accel = accel;
  if (s.length >= speed * speed / accel) {
    s.v_peak = speed;
    s.t_accel = speed / accel;
    s.t_cruise = (s.length - speed * speed / accel) / speed;
  } else {  // a triangle: never reaches the cruise speed
    s.v_peak = std::sqrt(s.length * accel);
    s.t_accel = s.v_peak / accel;
    s.t_cruise = 0;
  }
  return s;
}

// Arc length (m), speed (m/s) and acceleration (m/s^2) along the stroke at tau (s).
void StrokeProfile(const Stroke& s, double tau, double* pos, double* vel, double* acc) {
  const double a = s.accel;
  const double t1 = s.t_accel, t2 = s.t_accel + s.t_cruise, t3 = s.duration();
  if (tau <= 0) {
    *pos = 0, *vel = 0, *acc = 0;
  } else if (tau < t1) {
    *pos = 0.5 * a * tau * tau, *vel = a * tau, *acc = a;
  } else if (tau < t2) {
    *pos = 0.5 * a * t1 * t1 + s.v_peak * (tau - t1), *vel = s.v_peak, *acc = 0;
  } else if (tau < t3) {
    const double r = t3 - tau;  // time left
    *pos = s.length - 0.5 * a * r * r, *vel = a * r, *acc = -a;
  } else {
    *pos = s.length, *vel = 0, *acc = 0;
  }
}

// The stretched arm's lengths: shoulder point (base frame), L1 (shoulder to elbow) and
// L2 (elbow to tool), m.
struct ArmGeometry {
  Eigen::Vector3d shoulder;
  double l1 = 0, l2 = 0;
};

ArmGeometry Geometry(const ArmModel& model, const Eigen::Vector3d& tool) {
  if (model.dof() != 3) {
    throw InputError("the writing task: '" + model.name + "' has " + std::to_string(model.dof()) +
                     " joints, a waist-shoulder-elbow arm has 3");
  }
  for (const ArmJoint& j : model.joints) {
    if (j.type != JointType::kRevolute) {
      throw InputError("the writing task: joint '" + j.name + "' of '" + model.name +
                       "' is not revolute");
    }
  }
  const std::vector<Eigen::Isometry3d> frames = ForwardKinematics(model, Eigen::VectorXd::Zero(3));
  ArmGeometry g;
  g.shoulder = frames[1].translation();
  const Eigen::Vector3d elbow = frames[2].translation();
  g.l1 = (elbow - g.shoulder).norm();
  g.l2 = (frames[2] * tool - elbow).norm();
  if (g.l1 <= 0 || g.l2 <= 0) {
    throw InputError("the writing task: '" + model.name + "' has a zero-length upper arm or forearm");
  }
  return g;
}

std::string Vec(const Eigen::Vector3d& p) {
  std::ostringstream out;
  out << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return out.str();
}

}  // namespace

bool WritingTaskOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  if (letters.empty()) return fail("letters is empty");
  bool any = false;
  for (char c : letters) {
    if (c == ' ') continue;
    if (!LetterTable().count(c)) {
      return fail(std::string("letter '") + c + "' has no strokes (known: " + WritingTaskLetters() + ")");
    }
    any = true;
  }
  if (!any) return fail("letters has only spaces");
  if (!PositiveFinite(height)) return fail("height must be > 0 (m)");
  if (!PositiveFinite(width_ratio)) return fail("width_ratio must be > 0");
  if (!(std::isfinite(gap_ratio) && gap_ratio >= 0)) return fail("gap_ratio must be >= 0");
  if (!std::isfinite(plane_x) || !std::isfinite(center_y) || !std::isfinite(center_z)) {
    return fail("plane_x, center_y and center_z must be finite (m)");
  }
  if (!PositiveFinite(speed)) return fail("speed must be > 0 (m/s)");
  if (!PositiveFinite(acceleration)) return fail("acceleration must be > 0 (m/s^2)");
  if (!(std::isfinite(hold_before) && hold_before >= 0)) return fail("hold_before must be >= 0 (s)");
  if (!(std::isfinite(hold_after) && hold_after >= 0)) return fail("hold_after must be >= 0 (s)");
  if (!tool.allFinite()) return fail("tool must be finite (m)");
  if (!(std::isfinite(sample_time) && sample_time >= 0)) return fail("sample_time must be >= 0 (s; 0 = the model's)");
  return true;
}

std::string WritingTaskLetters() {
  std::string known;
  for (const auto& [c, corners] : LetterTable()) known += c;
  return known;
}

Eigen::Matrix3Xd WritingTaskCorners(const WritingTaskOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("WritingTaskOptions: " + why);
  const double h = options.height, w = options.width_ratio * h, gap = options.gap_ratio * h;
  const double n = static_cast<double>(options.letters.size());
  const double total_width = n * w + (n - 1) * gap;
  const double y_left = options.center_y + 0.5 * total_width;  // the text runs towards -y
  const double z_foot = options.center_z - 0.5 * h;
  std::vector<Eigen::Vector3d> points;
  for (std::size_t k = 0; k < options.letters.size(); ++k) {
    const char c = options.letters[k];
    if (c == ' ') continue;
    const double offset = static_cast<double>(k) * (w + gap);
    for (const auto& [u, v] : LetterTable().at(c)) {
      const Eigen::Vector3d p(options.plane_x, y_left - offset - u * w, z_foot + v * h);
      if (points.empty() || (p - points.back()).norm() > 1e-12) points.push_back(p);
    }
  }
  Eigen::Matrix3Xd out(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t k = 0; k < points.size(); ++k) out.col(static_cast<Eigen::Index>(k)) = points[k];
  return out;
}

Eigen::Vector3d ToolPoint(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::Vector3d& tool) {
  return ForwardKinematics(model, q).back() * tool;
}

Eigen::MatrixXd ToolJacobian(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::Vector3d& tool) {
  const std::vector<Eigen::Isometry3d> frames = ForwardKinematics(model, q);
  const Eigen::Vector3d p = frames.back() * tool;
  Eigen::MatrixXd jac(3, model.dof());
  for (int i = 0; i < model.dof(); ++i) {
    const Eigen::Vector3d z = frames[i].linear() * model.joints[i].axis;
    if (model.joints[i].type == JointType::kRevolute) {
      jac.col(i) = z.cross(p - frames[i].translation());
    } else {
      jac.col(i) = z;
    }
  }
  return jac;
}

Eigen::Vector3d ToolBiasAcceleration(const ArmModel& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                     const Eigen::Vector3d& tool) {
  // Each column's time derivative: the axis z_i turns with link i-1's angular velocity,
  // the axis' point o_i moves with link i-1, and the tool point moves at J qd.
  const std::vector<Eigen::Isometry3d> frames = ForwardKinematics(model, q);
  const int n = model.dof();
  const Eigen::Vector3d p = frames.back() * tool;
  std::vector<Eigen::Vector3d> z(n), o(n);
  for (int i = 0; i < n; ++i) {
    z[i] = frames[i].linear() * model.joints[i].axis;
    o[i] = frames[i].translation();
  }
  const Eigen::Vector3d vp = ToolJacobian(model, q, tool) * qd;
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();  // angular velocity of link i-1
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d vo = Eigen::Vector3d::Zero();  // velocity of o_i (fixed in link i-1)
    for (int j = 0; j < i; ++j) {
      vo += (model.joints[j].type == JointType::kRevolute ? Eigen::Vector3d(z[j].cross(o[i] - o[j])) : z[j]) * qd(j);
    }
    const Eigen::Vector3d zdot = omega.cross(z[i]);
    Eigen::Vector3d column_dot;
    if (model.joints[i].type == JointType::kRevolute) {
      column_dot = zdot.cross(p - o[i]) + z[i].cross(vp - vo);
      omega += z[i] * qd(i);
    } else {
      column_dot = zdot;
    }
    bias += column_dot * qd(i);
  }
  return bias;
}

Eigen::VectorXd WaistShoulderElbowIk(const ArmModel& model, const Eigen::Vector3d& point,
                                     const Eigen::Vector3d& tool) {
  const ArmGeometry g = Geometry(model, tool);
  const double r = std::hypot(point.x(), point.y());
  if (r < 1e-9) {
    throw InputError("the writing task: point " + Vec(point) + " is on the waist axis (singular)");
  }
  const double zp = point.z() - g.shoulder.z();
  const double c = (r * r + zp * zp - g.l1 * g.l1 - g.l2 * g.l2) / (2 * g.l1 * g.l2);
  if (c > 1 + 1e-12 || c < -1 - 1e-12) {
    std::ostringstream out;
    out << "the writing task: point " << Vec(point) << " is out of reach of '" << model.name << "' (distance "
        << std::hypot(r, zp) << " m from the shoulder, reach " << std::abs(g.l1 - g.l2) << " to " << g.l1 + g.l2
        << " m)";
    throw InputError(out.str());
  }
  Eigen::VectorXd q(3);
  q(0) = std::atan2(point.y(), point.x());
  q(2) = -std::acos(std::max(-1.0, std::min(1.0, c)));  // elbow up
  q(1) = std::atan2(zp, r) - std::atan2(g.l2 * std::sin(q(2)), g.l1 + g.l2 * std::cos(q(2)));
  const Eigen::Vector3d reached = ToolPoint(model, q, tool);
  if ((reached - point).norm() > 1e-9) {
    throw InputError("the writing task: '" + model.name +
                     "' is not a waist-shoulder-elbow arm stretched along +x at q = 0 (the closed form "
                     "reaches " + Vec(reached) + " instead of " + Vec(point) + ")");
  }
  for (int i = 0; i < 3; ++i) {
    const ArmJoint& j = model.joints[i];
    if (q(i) < j.lower || q(i) > j.upper) {
      std::ostringstream out;
      out << "the writing task: point " << Vec(point) << " needs joint '" << j.name << "' at " << q(i)
          << " rad, beyond its limits [" << j.lower << ", " << j.upper << "]";
      throw InputError(out.str());
    }
  }
  return q;
}

ArmReference WritingTaskReference(const ArmModel& model, const WritingTaskOptions& options) {
  const Eigen::Matrix3Xd corners = WritingTaskCorners(options);  // validates the options
  const double ts = options.sample_time > 0 ? options.sample_time : model.sample_time;
  if (!PositiveFinite(ts)) throw InputError("WritingTaskReference: the sample time must be > 0");
  std::vector<Stroke> strokes;
  for (Eigen::Index k = 1; k < corners.cols(); ++k) {
    strokes.push_back(MakeStroke(corners.col(k - 1), corners.col(k), options.speed, options.acceleration));
  }
  std::vector<double> start_times;  // s, when each stroke begins
  double t_end = options.hold_before;
  for (const Stroke& s : strokes) {
    start_times.push_back(t_end);
    t_end += s.duration();
  }
  const double total = t_end + options.hold_after;
  const Eigen::Index samples = static_cast<Eigen::Index>(std::floor(total / ts + 1e-9)) + 1;

  ArmReference ref;
  ref.sample_time = ts;
  const int n = model.dof();
  ref.t.resize(samples);
  ref.q.resize(samples, n), ref.qd.resize(samples, n), ref.qdd.resize(samples, n);
  ref.p.resize(samples, 3), ref.pd.resize(samples, 3), ref.pdd.resize(samples, 3);
  std::size_t current = 0;
  for (Eigen::Index k = 0; k < samples; ++k) {
    const double t = static_cast<double>(k) * ts;
    while (current + 1 < strokes.size() && t >= start_times[current + 1]) ++current;
    Eigen::Vector3d p, pd = Eigen::Vector3d::Zero(), pdd = Eigen::Vector3d::Zero();
    if (strokes.empty()) {
      p = corners.col(0);
    } else {
      const Stroke& s = strokes[current];
      double pos, vel, acc;
      StrokeProfile(s, t - start_times[current], &pos, &vel, &acc);
      p = s.start + pos * s.direction;
      pd = vel * s.direction;
      pdd = acc * s.direction;
    }
    const Eigen::VectorXd q = WaistShoulderElbowIk(model, p, options.tool);
    const Eigen::MatrixXd jac = ToolJacobian(model, q, options.tool);
    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(jac);
    if (!(std::abs(lu.determinant()) > 1e-9)) {
      throw InputError("WritingTaskReference: the arm is singular at " + Vec(p));
    }
    const Eigen::VectorXd qd = lu.solve(pd);
    const Eigen::VectorXd qdd = lu.solve(pdd - ToolBiasAcceleration(model, q, qd, options.tool));
    ref.t(k) = t;
    ref.q.row(k) = q.transpose(), ref.qd.row(k) = qd.transpose(), ref.qdd.row(k) = qdd.transpose();
    ref.p.row(k) = p.transpose(), ref.pd.row(k) = pd.transpose(), ref.pdd.row(k) = pdd.transpose();
  }
  return ref;
}

}  // namespace twinsim

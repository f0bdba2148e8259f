#include "robots/omni/omni_model.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/math_constants.h"

namespace twinsim {

Eigen::Matrix<double, 6, 1> PidGains::AsVector() const {
  Eigen::Matrix<double, 6, 1> v;
  v << kp, ki, kd, integral_limit, output_limit, slew_rate;
  return v;
}

PidGains PidGains::FromVector(const Eigen::Matrix<double, 6, 1>& v) {
  PidGains g;
  g.kp = v[0];
  g.ki = v[1];
  g.kd = v[2];
  g.integral_limit = v[3];
  g.output_limit = v[4];
  g.slew_rate = v[5];
  return g;
}

double OmniModel::ObserverNoiseXy() const {
  const double given = observer.measurement_noise_xy > 0 ? observer.measurement_noise_xy : vision_noise_xy;
  return std::max(given, OmniObserverModel::kMinMeasurementNoiseXy);
}

double OmniModel::ObserverNoiseTheta() const {
  const double given = observer.measurement_noise_theta > 0 ? observer.measurement_noise_theta : vision_noise_theta;
  return std::max(given, OmniObserverModel::kMinMeasurementNoiseTheta);
}

void OmniModel::Finalize() {
  const int n = num_wheels();
  const double r = wheel_radius, m_w = wheel_mass;
  total_mass = chassis_mass + n * m_w;
  wheel_spin_inertia = 0.5 * m_w * r * r;
  wheel_inertia_diametral = 0.25 * m_w * r * r + m_w * wheel_width * wheel_width / 12.0;
  const double chassis_iz =
      chassis_inertia_z > 0 ? chassis_inertia_z : 0.5 * chassis_mass * chassis_radius * chassis_radius;
  // Each wheel spins about a horizontal axle, so its vertical axis is a diameter.
  total_inertia_z = chassis_iz + chassis_mass * chassis_com.squaredNorm() +
                    n * (wheel_inertia_diametral + m_w * wheel_distance * wheel_distance);

  // The wheels sit off the centre unless the layout is symmetric front to back.
  com_offset = chassis_mass * chassis_com;
  for (int i = 0; i < n; ++i)
    com_offset += m_w * wheel_distance * Eigen::Vector2d(std::cos(wheel_angles[i]), std::sin(wheel_angles[i]));
  com_offset /= total_mass;

  geometry.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    geometry(i, 0) = -std::sin(wheel_angles[i]);
    geometry(i, 1) = std::cos(wheel_angles[i]);
    geometry(i, 2) = wheel_distance;
  }

  // Static wheel loads: with equal contact stiffness under a rigid chassis, the loads
  // are the least-norm solution of the three equilibrium equations (exact for 3 wheels):
  // sum N = m g, and their moments balance the weight at the centre of mass.
  wheel_load.setZero(n);
  if (n >= 3) {
    Eigen::MatrixXd a(3, n);
    for (int i = 0; i < n; ++i) {
      a(0, i) = 1;
      a(1, i) = wheel_distance * std::cos(wheel_angles[i]);
      a(2, i) = wheel_distance * std::sin(wheel_angles[i]);
    }
    const Eigen::Vector3d rhs =
        total_mass * kGravity * Eigen::Vector3d(1, com_offset.x(), com_offset.y());
    wheel_load = a.transpose() * (a * a.transpose()).ldlt().solve(rhs);
  }
}

Eigen::Matrix3d OmniModel::RigidBodyMass() const {
  const double m = total_mass, xc = com_offset.x(), yc = com_offset.y();
  Eigen::Matrix3d mass;
  mass << m, 0, -m * yc, 0, m, m * xc, -m * yc, m * xc, total_inertia_z;
  return mass;
}

bool SameWheelAngle(double a, double b) { return std::abs(std::remainder(a - b, 2 * kPi)) < 1e-3; }

std::string OmniModel::Validate() const {
  std::ostringstream out;
  const int n = num_wheels();
  if (n < 3) out << "an omni robot needs at least 3 wheels, got " << n << "\n";
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (SameWheelAngle(wheel_angles[i], wheel_angles[j]))
        out << "wheels " << i + 1 << " and " << j + 1 << " are at the same angle\n";
    }
  }
  if (wheel_distance >= chassis_radius + wheel_width)
    out << "wheel_distance " << wheel_distance << " m puts the wheels outside the chassis (radius "
        << chassis_radius << " m)\n";
  if (ground_clearance >= 2 * wheel_radius)
    out << "ground_clearance must be below the wheel diameter\n";
  if (!(chassis_com.allFinite() && chassis_com.norm() < 0.5 * chassis_radius))
    out << "chassis com must lie within half the chassis radius of the centre (" << 0.5 * chassis_radius << " m)\n";
  if (com_height <= ground_clearance || com_height >= ground_clearance + chassis_height)
    out << "com_height must lie inside the chassis (between " << ground_clearance << " and "
        << ground_clearance + chassis_height << " m)\n";
  const auto& scales = observer.interval_scale;
  for (std::size_t i = 0; i < scales.size(); ++i) {
    constexpr double kMost = OmniObserverModel::kMaxIntervalScale;
    const auto in_range = [](double v) { return v >= 1 / kMost && v <= kMost; };
    if (scales[i].frames < 1 || (i > 0 && scales[i].frames <= scales[i - 1].frames))
      out << "observer interval_scale: the horizons must be at least 1 frame and increase\n";
    if (!in_range(scales[i].position) || !in_range(scales[i].heading))
      out << "observer interval_scale: the scales must lie in [" << 1 / kMost << ", " << kMost << "]\n";
    const auto growth_in_range = [](double g) { return g >= 0 && g <= OmniObserverModel::kMaxIntervalGrowth; };
    if (!growth_in_range(scales[i].position_growth) || !growth_in_range(scales[i].heading_growth))
      out << "observer interval_scale: the growths must lie in [0, " << OmniObserverModel::kMaxIntervalGrowth << "]\n";
    if ((scales[i].position_growth > 0 || scales[i].heading_growth > 0) && observer.seen_inputs.empty())
      out << "observer interval_scale: a growth needs observer.seen_inputs to measure distances from\n";
  }
  const OmniSeenInputs& seen = observer.seen_inputs;
  for (const Eigen::VectorXd& p : seen.points) {
    if (p.size() != 2 * n || !p.allFinite()) {
      out << "observer seen_inputs: each point must hold " << 2 * n << " finite wheel speeds (command, then body)\n";
      break;
    }
  }
  if (!seen.empty() && !(seen.scale > 0 && std::isfinite(seen.scale)))
    out << "observer seen_inputs: the scale must be positive\n";
  const OmniObserverModel::ParameterCovariance& pc = observer.parameter_covariance;
  if (!pc.empty()) {
    const long k = static_cast<long>(pc.parameters.size());
    if (pc.matrix.rows() != k || pc.matrix.cols() != k || !pc.matrix.allFinite()) {
      out << "observer parameter_covariance: the matrix must be " << k << " x " << k << " finite numbers, one row per parameter\n";
    } else if ((pc.matrix.diagonal().array() <= 0).any() ||
               (pc.matrix - pc.matrix.transpose()).cwiseAbs().maxCoeff() > 1e-9 * pc.matrix.diagonal().maxCoeff()) {
      out << "observer parameter_covariance: the matrix must be symmetric with a positive diagonal\n";
    }
    for (long i = 0; i < k; ++i)
      for (long j = 0; j < i; ++j)
        if (pc.parameters[static_cast<std::size_t>(i)] == pc.parameters[static_cast<std::size_t>(j)])
          out << "observer parameter_covariance: '" << pc.parameters[static_cast<std::size_t>(i)] << "' is listed twice\n";
  }
  if (!motor_strength.empty() && static_cast<int>(motor_strength.size()) != n)
    out << "motor strength lists " << motor_strength.size() << " values for " << n << " wheels\n";
  if (n >= 3) {
    // The wheels must span all three body velocities, and hold the robot up.
    Eigen::MatrixXd g(n, 3);
    for (int i = 0; i < n; ++i)
      g.row(i) << -std::sin(wheel_angles[i]), std::cos(wheel_angles[i]), wheel_distance;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(g);
    if (svd.singularValues()(2) < 1e-3 * svd.singularValues()(0))
      out << "the wheel layout cannot produce every body velocity (wheel angles are degenerate)\n";
    OmniModel copy = *this;
    copy.Finalize();
    if (copy.wheel_load.minCoeff() <= 0)
      out << "the wheels do not surround the centre of mass: a wheel would carry no load\n";
  }
  std::string s = out.str();
  if (!s.empty()) s.pop_back();
  return s;
}

std::string ReplayEngineFor(const OmniModel& model, const std::string& asked, const std::string& fallback,
                            std::string* note) {
  if (note) note->clear();
  if (asked.empty()) return model.fitted_on.empty() ? fallback : model.fitted_on;
  if (note && !model.fitted_on.empty() && asked != model.fitted_on && asked != "learned") {
    *note = model.name + " was fitted on the " + model.fitted_on + " engine (fitted_on); replaying it on " + asked +
            " as asked: the engines part where the wheels near their grip (fast turns, hard stops), and there " + asked +
            " does not follow the fitted response";
  }
  return asked;
}

std::array<double, 2> IntervalScaleAt(const std::vector<OmniObserverModel::IntervalScale>& scales, int k,
                                      double distance) {
  using IntervalScale = OmniObserverModel::IntervalScale;
  if (scales.empty()) return {1, 1};
  auto at = [distance](const IntervalScale& h) -> std::array<double, 2> {
    return {h.position * (1 + h.position_growth * distance), h.heading * (1 + h.heading_growth * distance)};
  };
  const IntervalScale& first = scales.front();
  const IntervalScale& last = scales.back();
  if (k <= first.frames) return at(first);
  if (k >= last.frames) return at(last);
  std::size_t i = 1;
  while (scales[i].frames < k) ++i;
  const IntervalScale& a = scales[i - 1];
  const IntervalScale& b = scales[i];
  const double u = std::log(static_cast<double>(k) / a.frames) / std::log(static_cast<double>(b.frames) / a.frames);
  auto between = [u](double x, double y) { return std::exp((1 - u) * std::log(x) + u * std::log(y)); };
  IntervalScale h;
  h.position = between(a.position, b.position);
  h.heading = between(a.heading, b.heading);
  h.position_growth = (1 - u) * a.position_growth + u * b.position_growth;
  h.heading_growth = (1 - u) * a.heading_growth + u * b.heading_growth;
  return at(h);
}

std::array<double, 2> OmniObserverModel::IntervalScaleAt(int k, double distance) const {
  return twinsim::IntervalScaleAt(interval_scale, k, distance);
}

}  // namespace twinsim

// Synthetic measurements of an arm for identification tests and benchmarks: a seeded
// multi-sine motion within the joint limits, the torques a "true" model needs for it,
// and the imperfections of real sensors (encoder quantisation, torque noise).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/math_constants.h"
#include "core/rng.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim::testing {

// q_j(t) = c_j + sum_k A_jk sin(2 pi k f0 t + phi_jk), k = 1..harmonics, scaled so that
// q stays within `range_fraction` of each joint's limits (at most +-1.5 rad about the
// middle) and |qd| below `max_speed`.
struct MultiSine {
  double f0 = 0.2;  // Hz
  Eigen::VectorXd centre;
  Eigen::MatrixXd amplitude;  // joints x harmonics, rad
  Eigen::MatrixXd phase;      // joints x harmonics, rad

  void At(double t, Eigen::VectorXd* q, Eigen::VectorXd* qd, Eigen::VectorXd* qdd) const {
    const int n = static_cast<int>(centre.size());
    q->resize(n);
    qd->resize(n);
    qdd->resize(n);
    for (int j = 0; j < n; ++j) {
      double p = centre[j], v = 0, a = 0;
      for (int k = 0; k < amplitude.cols(); ++k) {
        const double w = 2 * kPi * (k + 1) * f0, arg = w * t + phase(j, k);
        p += amplitude(j, k) * std::sin(arg);
        v += amplitude(j, k) * w * std::cos(arg);
        a -= amplitude(j, k) * w * w * std::sin(arg);
      }
      (*q)[j] = p;
      (*qd)[j] = v;
      (*qdd)[j] = a;
    }
  }
};

inline MultiSine MakeMultiSine(const ArmModel& model, std::uint64_t seed, int harmonics = 5, double f0 = 0.2,
                               double range_fraction = 0.8, double max_speed = 4.0) {
  const int n = model.dof();
  Rng rng(seed);
  MultiSine m;
  m.f0 = f0;
  m.centre.resize(n);
  m.amplitude.resize(n, harmonics);
  m.phase.resize(n, harmonics);
  for (int j = 0; j < n; ++j) {
    const ArmJoint& joint = model.joints[static_cast<std::size_t>(j)];
    const double lo = std::max(joint.lower, -10.0), hi = std::min(joint.upper, 10.0);
    m.centre[j] = 0.5 * (lo + hi);
    for (int k = 0; k < harmonics; ++k) {
      m.amplitude(j, k) = rng.Uniform(0.4, 1.0) / (k + 1);
      m.phase(j, k) = rng.Uniform(-kPi, kPi);
    }
    // Scale to the range and speed limits over one period.
    double peak = 0, speed = 0;
    for (int s = 0; s < 2000; ++s) {
      const double t = s / (2000 * f0);
      double p = 0, v = 0;
      for (int k = 0; k < harmonics; ++k) {
        const double w = 2 * kPi * (k + 1) * f0;
        p += m.amplitude(j, k) * std::sin(w * t + m.phase(j, k));
        v += m.amplitude(j, k) * w * std::cos(w * t + m.phase(j, k));
      }
      peak = std::max(peak, std::abs(p));
      speed = std::max(speed, std::abs(v));
    }
    const double half = std::min(1.5, range_fraction * 0.5 * (hi - lo));
    m.amplitude.row(j) *= std::min(half / peak, max_speed / speed);
  }
  return m;
}

struct SensorNoise {
  double counts_per_rev = 0;   // encoder counts per revolution; 0 = exact positions
  double torque_fraction = 0;  // torque noise std dev as a fraction of each joint's torque RMS
  std::uint64_t seed = 7;
};

// A log of `seconds` at `rate_hz` of `truth` following `motion`: t, q (quantised) and
// tau (noisy), with no qd/qdd (a reader derives them). `still_joint` (0-based, -1 none)
// is held at its centre.
inline ArmLog MakeSyntheticLog(const ArmModel& truth, const MultiSine& motion, double seconds, double rate_hz,
                               const SensorNoise& noise, int still_joint = -1) {
  const int n = truth.dof();
  const int rows = static_cast<int>(std::lround(seconds * rate_hz)) + 1;
  ArmLog log;
  log.path = "synthetic.csv";
  log.dof = n;
  log.t.resize(rows);
  log.q.resize(rows, n);
  log.tau.resize(rows, n);
  Eigen::VectorXd q, qd, qdd;
  for (int r = 0; r < rows; ++r) {
    log.t[r] = r / rate_hz;
    motion.At(log.t[r], &q, &qd, &qdd);
    if (still_joint >= 0) {
      q[still_joint] = motion.centre[still_joint] + 0.3;
      qd[still_joint] = qdd[still_joint] = 0;
    }
    log.tau.row(r) = InverseDynamics(truth, q, qd, qdd, true).transpose();
    if (noise.counts_per_rev > 0) {
      const double step = 2 * kPi / noise.counts_per_rev;
      for (int j = 0; j < n; ++j) q[j] = step * std::round(q[j] / step);
    }
    log.q.row(r) = q.transpose();
  }
  if (noise.torque_fraction > 0) {
    Rng rng(noise.seed);
    for (int j = 0; j < n; ++j) {
      const double sigma = noise.torque_fraction * std::sqrt(log.tau.col(j).squaredNorm() / rows);
      for (int r = 0; r < rows; ++r) log.tau(r, j) += rng.Gaussian(sigma);
    }
  }
  return log;
}

// A plant that differs from models/rrr.yaml (`a_priori`): heavier links (1.15x) and
// more viscous friction (1.3x). Its fit log follows multisine 3 for `fit_seconds`, its
// held-out log multisine 4 for half as long, both at 500 Hz with 1 % torque noise and
// read back as a reader gives them (qd and qdd derived from q).
struct HeavierRrr {
  ArmModel a_priori, truth;
  ArmLog fit, held_out;
};

inline HeavierRrr MakeHeavierRrr(const ArmModel& a_priori, double fit_seconds) {
  HeavierRrr c;
  c.a_priori = a_priori;
  c.truth = a_priori;
  for (auto& j : c.truth.joints) j.child.mass *= 1.15, j.viscous *= 1.3;
  SensorNoise noise;
  noise.torque_fraction = 0.01;
  const auto read = [](const ArmLog& log, const std::string& path) { return ParseArmLog(FormatArmLog(log, false), path); };
  c.fit = read(MakeSyntheticLog(c.truth, MakeMultiSine(c.truth, 3), fit_seconds, 500.0, noise), "fit.csv");
  c.held_out = read(MakeSyntheticLog(c.truth, MakeMultiSine(c.truth, 4), fit_seconds / 2, 500.0, noise), "held_out.csv");
  return c;
}

}  // namespace twinsim::testing

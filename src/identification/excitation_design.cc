#include "identification/excitation_design.h"

#include <ceres/first_order_function.h>
#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>

#include <Eigen/Dense>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <mutex>
#include <sstream>
#include <thread>

#include "core/error.h"
#include "core/math_constants.h"
#include "core/rng.h"
#include "io/printf_number.h"
#include "robots/arm/arm_dynamics.h"

namespace twinsim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// The penalties aim inside the limits by this fraction, so that the optimum, which
// leans on them, still passes the dense check.
constexpr double kPenaltyTightening = 0.01;

// The base columns that hold sign(qd_i): (joint, column).
std::vector<std::pair<int, int>> CoulombColumns(const ArmModel& model, const BaseParameters& base) {
  std::vector<std::pair<int, int>> out;
  const int n = model.dof();
  for (int c = 0; c < base.rank(); ++c) {
    const int s = base.independent[static_cast<std::size_t>(c)] - kParametersPerLink * n;
    if (s >= 0 && s % kFrictionPerJoint == 1) out.emplace_back(s / kFrictionPerJoint, c);
  }
  return out;
}

// Scales the oscillation about q0 by `s` (positions, velocities and accelerations all
// scale by s; the rest conditions stay satisfied).
FourierTrajectory Scaled(const FourierTrajectory& t, double s) {
  FourierTrajectory out = t;
  out.a *= s;
  out.b *= s;
  return out;
}

// True when q, qd, qdd and the nominal torque at t_k = k * dt (k < samples) are inside
// `limits`.
bool Feasible(const ArmModel& model, const FourierTrajectory& t, const ExcitationLimits& limits, double dt,
              int samples) {
  std::vector<JointMotion> motions;
  motions.reserve(static_cast<std::size_t>(samples));
  for (int k = 0; k < samples; ++k) {
    JointMotion m = EvaluateFourier(t, k * dt);
    for (int i = 0; i < t.dof(); ++i) {
      if (m.q[i] < limits.lower[i] || m.q[i] > limits.upper[i] || std::abs(m.qd[i]) > limits.velocity[i] ||
          std::abs(m.qdd[i]) > limits.acceleration[i])
        return false;
    }
    motions.push_back(std::move(m));
  }
  if ((limits.torque.array() < kInf).any()) {
    for (const JointMotion& m : motions) {
      const Eigen::VectorXd tau = InverseDynamics(model, m.q, m.qd, m.qdd);
      if ((tau.array().abs() > limits.torque.array()).any()) return false;
    }
  }
  return true;
}

// The largest s (up to `cap`) for which Scaled(t, s) is feasible on the grid, by
// doubling/halving and bisection; 0 when even the resting arm at q0 is not.
double LargestFeasibleScale(const ArmModel& model, const FourierTrajectory& t, const ExcitationLimits& limits,
                            double dt, int samples, double cap) {
  auto ok = [&](double s) { return Feasible(model, Scaled(t, s), limits, dt, samples); };
  if (!ok(0)) return 0;
  double lo = 0, hi = cap;
  if (ok(cap)) return cap;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (ok(mid) ? lo : hi) = mid;
    if (hi - lo < 1e-4 * hi) break;
  }
  return lo;
}

// Everything the criterion needs, shared read-only by every start.
struct DesignSetup {
  const ArmModel* model = nullptr;
  BaseParameters base;
  ExcitationLimits limits;      // what the design must respect
  ExcitationLimits penalty;     // tightened by kPenaltyTightening
  Eigen::VectorXd scales;       // r, S
  Eigen::VectorXd beta;         // r, the nominal model's base parameters
  std::vector<std::pair<int, int>> coulomb;
  bool torque_constrained = false;
  int n = 0, harmonics = 0, samples = 0;
  int first_free = 0;           // first harmonic (0-based) that is a free variable
  double omega = 0, fundamental = 0;
  double smoothing = 0.05;
  Eigen::MatrixXd sin_table, cos_table;  // samples x N: sin/cos(w l t_s)

  int PerJoint() const { return 1 + 2 * (harmonics - first_free); }
  int NumParameters() const { return n * PerJoint(); }

  // Sets the first harmonic so that qd(0) = 0 and qdd(0) = 0.
  void ApplyRest(FourierTrajectory* t) const {
    if (first_free == 0) return;
    for (int i = 0; i < n; ++i) {
      double sa = 0, sb = 0;
      for (int l = 1; l < harmonics; ++l) {
        sa += t->a(i, l);
        sb += (l + 1) * t->b(i, l);
      }
      t->a(i, 0) = -sa;
      t->b(i, 0) = -sb;
    }
  }

  FourierTrajectory ToTrajectory(const double* x) const {
    FourierTrajectory t = ZeroFourierTrajectory(n, harmonics, fundamental);
    for (int i = 0; i < n; ++i) {
      const double* p = x + i * PerJoint();
      t.q0[i] = p[0];
      const int free = harmonics - first_free;
      for (int l = first_free; l < harmonics; ++l) {
        t.a(i, l) = p[1 + (l - first_free)];
        t.b(i, l) = p[1 + free + (l - first_free)];
      }
    }
    ApplyRest(&t);
    return t;
  }

  Eigen::VectorXd FromTrajectory(const FourierTrajectory& t) const {
    Eigen::VectorXd x(NumParameters());
    const int free = harmonics - first_free;
    for (int i = 0; i < n; ++i) {
      double* p = x.data() + i * PerJoint();
      p[0] = t.q0[i];
      for (int l = first_free; l < harmonics; ++l) {
        p[1 + (l - first_free)] = t.a(i, l);
        p[1 + free + (l - first_free)] = t.b(i, l);
      }
    }
    return x;
  }

  // Y_b with tanh(qd / smoothing) for sign(qd): n x r, unscaled.
  Eigen::MatrixXd DesignRegressor(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                  const Eigen::VectorXd& qdd) const {
    Eigen::MatrixXd y = base.Reduce(Regressor(*model, q, qd, qdd));
    for (const auto& [joint, column] : coulomb) y(joint, column) = std::tanh(qd[joint] / smoothing);
    return y;
  }
};

// Hinge-squared penalty of v beyond [lo, hi], normalised by `scale`: adds to *cost and
// returns d/dv.
double Penalty(double v, double lo, double hi, double scale, double mu, double* cost) {
  double excess = 0;
  if (v > hi) excess = v - hi;
  else if (v < lo) excess = v - lo;
  if (excess == 0 || !std::isfinite(scale)) return 0;
  const double r = excess / scale;
  *cost += mu * r * r;
  return 2 * mu * r / scale;
}

// Samples the trajectory's joint motion over one period into `motion` and returns the stacked regressor W S^-1.
Eigen::MatrixXd SampleDesignMotion(const DesignSetup& s_, const FourierTrajectory& t,
                                   std::vector<JointMotion>* motion) {
  const int n = s_.n, r = s_.base.rank(), m = s_.samples, nh = s_.harmonics;
  Eigen::MatrixXd w(m * n, r);
  const Eigen::VectorXd inv_scale = s_.scales.cwiseInverse();
  for (int k = 0; k < m; ++k) {
    JointMotion& mo = (*motion)[static_cast<std::size_t>(k)];
    mo.q = t.q0;
    mo.qd = Eigen::VectorXd::Zero(n);
    mo.qdd = Eigen::VectorXd::Zero(n);
    for (int l = 0; l < nh; ++l) {
      const double wl = s_.omega * (l + 1), sn = s_.sin_table(k, l), cs = s_.cos_table(k, l);
      mo.q += (t.a.col(l) * sn - t.b.col(l) * cs) / wl;
      mo.qd += t.a.col(l) * cs + t.b.col(l) * sn;
      mo.qdd += (t.b.col(l) * cs - t.a.col(l) * sn) * wl;
    }
    w.middleRows(k * n, n) = s_.DesignRegressor(mo.q, mo.qd, mo.qdd) * inv_scale.asDiagonal();
  }
  return w;
}

// Adds to gq, gqd, gqdd the cost's sensitivity through the regressor: d<h, Y(q, qd, qdd)> / d(q, qd, qdd) per sample.
void AddRegressorSensitivity(const DesignSetup& s_, const std::vector<JointMotion>& motion,
                             const std::vector<Eigen::MatrixXd>& h, Eigen::MatrixXd* gq, Eigen::MatrixXd* gqd,
                             Eigen::MatrixXd* gqdd) {
  const int n = s_.n, m = s_.samples;
  // d<h, Y(q, qd, qdd)> / d(q, qd, qdd): central differences in q and qd, and an exact
  // forward difference in qdd (the regressor is affine in qdd).
  constexpr double kStep = 1e-6;
  for (int k = 0; k < m; ++k) {
    const JointMotion& mo = motion[static_cast<std::size_t>(k)];
    const Eigen::MatrixXd& hk = h[static_cast<std::size_t>(k)];
    auto dot = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
      return hk.cwiseProduct(s_.DesignRegressor(q, qd, qdd)).sum();
    };
    const double centre = dot(mo.q, mo.qd, mo.qdd);
    for (int i = 0; i < n; ++i) {
      Eigen::VectorXd a = mo.q, b = mo.q;
      a[i] += kStep;
      b[i] -= kStep;
      (*gq)(k, i) += (dot(a, mo.qd, mo.qdd) - dot(b, mo.qd, mo.qdd)) / (2 * kStep);
      a = mo.qd;
      b = mo.qd;
      a[i] += kStep;
      b[i] -= kStep;
      (*gqd)(k, i) += (dot(mo.q, a, mo.qdd) - dot(mo.q, b, mo.qdd)) / (2 * kStep);
      a = mo.qdd;
      a[i] += 1.0;
      (*gqdd)(k, i) += dot(mo.q, mo.qd, a) - centre;
    }
  }
}

// The gradient with respect to q0, a and b, through the Fourier basis, from the per-sample gq, gqd and gqdd.
FourierTrajectory FourierGradient(const DesignSetup& s_, const FourierTrajectory& t, const Eigen::MatrixXd& gq,
                                  const Eigen::MatrixXd& gqd, const Eigen::MatrixXd& gqdd) {
  const int n = s_.n, nh = s_.harmonics;
  FourierTrajectory gradient = ZeroFourierTrajectory(n, nh, t.fundamental);
  gradient.q0 = gq.colwise().sum().transpose();
  for (int l = 0; l < nh; ++l) {
    const double wl = s_.omega * (l + 1);
    const Eigen::VectorXd sn = s_.sin_table.col(l), cs = s_.cos_table.col(l);
    gradient.a.col(l) = gq.transpose() * sn / wl + gqd.transpose() * cs - gqdd.transpose() * sn * wl;
    gradient.b.col(l) = -gq.transpose() * cs / wl + gqd.transpose() * sn + gqdd.transpose() * cs * wl;
  }
  return gradient;
}

// log(cond(W S^-1)) + mu * (limit penalties) of a trajectory, and where `gradient` is
// given, its derivatives with respect to q0, a and b (in the same shapes). NaN when W
// is rank deficient.
double Objective(const DesignSetup& s_, const FourierTrajectory& t, double mu, FourierTrajectory* gradient) {
  const int n = s_.n, r = s_.base.rank(), m = s_.samples;
  std::vector<JointMotion> motion(static_cast<std::size_t>(m));
  const Eigen::VectorXd inv_scale = s_.scales.cwiseInverse();
  const Eigen::MatrixXd w = SampleDesignMotion(s_, t, &motion);
  const Eigen::MatrixXd gram = w.transpose() * w;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(gram);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (eig.info() != Eigen::Success) return nan;
  const double lmin = eig.eigenvalues()[0], lmax = eig.eigenvalues()[r - 1];
  if (!(lmin > 1e-300) || !std::isfinite(lmax)) return nan;
  double f = 0.5 * (std::log(lmax) - std::log(lmin));

  // Per sample: the cost's sensitivity to the unscaled regressor (h, n x r; from
  // d log(cond)/dW = W (v_max v_max'/l_max - v_min v_min'/l_min) and the torque
  // penalty) and to q, qd, qdd directly (the limit penalties).
  Eigen::MatrixXd gq = Eigen::MatrixXd::Zero(m, n), gqd = gq, gqdd = gq;
  std::vector<Eigen::MatrixXd> h(static_cast<std::size_t>(m));
  Eigen::MatrixXd p;
  if (gradient) {
    const Eigen::VectorXd vmin = eig.eigenvectors().col(0), vmax = eig.eigenvectors().col(r - 1);
    p = vmax * vmax.transpose() / lmax - vmin * vmin.transpose() / lmin;
  }
  const ExcitationLimits& lim = s_.penalty;
  for (int k = 0; k < m; ++k) {
    const JointMotion& mo = motion[static_cast<std::size_t>(k)];
    for (int i = 0; i < n; ++i) {
      const double range = lim.upper[i] - lim.lower[i];
      gq(k, i) = Penalty(mo.q[i], lim.lower[i], lim.upper[i], range, mu, &f);
      gqd(k, i) = Penalty(mo.qd[i], -lim.velocity[i], lim.velocity[i], lim.velocity[i], mu, &f);
      gqdd(k, i) = Penalty(mo.qdd[i], -lim.acceleration[i], lim.acceleration[i], lim.acceleration[i], mu, &f);
    }
    Eigen::MatrixXd hk;
    if (gradient) hk = w.middleRows(k * n, n) * p * inv_scale.asDiagonal();
    if (s_.torque_constrained) {
      const Eigen::VectorXd tau = (w.middleRows(k * n, n) * s_.scales.asDiagonal()) * s_.beta;
      Eigen::VectorXd dtau(n);
      for (int i = 0; i < n; ++i) dtau[i] = Penalty(tau[i], -lim.torque[i], lim.torque[i], lim.torque[i], mu, &f);
      if (gradient && dtau.any()) hk += dtau * s_.beta.transpose();
    }
    if (gradient) h[static_cast<std::size_t>(k)] = std::move(hk);
  }
  if (!gradient) return f;

  AddRegressorSensitivity(s_, motion, h, &gq, &gqd, &gqdd);
  *gradient = FourierGradient(s_, t, gq, gqd, gqdd);
  return f;
}

// The objective over the free variables x (q0 and the harmonics not fixed by the rest
// conditions, joint by joint), for Ceres.
class DesignCriterion : public ceres::FirstOrderFunction {
 public:
  DesignCriterion(const DesignSetup& setup, double mu) : s_(setup), mu_(mu) {}
  int NumParameters() const override { return s_.NumParameters(); }

  bool Evaluate(const double* x, double* cost, double* gradient) const override {
    FourierTrajectory g;
    const double f = Objective(s_, s_.ToTrajectory(x), mu_, gradient ? &g : nullptr);
    if (!std::isfinite(f)) return false;
    *cost = f;
    if (!gradient) return true;
    const int nh = s_.harmonics, free = nh - s_.first_free;
    for (int i = 0; i < s_.n; ++i) {
      double* gi = gradient + i * s_.PerJoint();
      gi[0] = g.q0[i];
      for (int l = s_.first_free; l < nh; ++l) {
        double ga = g.a(i, l), gb = g.b(i, l);
        if (s_.first_free == 1) {  // a_1 = -sum a_l, b_1 = -sum l b_l
          ga -= g.a(i, 0);
          gb -= (l + 1) * g.b(i, 0);
        }
        gi[1 + (l - s_.first_free)] = ga;
        gi[1 + free + (l - s_.first_free)] = gb;
      }
    }
    return true;
  }

 private:
  const DesignSetup& s_;
  double mu_;
};

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

double ConditionOf(const Eigen::MatrixXd& w) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(w);
  const Eigen::VectorXd s = svd.singularValues();
  return s[s.size() - 1] > 0 ? s[0] / s[s.size() - 1] : kInf;
}

std::uint64_t StartSeed(std::uint64_t seed, int start) { return seed * 1000003ULL + static_cast<std::uint64_t>(start); }

DesignSetup MakeSetup(const ArmModel& model, const ExcitationOptions& options) {
  DesignSetup s;
  s.model = &model;
  s.base = FindBaseParameters(model);
  s.limits = ResolveExcitationLimits(model, options);
  s.penalty = s.limits;
  for (int i = 0; i < model.dof(); ++i) {
    const double shrink = kPenaltyTightening * (s.limits.upper[i] - s.limits.lower[i]) / 2;
    s.penalty.lower[i] += shrink;
    s.penalty.upper[i] -= shrink;
  }
  s.penalty.velocity *= 1 - kPenaltyTightening;
  s.penalty.acceleration *= 1 - kPenaltyTightening;
  s.penalty.torque *= 1 - kPenaltyTightening;
  s.scales = ExcitationColumnScales(model, s.base, s.limits);
  s.beta = s.base.from_standard * StandardParameters(model);
  s.coulomb = CoulombColumns(model, s.base);
  s.torque_constrained = (s.limits.torque.array() < kInf).any();
  s.n = model.dof();
  s.harmonics = options.harmonics;
  s.samples = options.samples_per_period;
  s.first_free = options.start_at_rest ? 1 : 0;
  s.fundamental = options.fundamental;
  s.omega = 2 * kPi * options.fundamental;
  s.smoothing = options.coulomb_smoothing;
  s.sin_table.resize(s.samples, s.harmonics);
  s.cos_table.resize(s.samples, s.harmonics);
  for (int k = 0; k < s.samples; ++k) {
    const double t = k / (options.fundamental * s.samples);
    for (int l = 0; l < s.harmonics; ++l) {
      s.sin_table(k, l) = std::sin(s.omega * (l + 1) * t);
      s.cos_table(k, l) = std::cos(s.omega * (l + 1) * t);
    }
  }
  return s;
}

}  // namespace

bool ExcitationOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& what) {
    if (why) *why = what;
    return false;
  };
  if (harmonics < 1) return fail("harmonics must be at least 1, got " + std::to_string(harmonics));
  if (start_at_rest && harmonics < 2)
    return fail("starting at rest needs at least 2 harmonics (the first one is fixed by the rest conditions)");
  if (!(fundamental >= 1e-3 && fundamental <= 100))
    return fail("fundamental must be 0.001 to 100 Hz (a period of 1000 s to 10 ms), got " + PrintfNumber("%g", fundamental));
  if (!(check_sample_time >= 0 && check_sample_time * fundamental <= 0.01))
    return fail("check_sample_time must give at least 100 samples per period, got " + PrintfNumber("%g", check_sample_time) +
                " s at " + PrintfNumber("%g", fundamental) + " Hz");
  if (samples_per_period < 2 * harmonics + 2)
    return fail("samples_per_period must be at least 2 harmonics + 2 = " + std::to_string(2 * harmonics + 2) +
                ", got " + std::to_string(samples_per_period));
  if (!(position_margin >= 0)) return fail("position_margin must not be negative");
  for (double a : acceleration_limits)
    if (!(a > 0 && a <= 1e6)) return fail("acceleration limits must be positive and at most 1e6, got " + PrintfNumber("%g", a));
  if (!(torque_fraction >= 0) || torque_fraction > 1) return fail("torque_fraction must be in [0, 1]");
  if (starts < 1) return fail("starts must be at least 1");
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
  if (penalty_rounds < 1) return fail("penalty_rounds must be at least 1");
  if (!(coulomb_smoothing > 0)) return fail("coulomb_smoothing must be positive");
  if (threads < 1) return fail("threads must be at least 1");
  return true;
}

bool ExcitationJointMargins::feasible() const {
  return position_margin() >= 0 && velocity_peak <= velocity_limit && acceleration_peak <= acceleration_limit &&
         torque_peak <= torque_limit;
}

ExcitationLimits ResolveExcitationLimits(const ArmModel& model, const ExcitationOptions& options) {
  const int n = model.dof();
  if (!options.acceleration_limits.empty() && static_cast<int>(options.acceleration_limits.size()) != n)
    throw InputError("acceleration limits: expected " + std::to_string(n) + " values (one per joint of '" +
                     model.name + "'), got " + std::to_string(options.acceleration_limits.size()));
  ExcitationLimits l;
  l.lower.resize(n);
  l.upper.resize(n);
  l.velocity.resize(n);
  l.acceleration.resize(n);
  l.torque.resize(n);
  for (int i = 0; i < n; ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    const bool unlimited = j.lower <= -1e8 && j.upper >= 1e8;
    l.lower[i] = (unlimited ? -kPi : j.lower) + options.position_margin;
    l.upper[i] = (unlimited ? kPi : j.upper) - options.position_margin;
    if (!(l.lower[i] < l.upper[i]))
      throw InputError("joint '" + j.name + "': a position margin of " + std::to_string(options.position_margin) +
                       " leaves no room between its limits");
    l.velocity[i] = j.velocity_limit > 0 ? j.velocity_limit : kInf;
    l.acceleration[i] = options.acceleration_limits.empty() ? kDefaultAccelerationLimit
                                                            : options.acceleration_limits[static_cast<std::size_t>(i)];
    l.torque[i] = j.effort_limit > 0 && options.torque_fraction > 0 ? options.torque_fraction * j.effort_limit : kInf;
  }
  return l;
}

Eigen::VectorXd ExcitationColumnScales(const ArmModel& model, const BaseParameters& base,
                                       const ExcitationLimits& limits) {
  constexpr int kStates = 2000;
  const int n = model.dof();
  Rng rng = Rng::Derived(20050101, 3);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(base.rank());
  Eigen::VectorXd q(n), qd(n), qdd(n);
  for (int s = 0; s < kStates; ++s) {
    for (int i = 0; i < n; ++i) {
      q[i] = rng.Uniform(limits.lower[i], limits.upper[i]);
      const double v = std::isfinite(limits.velocity[i]) ? limits.velocity[i] : 2.0;
      qd[i] = rng.Uniform(-v, v);
      qdd[i] = rng.Uniform(-limits.acceleration[i], limits.acceleration[i]);
    }
    sum += base.Reduce(Regressor(model, q, qd, qdd)).colwise().squaredNorm().transpose();
  }
  Eigen::VectorXd scales = (sum / (kStates * n)).cwiseSqrt();
  const double largest = scales.maxCoeff();
  for (Eigen::Index c = 0; c < scales.size(); ++c)
    if (!(scales[c] > 1e-12 * largest)) scales[c] = 1;
  return scales;
}

Eigen::MatrixXd StackedBaseRegressor(const ArmModel& model, const BaseParameters& base,
                                     const FourierTrajectory& trajectory, int samples) {
  const int n = model.dof();
  Eigen::MatrixXd w(samples * n, base.rank());
  for (int k = 0; k < samples; ++k) {
    const JointMotion m = EvaluateFourier(trajectory, k * trajectory.period() / samples);
    w.middleRows(k * n, n) = base.Reduce(Regressor(model, m.q, m.qd, m.qdd));
  }
  return w;
}

double ExcitationCondition(const ArmModel& model, const BaseParameters& base, const Eigen::VectorXd& scales,
                           const FourierTrajectory& trajectory, int samples) {
  return ConditionOf(StackedBaseRegressor(model, base, trajectory, samples) * scales.cwiseInverse().asDiagonal());
}

std::vector<ExcitationJointMargins> CheckExcitationLimits(const ArmModel& model, const FourierTrajectory& trajectory,
                                                          const ExcitationLimits& limits, double sample_time) {
  const int n = model.dof();
  std::vector<ExcitationJointMargins> out(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    ExcitationJointMargins& j = out[static_cast<std::size_t>(i)];
    j.q_min = kInf;
    j.q_max = -kInf;
    j.lower = limits.lower[i];
    j.upper = limits.upper[i];
    j.velocity_limit = limits.velocity[i];
    j.acceleration_limit = limits.acceleration[i];
    j.torque_limit = limits.torque[i];
  }
  const long samples = std::lround(trajectory.period() / sample_time);
  for (long k = 0; k < samples; ++k) {
    const JointMotion m = EvaluateFourier(trajectory, static_cast<double>(k) * sample_time);
    const Eigen::VectorXd tau = InverseDynamics(model, m.q, m.qd, m.qdd);
    for (int i = 0; i < n; ++i) {
      ExcitationJointMargins& j = out[static_cast<std::size_t>(i)];
      j.q_min = std::min(j.q_min, m.q[i]);
      j.q_max = std::max(j.q_max, m.q[i]);
      j.velocity_peak = std::max(j.velocity_peak, std::abs(m.qd[i]));
      j.acceleration_peak = std::max(j.acceleration_peak, std::abs(m.qdd[i]));
      j.torque_peak = std::max(j.torque_peak, std::abs(tau[i]));
    }
  }
  return out;
}

FourierTrajectory RandomFeasibleExcitation(const ArmModel& model, const ExcitationOptions& options,
                                           std::uint64_t seed) {
  std::string invalid;
  if (!options.IsValid(&invalid)) throw InputError("excitation options: " + invalid);
  const ExcitationLimits limits = ResolveExcitationLimits(model, options);
  const int n = model.dof(), nh = options.harmonics;
  Rng rng = Rng::Derived(seed, 1001);
  FourierTrajectory t = ZeroFourierTrajectory(n, nh, options.fundamental);
  for (int i = 0; i < n; ++i) {
    const double mid = 0.5 * (limits.lower[i] + limits.upper[i]), half = 0.5 * (limits.upper[i] - limits.lower[i]);
    t.q0[i] = mid + rng.Uniform(-0.3, 0.3) * half;
    for (int l = 0; l < nh; ++l) {
      t.a(i, l) = rng.Uniform(-1, 1) / (l + 1);
      t.b(i, l) = rng.Uniform(-1, 1) / (l + 1);
    }
    if (options.start_at_rest) {
      double sa = 0, sb = 0;
      for (int l = 1; l < nh; ++l) {
        sa += t.a(i, l);
        sb += (l + 1) * t.b(i, l);
      }
      t.a(i, 0) = -sa;
      t.b(i, 0) = -sb;
    }
  }
  for (const ArmJoint& j : model.joints) t.joint_names.push_back(j.name);
  t.model = model.name;
  const double fill = rng.Uniform(0.5, 0.9);
  const double largest = LargestFeasibleScale(model, t, limits, t.period() / options.samples_per_period,
                                              options.samples_per_period, 1e3);
  if (!(largest > 0))
    throw InputError("model '" + model.name + "': the nominal torque at rest exceeds " +
                     PrintfNumber("%g", options.torque_fraction) + " of an effort limit at the start q0");
  return Scaled(t, largest * fill);
}

namespace {

// One start of the design: a random feasible excitation optimised by L-BFGS under growing limit penalties, shrunk
// where it still touches a limit between the samples; its record goes into `st`.
FourierTrajectory RunExcitationStart(const ArmModel& model, const ExcitationOptions& options, const DesignSetup& s,
                                     double check_dt, int check_samples, int k, ExcitationStart* st) {
  const FourierTrajectory initial = RandomFeasibleExcitation(model, options, StartSeed(options.seed, k));
  st->initial_condition = ExcitationCondition(model, s.base, s.scales, initial, s.samples);
  Eigen::VectorXd x = s.FromTrajectory(initial);
  ceres::GradientProblemSolver::Options solver;
  solver.line_search_direction_type = ceres::LBFGS;
  solver.max_num_iterations = options.max_iterations;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  solver.function_tolerance = 1e-9;
  solver.gradient_tolerance = 1e-9;
  solver.parameter_tolerance = 1e-10;
  double mu = 10;
  for (int round = 0; round < options.penalty_rounds; ++round, mu *= 10) {
    ceres::GradientProblem problem(new DesignCriterion(s, mu));
    ceres::GradientProblemSolver::Summary result;
    ceres::Solve(solver, problem, x.data(), &result);
    st->iterations += static_cast<int>(result.iterations.size()) - 1;
  }
  FourierTrajectory t = s.ToTrajectory(x.data());
  t.joint_names = initial.joint_names;
  t.model = model.name;
  // The penalties leave the optimum a little inside the limits; where it still
  // touches one between the samples, shrink the oscillation until it passes.
  if (!Feasible(model, t, s.limits, check_dt, check_samples)) {
    st->shrink = LargestFeasibleScale(model, t, s.limits, check_dt, check_samples, 1.0);
    t = Scaled(t, st->shrink);
  }
  st->feasible = st->shrink > 0;
  st->final_condition = ExcitationCondition(model, s.base, s.scales, t, s.samples);
  return t;
}

// The feasible start with the lowest final condition number; throws when no start ended inside the limits.
int BestExcitationStart(const std::vector<ExcitationStart>& starts) {
  int best = -1;
  for (int k = 0; k < static_cast<int>(starts.size()); ++k) {
    const ExcitationStart& st = starts[static_cast<std::size_t>(k)];
    if (st.feasible && (best < 0 || st.final_condition < starts[static_cast<std::size_t>(best)].final_condition))
      best = k;
  }
  if (best < 0) throw CheckFailed("excitation design: no start ended inside the limits");
  return best;
}

// The design's summary: every start, the best one's condition numbers and its margins to the limits.
ExcitationSummary SummariseExcitation(const ArmModel& model, const ExcitationOptions& options, const DesignSetup& s,
                                      const std::vector<ExcitationStart>& starts, int best,
                                      const FourierTrajectory& design, double check_dt) {
  ExcitationSummary out;
  out.model = model.name;
  out.harmonics = options.harmonics;
  out.fundamental = options.fundamental;
  out.parameters = s.base.rank();
  out.best_start = best;
  out.starts = starts;
  out.start_condition = starts[static_cast<std::size_t>(best)].initial_condition;
  out.final_condition = starts[static_cast<std::size_t>(best)].final_condition;
  std::vector<double> initial;
  for (const ExcitationStart& st : starts) {
    initial.push_back(st.initial_condition);
    out.iterations += st.iterations;
  }
  out.random_condition_median = Median(initial);
  const Eigen::MatrixXd w = StackedBaseRegressor(model, s.base, design, s.samples);
  out.final_condition_unscaled = ConditionOf(w);
  out.final_condition_equilibrated = ConditionOf(w * w.colwise().norm().cwiseInverse().asDiagonal());
  out.margins = CheckExcitationLimits(model, design, s.limits, check_dt);
  return out;
}

}  // namespace

FourierTrajectory DesignExcitation(const ArmModel& model, const ExcitationOptions& options, ExcitationSummary* summary,
                                   const ExcitationProgress& progress) {
  const auto started = std::chrono::steady_clock::now();
  std::string invalid;
  if (!options.IsValid(&invalid)) throw InputError("excitation options: " + invalid);
  const DesignSetup s = MakeSetup(model, options);
  const double check_dt = options.check_sample_time > 0 ? options.check_sample_time : model.sample_time;
  const int check_samples = static_cast<int>(std::lround(1.0 / (options.fundamental * check_dt)));

  std::vector<ExcitationStart> starts(static_cast<std::size_t>(options.starts));
  std::vector<FourierTrajectory> finals(static_cast<std::size_t>(options.starts));
  std::atomic<int> next{0};
  std::mutex mutex;
  int done = 0;
  double best_so_far = kInf;
  std::exception_ptr failure;

  auto worker = [&]() {
    for (int k = next++; k < options.starts; k = next++) {
      try {
        finals[static_cast<std::size_t>(k)] =
            RunExcitationStart(model, options, s, check_dt, check_samples, k, &starts[static_cast<std::size_t>(k)]);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!failure) failure = std::current_exception();
        return;
      }
      std::lock_guard<std::mutex> lock(mutex);
      ++done;
      const ExcitationStart& st = starts[static_cast<std::size_t>(k)];
      if (st.feasible) best_so_far = std::min(best_so_far, st.final_condition);
      if (progress) progress(done, options.starts, best_so_far);
    }
  };
  const int threads = std::min(options.threads, options.starts);
  if (threads <= 1) {
    worker();
  } else {
    std::vector<std::thread> pool;
    for (int k = 0; k < threads; ++k) pool.emplace_back(worker);
    for (std::thread& th : pool) th.join();
  }
  if (failure) std::rethrow_exception(failure);

  const int best = BestExcitationStart(starts);
  const FourierTrajectory& design = finals[static_cast<std::size_t>(best)];
  if (summary) {
    *summary = SummariseExcitation(model, options, s, starts, best, design, check_dt);
    summary->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  }
  return design;
}

double EvaluateExcitationObjective(const ArmModel& model, const ExcitationOptions& options,
                                  const FourierTrajectory& trajectory, double penalty_weight,
                                  FourierTrajectory* gradient) {
  std::string invalid;
  if (!options.IsValid(&invalid)) throw InputError("excitation options: " + invalid);
  CheckTrajectoryFitsModel(trajectory, model, "excitation objective");
  if (trajectory.harmonics() != options.harmonics || trajectory.fundamental != options.fundamental)
    throw InputError("excitation objective: the trajectory's harmonics and fundamental differ from the options'");
  const DesignSetup s = MakeSetup(model, options);
  return Objective(s, trajectory, penalty_weight, gradient);
}

std::string ExcitationSummary::BriefReport() const {
  std::ostringstream s;
  s << "condition number " << PrintfNumber("%.4g", start_condition) << " -> " << PrintfNumber("%.4g", final_condition)
    << " (random feasible median " << PrintfNumber("%.4g", random_condition_median) << "), " << starts.size()
    << " starts, " << iterations << " iterations, " << PrintfNumber("%.1f", seconds) << " s";
  return s.str();
}

std::string ExcitationSummary::FullReport() const {
  std::ostringstream s;
  s << "Excitation design for " << model << ": " << harmonics << " harmonics of " << PrintfNumber("%g", fundamental)
    << " Hz, " << parameters << " base parameters\n";
  s << "condition number of the scaled stacked base regressor (the criterion):\n";
  s << "  start   random feasible   optimised   iterations   shrink\n";
  for (std::size_t k = 0; k < starts.size(); ++k) {
    const ExcitationStart& st = starts[k];
    char line[160];
    std::snprintf(line, sizeof line, "  %5zu   %15.4g   %9.4g   %10d   %6.3f%s%s\n", k, st.initial_condition,
                  st.final_condition, st.iterations, st.shrink, st.feasible ? "" : "  (infeasible)",
                  static_cast<int>(k) == best_start ? "  <- best" : "");
    s << line;
  }
  s << "design: scaled " << PrintfNumber("%.4g", final_condition) << ", unscaled " << PrintfNumber("%.4g", final_condition_unscaled)
    << ", unit-norm columns " << PrintfNumber("%.4g", final_condition_equilibrated) << "\n";
  s << "limits (peak / limit) per joint:\n";
  s << "  joint   q range [rad]        margin [rad]   |qd| [rad/s]     |qdd| [rad/s^2]   |tau| [N m]\n";
  for (std::size_t i = 0; i < margins.size(); ++i) {
    const ExcitationJointMargins& m = margins[i];
    auto lim = [](double v) { return std::isfinite(v) ? PrintfNumber("%.3g", v) : std::string("-"); };
    char line[200];
    std::snprintf(line, sizeof line, "  %5zu   [%6.3f, %6.3f]   %12.4f   %5.2f / %-6s   %6.2f / %-6s   %6.2f / %-6s\n",
                  i + 1, m.q_min, m.q_max, m.position_margin(), m.velocity_peak, lim(m.velocity_limit).c_str(),
                  m.acceleration_peak, lim(m.acceleration_limit).c_str(), m.torque_peak, lim(m.torque_limit).c_str());
    s << line;
  }
  s << BriefReport() << "\n";
  return s.str();
}

}  // namespace twinsim

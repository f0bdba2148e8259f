#include "sim/newtonian_arm_backend.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/error.h"
#include "robots/arm/arm_dynamics.h"

namespace twinsim {
namespace {

// joint_flexibility: the physics step keeps the spring's phase error per step and its
// explicit damping well inside the stable range (docs/arm_backends.md).
constexpr double kMaxSpringPhasePerStep = 0.1;    // rad: h sqrt(k / J_eff)
constexpr double kMaxSpringDampingPerStep = 0.5;  // h d / J_eff
// The trapezoidal rule is stable for any step; its resonance comes out at
// 2 atan(h w / 2) / h, low by (h w)^2 / 12: within 1 % at h w = 0.34.
constexpr double kMaxSpringPhasePerStepTrapezoidal = 0.34;  // rad
// Pre-sliding bristles: their spring against the link resolved this finely, within this many
// physics steps per sample.
constexpr double kMaxBristlePhasePerStep = 0.5;  // rad: h sqrt(sigma0 / J_l)
constexpr int kMaxBristleSubsteps = 64;
// The velocity-level friction solve: projected Gauss-Seidel sweeps over the joints.
constexpr int kFrictionSweeps = 50;
constexpr double kFrictionTolerance = 1e-13;  // relative change of a sweep that ends it

// The friction torque of one joint for one step: `v` is the velocity the joint would
// reach at the end of the step without its own friction, `w` (s/(kg m^2)) how much a
// unit torque over the step changes it, `qd` its velocity at the start. The joint
// sticks when its break-away level can stop it within the step; else it slides with
// the Coulomb/Stribeck level of its present speed and viscous friction on the mean of
// its start and end velocities (trapezoidal: second order, and stable for any b); `q`
// its position at the start (position_friction's level).
// `inv_w` = 1 / w and `inv_damping` = 1 / (1 + w b / 2), b the joint's viscous
// coefficient: fixed over a step's sweeps, so divided once.
double JointFriction(const ArmJoint& nominal, const JointEffects& e, double v, double w, double inv_w,
                     double inv_damping, double q, double qd) {
  const double viscous = nominal.viscous + e.viscous;
  for (const int dir : {+1, -1}) {
    if (dir * v <= w * e.SlidingLevel(nominal.coulomb, q, 0, dir)) continue;
    const double level = dir * e.SlidingLevel(nominal.coulomb, q, std::max(dir * qd, 0.0), dir);
    // Sliding: f = level + b (qd + v_end) / 2 with v_end = v - w f.
    const double f = (level + 0.5 * viscous * (v + qd)) * inv_damping;
    // A damping so strong that the trapezoid would overshoot zero stops the joint.
    if (dir * (v - w * f) < 0) return v * inv_w;
    return f;
  }
  return v * inv_w;  // sticks: exactly the torque that stops it
}

// M^-1 of a symmetric positive definite M (n x n) by Cholesky, M = L L', into `inverse`,
// with `factor` as work space for L^-1: (L^-1)' L^-1. Plain loops: at an arm's size
// (n <= 7) Eigen's blocked triangular solves cost several times the arithmetic
// (docs/benchmarks.md has the profile that chose them).
void InverseByCholesky(const Eigen::MatrixXd& m, Eigen::MatrixXd* factor, Eigen::MatrixXd* inverse) {
  const Eigen::Index n = m.rows();
  Eigen::MatrixXd& l = *factor;
  l.resize(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    double d = m(j, j);
    for (Eigen::Index k = 0; k < j; ++k) d -= l(j, k) * l(j, k);
    l(j, j) = std::sqrt(d);
    for (Eigen::Index i = j + 1; i < n; ++i) {
      double s = m(i, j);
      for (Eigen::Index k = 0; k < j; ++k) s -= l(i, k) * l(j, k);
      l(i, j) = s / l(j, j);
    }
  }
  // L^-1 in place (lower triangular), column by column from the diagonal down.
  for (Eigen::Index j = 0; j < n; ++j) {
    l(j, j) = 1 / l(j, j);
    for (Eigen::Index i = j + 1; i < n; ++i) {
      double s = 0;
      for (Eigen::Index k = j; k < i; ++k) s -= l(i, k) * l(k, j);
      l(i, j) = s / l(i, i);
    }
  }
  // M^-1 = (L^-1)' L^-1, symmetric.
  inverse->resize(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    for (Eigen::Index i = j; i < n; ++i) {
      double s = 0;
      for (Eigen::Index k = i; k < n; ++k) s += l(k, i) * l(k, j);
      (*inverse)(i, j) = (*inverse)(j, i) = s;
    }
  }
}

}  // namespace

NewtonianArmBackend::NewtonianArmBackend(const ArmModel& model, std::unique_ptr<ArmEngine> engine,
                                         int physics_substeps)
    : model_(ArmPlantModel(model)), engine_(std::move(engine)) {
  if (physics_substeps < 0 || physics_substeps > 100000) {
    throw InputError("arm backend options: physics_substeps must be in [0, 100000] (0 = automatic)");
  }
  if (!engine_ || engine_->dof() != model_.dof()) {
    throw std::invalid_argument("arm backend: the engine was built for another arm");
  }
  if (const std::string problems = model_.Validate(); !problems.empty()) {
    throw InputError("arm backend: model '" + model_.name + "': " + problems);
  }
  const int n = model_.dof();
  const double ts = model_.sample_time;
  // The automatic physics step: fine enough for the stiffest flexible joint, whose
  // link side is taken at q = 0 with the other joints free, the lightest it gets:
  // J_l = 1 / (M^-1)_jj, J_eff = J_m J_l / (J_m + J_l).
  int substeps = 1;
  const Eigen::MatrixXd mobility = MassMatrix(model_, Eigen::VectorXd::Zero(n)).inverse();
  for (int j = 0; j < n; ++j) {
    const JointEffects e = model_.effects.joint(j);
    effects_.push_back(e);
    const ArmJoint& nominal = model_.joints[static_cast<std::size_t>(j)];
    if (e.friction() || nominal.viscous > 0 || nominal.coulomb > 0) friction_joints_.push_back(j);
    if (e.torque_profile.on()) position_torque_joints_.push_back(j);
    if (e.presliding()) {
      presliding_joints_.push_back(j);
      // The bristles' spring against the link: resolved at h sqrt(sigma0 / J_l) <= 0.5
      // up to kMaxBristleSubsteps; stiffer bristles are stable (the step is implicit in
      // them) and act as sticking.
      const double omega = std::sqrt(e.bristle_stiffness * mobility(j, j));
      substeps = std::max(substeps, std::min(kMaxBristleSubsteps,
                                             static_cast<int>(std::ceil(ts * omega / kMaxBristlePhasePerStep))));
    }
    if (e.flexible()) {
      flexible_ = true;
      const double link = 1 / mobility(j, j);
      const double j_eff = e.motor_inertia * link / (e.motor_inertia + link);
      const double omega = std::sqrt(e.stiffness / j_eff);
      if (model_.flexibility_integrator == FlexibilityIntegrator::kTrapezoidal) {
        trapezoidal_joints_.push_back(j);
        substeps = std::max(substeps, static_cast<int>(std::ceil(ts * omega / kMaxSpringPhasePerStepTrapezoidal)));
        continue;
      }
      substeps = std::max(substeps, static_cast<int>(std::ceil(ts * omega / kMaxSpringPhasePerStep)));
      if (e.flex_damping > 0) {
        substeps = std::max(substeps,
                            static_cast<int>(std::ceil(ts * e.flex_damping / j_eff / kMaxSpringDampingPerStep)));
      }
    }
  }
  substeps_ = physics_substeps > 0 ? physics_substeps : substeps;
  const double h = ts / substeps_;
  for (int j = 0; j < n; ++j) {
    double steps = effects_[static_cast<std::size_t>(j)].time_delay / h;
    // A delay that is a whole number of steps up to rounding is taken as exactly that.
    if (std::abs(steps - std::round(steps)) < 1e-9 * std::max(1.0, steps)) steps = std::round(steps);
    delay_steps_.push_back(steps);
    max_delay_steps_ = std::max(max_delay_steps_, steps);
  }
  scratch_.bristle_steps.assign(static_cast<std::size_t>(n), ArmBristleStep{});
  scratch_.bristle_torque = Eigen::VectorXd::Zero(n);
  scratch_.bristle_gain = Eigen::VectorXd::Zero(n);
  scratch_.slip_levels.assign(static_cast<std::size_t>(n), ArmSlipLevels{});
  scratch_.slid_deflection = Eigen::VectorXd::Zero(n);
  scratch_.slid.assign(static_cast<std::size_t>(n), false);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  Reset(zero, zero, zero);
}

void NewtonianArmBackend::Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                const Eigen::VectorXd& tau_before) {
  if (tau_before.size() != model_.dof() || !tau_before.allFinite()) {
    throw std::invalid_argument("arm backend: Reset needs " + std::to_string(model_.dof()) +
                                " finite torques before t = 0");
  }
  engine_->Reset(q, qd);
  state_ = ArmBackendState{};
  state_.held_before = tau_before;
  state_.motor_q = q;
  state_.motor_qd = qd;
  state_.bristle = Eigen::VectorXd::Zero(model_.dof());
  if (presliding_joints_.empty()) return;
  // The bristles start carrying the dry friction the joint's torque balance asks for,
  // within the friction level: tau - bias - viscous qd, clipped to +-g(qd). A sliding
  // joint's (at a constant speed) is its steady deflection g sign(qd) / sigma0; a held
  // one's what holds it. Starting them unloaded would let every restart slip by up to
  // g / sigma0 before they carry it.
  MassMatrixAndBias(model_, q, qd, &scratch_.mass, &scratch_.bias);
  for (int j : presliding_joints_) {
    const auto k = static_cast<std::size_t>(j);
    const JointEffects& e = effects_[k];
    const double g = ArmDryFrictionLevel(model_, j, q[j], qd[j]);
    const double carried = tau_before[j] + e.torque_offset + e.PositionTorque(q[j]) - scratch_.bias[j] -
                           (model_.joints[k].viscous + e.viscous) * qd[j];
    state_.bristle[j] = std::clamp(carried, -g, g) / e.bristle_stiffness;
  }
}

void NewtonianArmBackend::DriveTorques(std::int64_t step, Eigen::VectorXd* drive) const {
  const auto& arrived = state_.arrived;
  for (int j = 0; j < model_.dof(); ++j) {
    const double d = delay_steps_[static_cast<std::size_t>(j)];
    double u = 0;
    if (d == 0) {
      u = arrived.back().second[j];
    } else {
      // The mean over this step of the arrived command signal shifted by the delay:
      // the window [step - d, step + 1 - d) in physics steps. Piecewise constant, so the
      // joint receives exactly the impulse it would with the delay resolved finely.
      const double a = static_cast<double>(step) - d, b = a + 1;
      double sum = 0;
      double start = -std::numeric_limits<double>::infinity();
      double value = state_.held_before[j];
      for (const auto& [at, command] : arrived) {
        const double end = static_cast<double>(at);
        sum += std::max(0.0, std::min(b, end) - std::max(a, start)) * value;
        start = end;
        value = command[j];
      }
      sum += std::max(0.0, b - std::max(a, start)) * value;
      u = sum;
    }
    const JointEffects& e = effects_[static_cast<std::size_t>(j)];
    if (e.saturation > 0) u = std::clamp(u, -e.saturation, e.saturation);
    (*drive)[j] = u + e.torque_offset;
  }
}

void NewtonianArmBackend::PrepareBristles(int j, double q, double qd, double h) {
  // The bristles end the step at z = base + slope v_end; their torque is sigma0 z plus
  // sigma1 times the step's mean z', and viscous friction is trapezoidal as elsewhere:
  // f = A + B v_end, linear in the joint's end velocity like the other unknowns.
  const auto k = static_cast<std::size_t>(j);
  const JointEffects& e = effects_[k];
  const double z0 = state_.bristle[j];
  const ArmBristleStep step = ArmBristleStepFrom(model_, j, q, z0, qd, h);
  scratch_.bristle_steps[k] = step;
  const double viscous = model_.joints[k].viscous + e.viscous;
  scratch_.bristle_torque[j] =
      e.bristle_stiffness * step.base + e.bristle_damping * (step.base - z0) / h + 0.5 * viscous * qd;
  scratch_.bristle_gain[j] = (e.bristle_stiffness + e.bristle_damping / h) * step.slope + 0.5 * viscous;
  if (e.bristle_slip) {
    // The dry levels the element slips at, either way (the start's speed).
    scratch_.slip_levels[k] = ArmMaxwellSlipLevels(model_, j, q, qd);
  }
}

double NewtonianArmBackend::BristleFriction(int j, double v, double w, double qd, double h) {
  const auto k = static_cast<std::size_t>(j);
  const JointEffects& e = effects_[k];
  Scratch& s = scratch_;
  const double f = (s.bristle_torque[j] + s.bristle_gain[j] * v) / (1 + w * s.bristle_gain[j]);
  s.slid[k] = false;
  if (!e.bristle_slip) return f;
  // A Maxwell-slip element: elastic while its force (damping included) stays within the
  // dry level; beyond it, it slips carrying exactly that level, and its deflection is
  // what makes sigma0 z + sigma1 (z - z0) / h equal it.
  const double viscous = model_.joints[k].viscous + e.viscous;
  const double dry = f - 0.5 * viscous * (qd + v - w * f);
  const double level = s.slip_levels[k].For(dry);
  if (std::abs(dry) <= std::abs(level)) return f;
  s.slid[k] = true;
  s.slid_deflection[j] = ArmMaxwellSlipDeflection(e, level, state_.bristle[j], h);
  return (level + 0.5 * viscous * (qd + v)) / (1 + 0.5 * w * viscous);
}

bool NewtonianArmBackend::SolveJointTorques(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                            const Eigen::VectorXd& tau, const Eigen::VectorXd& drive, double h,
                                            Eigen::VectorXd* friction, Eigen::VectorXd* spring) {
  const int n = model_.dof();
  friction->setZero(n);
  spring->setZero(n);
  const std::size_t unknowns = friction_joints_.size() + trapezoidal_joints_.size();
  if (unknowns == 0) return false;
  // Velocities at the end of the step without friction, and how a torque on one joint
  // changes them: h M^-1. M and the bias forces in one pass (MassMatrixAndBias), into
  // scratch kept from step to step: nothing allocated.
  Scratch& w = scratch_;
  MassMatrixAndBias(model_, q, qd, &w.mass, &w.bias);
  InverseByCholesky(w.mass, &w.factor, &w.mobility);
  w.free_end = tau - w.bias;
  w.free_accel.noalias() = w.mobility * w.free_end;
  w.free_end = qd + h * w.free_accel;
  w.response = h * w.mobility;
  const Eigen::VectorXd& free_end = w.free_end;
  const Eigen::MatrixXd& response = w.response;
  const bool springs = !trapezoidal_joints_.empty();
  Eigen::VectorXd& w_inverse = w.w_inverse;
  Eigen::VectorXd& damping_inverse = w.damping_inverse;
  w_inverse.resize(n);
  damping_inverse.resize(n);
  for (int j : friction_joints_) {
    const auto k = static_cast<std::size_t>(j);
    const double viscous = model_.joints[k].viscous + effects_[k].viscous;
    w_inverse[j] = 1 / response(j, j);
    damping_inverse[j] = 1 / (1 + 0.5 * response(j, j) * viscous);
    if (effects_[k].presliding()) PrepareBristles(j, q[j], qd[j], h);
  }
  // Projected Gauss-Seidel: each joint's friction, and each trapezoidal spring's torque,
  // given the others', until they settle.
  for (int sweep = 0; sweep < kFrictionSweeps; ++sweep) {
    double change = 0, size = 0;
    for (int j : trapezoidal_joints_) {
      // The mean spring torque s over the step, the trapezoidal rule on deflection
      // e = thm - q: s = k e + c (e' + e'_end) with c = k h / 4 + d / 2, where the
      // motor ends at thm'_end = thm' + a (u - s), a = h / J_m, and the link at
      // qd_end = r + W_jj s (r: its end velocity under every other torque). Linear in s.
      const JointEffects& e = effects_[static_cast<std::size_t>(j)];
      const double c = 0.25 * e.stiffness * h + 0.5 * e.flex_damping;
      const double a = h / e.motor_inertia;
      const double wjj = response(j, j);
      const double r = free_end[j] + response.row(j).dot(*spring) - response.row(j).dot(*friction) - wjj * (*spring)[j];
      const double s = (e.stiffness * (state_.motor_q[j] - q[j]) +
                        c * (2 * state_.motor_qd[j] - qd[j] + a * drive[j] - r)) /
                       (1 + c * (a + wjj));
      change = std::max(change, std::abs(s - (*spring)[j]));
      size = std::max(size, std::abs(s));
      (*spring)[j] = s;
    }
    for (int j : friction_joints_) {
      const double w = response(j, j);
      double v = free_end[j] - response.row(j).dot(*friction) + w * (*friction)[j];
      if (springs) v += response.row(j).dot(*spring);
      const auto k = static_cast<std::size_t>(j);
      const double f =
          effects_[k].presliding()
              ? BristleFriction(j, v, w, qd[j], h)
              : JointFriction(model_.joints[k], effects_[k], v, w, w_inverse[j], damping_inverse[j], q[j], qd[j]);
      change = std::max(change, std::abs(f - (*friction)[j]));
      size = std::max(size, std::abs(f));
      (*friction)[j] = f;
    }
    if (unknowns == 1 || change <= kFrictionTolerance * (1 + size)) break;
  }
  // The engine's first stage comes from the same M: M^-1 (tau + spring - friction - bias).
  w.start_accel = w.free_accel;
  if (springs) w.start_accel.noalias() += w.mobility * *spring;
  w.start_accel.noalias() -= w.mobility * *friction;
  return true;
}

void NewtonianArmBackend::Step(const Eigen::VectorXd& command, Eigen::VectorXd* applied) {
  const int n = model_.dof();
  // The time_delay history, kept as long as the longest time_delay reaches back. An
  // entry that drops out lends its storage to the next command (Eigen's moves swap
  // buffers), so that the history allocates nothing from step to step.
  const std::int64_t first_step = state_.sample * substeps_;
  auto& arrived = state_.arrived;
  arrived.emplace_back(first_step, std::move(scratch_.delayed));
  arrived.back().second = command;
  const double oldest_needed = static_cast<double>(first_step) - max_delay_steps_;
  while (arrived.size() >= 2 && static_cast<double>(arrived[1].first) <= oldest_needed) {
    state_.held_before.swap(arrived.front().second);
    scratch_.delayed = std::move(arrived.front().second);
    arrived.erase(arrived.begin());
  }

  const double h = model_.sample_time / substeps_;
  Eigen::VectorXd& drive = scratch_.drive;
  Eigen::VectorXd& link = scratch_.link;
  Eigen::VectorXd& friction = scratch_.friction;
  Eigen::VectorXd& spring = scratch_.spring;
  drive.resize(n);
  applied->setZero(n);
  for (int s = 0; s < substeps_; ++s) {
    DriveTorques(first_step + s, &drive);
    *applied += drive / substeps_;
    const Eigen::VectorXd& q = engine_->q();
    const Eigen::VectorXd& qd = engine_->qd();
    link = drive;
    if (flexible_) {
      for (int j = 0; j < n; ++j) {
        const JointEffects& e = effects_[static_cast<std::size_t>(j)];
        if (!e.flexible()) continue;
        // The spring between motor and link carries the drive to the link (trapezoidal:
        // solved below with the friction).
        link[j] = 0;
        if (model_.flexibility_integrator == FlexibilityIntegrator::kTrapezoidal) continue;
        // Explicit: the motor follows by semi-implicit Euler with the spring torque of
        // the step's start.
        const double spring =
            e.stiffness * (state_.motor_q[j] - q[j]) + e.flex_damping * (state_.motor_qd[j] - qd[j]);
        link[j] = spring;
        state_.motor_qd[j] += h * (drive[j] - spring) / e.motor_inertia;
        state_.motor_q[j] += h * state_.motor_qd[j];
      }
    }
    // position_torque acts on the link at its position at the step's start.
    for (int j : position_torque_joints_) link[j] += effects_[static_cast<std::size_t>(j)].PositionTorque(q[j]);
    const bool solved = SolveJointTorques(q, qd, link, drive, h, &friction, &spring);
    link -= friction;
    for (int j : trapezoidal_joints_) {
      // The motor by the trapezoidal rule under the same mean spring torque.
      const JointEffects& e = effects_[static_cast<std::size_t>(j)];
      link[j] += spring[j];
      const double motor_qd = state_.motor_qd[j];
      state_.motor_qd[j] += h * (drive[j] - spring[j]) / e.motor_inertia;
      state_.motor_q[j] += 0.5 * h * (motor_qd + state_.motor_qd[j]);
    }
    if (solved) {
      engine_->StepFromAcceleration(link, h, scratch_.start_accel);
    } else {
      engine_->Step(link, h);
    }
    for (int j : presliding_joints_) {
      const auto k = static_cast<std::size_t>(j);
      state_.bristle[j] =
          scratch_.slid[k] ? scratch_.slid_deflection[j] : scratch_.bristle_steps[k].At(engine_->qd()[j]);
    }
  }
  ++state_.sample;
}

ArmBackendState NewtonianArmBackend::Save() const {
  ArmBackendState s = state_;
  s.engine = engine_->Save();
  return s;
}

void NewtonianArmBackend::Restore(const ArmBackendState& state) {
  const int n = model_.dof();
  if (state.held_before.size() != n || state.motor_q.size() != n || state.motor_qd.size() != n ||
      state.bristle.size() != n) {
    throw std::invalid_argument("arm backend: state of another arm");
  }
  engine_->Restore(state.engine);
  state_ = state;
  state_.engine = {};
}

std::unique_ptr<ArmBackend> MakeNewtonianArmBackend(const std::string& engine, const ArmModel& model,
                                                    int physics_substeps, const ArmEngineOptions& options) {
  return std::make_unique<NewtonianArmBackend>(model, MakeArmEngine(engine, model, options), physics_substeps);
}

}  // namespace twinsim

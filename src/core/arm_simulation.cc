#include "core/arm_simulation.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_effects.h"

namespace twinsim {
namespace {

// joint_flexibility: the physics step keeps the spring's phase error per step and its
// explicit damping well inside the stable range (docs/arm_backends.md).
constexpr double kMaxSpringPhasePerStep = 0.1;    // rad: h sqrt(k / J_eff)
constexpr double kMaxSpringDampingPerStep = 0.5;  // h d / J_eff
// The velocity-level friction solve: projected Gauss-Seidel sweeps over the joints.
constexpr int kFrictionSweeps = 50;
constexpr double kFrictionTolerance = 1e-13;  // relative change of a sweep that ends it

std::string Unit(const ArmJoint& j, bool velocity) {
  const bool revolute = j.type == JointType::kRevolute;
  if (velocity) return revolute ? "rad/s" : "m/s";
  return revolute ? "rad" : "m";
}

std::string JointName(const ArmModel& model, int j) {
  return "joint " + std::to_string(j + 1) + " '" + model.joints[static_cast<std::size_t>(j)].name + "'";
}

// The sliding friction level of a joint moving at `speed` >= 0 in direction `dir` (+1 or
// -1), without viscous friction: nominal Coulomb plus the Coulomb and Stribeck effects.
double SlidingLevel(const ArmJoint& nominal, const JointEffects& e, double speed, int dir) {
  double level = nominal.coulomb + (dir > 0 ? e.coulomb_positive : e.coulomb_negative);
  if (e.stribeck()) {
    const double r = speed / e.stribeck_velocity;
    level += e.stribeck_coulomb + (e.stribeck_static - e.stribeck_coulomb) * std::exp(-r * r);
  }
  return level;
}

// The friction torque of one joint for one step: `v` is the velocity the joint would
// reach at the end of the step without its own friction, `w` (s/(kg m^2)) how much a
// unit torque over the step changes it, `qd` its velocity at the start. The joint
// sticks when its break-away level can stop it within the step; else it slides with
// the Coulomb/Stribeck level of its present speed and viscous friction on the mean of
// its start and end velocities (trapezoidal: second order, and stable for any b).
double JointFriction(const ArmJoint& nominal, const JointEffects& e, double v, double w, double qd) {
  const double viscous = nominal.viscous + e.viscous;
  for (const int dir : {+1, -1}) {
    if (dir * v <= w * SlidingLevel(nominal, e, 0, dir)) continue;
    const double level = dir * SlidingLevel(nominal, e, std::max(dir * qd, 0.0), dir);
    double v_end = (v - w * (level + 0.5 * viscous * qd)) / (1 + 0.5 * w * viscous);
    // A damping so strong that the trapezoid would overshoot zero stops the joint.
    if (dir * v_end < 0) v_end = 0;
    return (v - v_end) / w;
  }
  return v / w;  // sticks: exactly the torque that stops it
}

}  // namespace

bool ArmSimulationOptions::IsValid(std::string* why) const {
  if (physics_substeps < 0 || physics_substeps > 100000) {
    if (why) *why = "physics_substeps must be in [0, 100000] (0 = automatic)";
    return false;
  }
  if (!(max_speed > 0) || !std::isfinite(max_speed)) {
    if (why) *why = "max_speed must be positive";
    return false;
  }
  return true;
}

ArmSimulation::ArmSimulation(const ArmModel& model, std::unique_ptr<ArmBackend> backend,
                             const ArmSimulationOptions& options)
    : model_(ArmPlantModel(model)), backend_(std::move(backend)), options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw InputError("arm simulation options: " + why);
  if (!backend_ || backend_->dof() != model_.dof()) {
    throw std::invalid_argument("arm simulation: the backend was built for another arm");
  }
  if (const std::string problems = model_.Validate(); !problems.empty()) {
    throw std::invalid_argument("arm simulation: model '" + model_.name + "': " + problems);
  }
  const int n = model_.dof();
  const double ts = model_.sample_time;
  // A learned backend has learned the real arm's friction and effects: none are added
  // on top, and it steps whole samples.
  const bool learned = backend_->includes_plant_effects();
  if (learned && options_.physics_substeps > 1) {
    throw InputError("arm simulation options: the " + backend_->name() +
                     " backend steps one whole sample at a time; physics_substeps must be 0 or 1");
  }
  // The automatic physics step: fine enough for the stiffest flexible joint, whose
  // link side is taken at q = 0 with the other joints free, the lightest it gets:
  // J_l = 1 / (M^-1)_jj, J_eff = J_m J_l / (J_m + J_l).
  int substeps = 1;
  const Eigen::MatrixXd mobility = MassMatrix(model_, Eigen::VectorXd::Zero(n)).inverse();
  for (int j = 0; j < n; ++j) {
    const JointEffects e = learned ? JointEffects{} : model_.effects.joint(j);
    effects_.push_back(e);
    const ArmJoint& nominal = model_.joints[static_cast<std::size_t>(j)];
    if (!learned && (e.friction() || nominal.viscous > 0 || nominal.coulomb > 0)) friction_joints_.push_back(j);
    if (e.flexible()) {
      flexible_ = true;
      const double link = 1 / mobility(j, j);
      const double j_eff = e.motor_inertia * link / (e.motor_inertia + link);
      const double omega = std::sqrt(e.stiffness / j_eff);
      substeps = std::max(substeps, static_cast<int>(std::ceil(ts * omega / kMaxSpringPhasePerStep)));
      if (e.flex_damping > 0) {
        substeps = std::max(substeps,
                            static_cast<int>(std::ceil(ts * e.flex_damping / j_eff / kMaxSpringDampingPerStep)));
      }
    }
  }
  substeps_ = options_.physics_substeps > 0 ? options_.physics_substeps : substeps;
  const double h = ts / substeps_;
  for (int j = 0; j < n; ++j) {
    double steps = effects_[static_cast<std::size_t>(j)].time_delay / h;
    // A delay that is a whole number of steps up to rounding is taken as exactly that.
    if (std::abs(steps - std::round(steps)) < 1e-9 * std::max(1.0, steps)) steps = std::round(steps);
    delay_steps_.push_back(steps);
    max_delay_steps_ = std::max(max_delay_steps_, steps);
  }
  Reset(Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n));
}

void ArmSimulation::Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_before) {
  const int n = model_.dof();
  const Eigen::VectorXd held = tau_before.size() == 0 ? Eigen::VectorXd::Zero(n) : tau_before;
  if (held.size() != n || !held.allFinite()) {
    throw std::invalid_argument("arm simulation: Reset needs " + std::to_string(n) + " finite torques before t = 0");
  }
  backend_->Reset(q, qd);
  state_ = ArmSimulationState{};
  state_.commands_in_flight = DelayLine<Eigen::VectorXd>(model_.delay_samples, held);
  state_.held_before = held;
  state_.motor_q = q;
  state_.motor_qd = qd;
}

void ArmSimulation::CheckState() const {
  const Eigen::VectorXd& q = backend_->q();
  const Eigen::VectorXd& qd = backend_->qd();
  for (int j = 0; j < model_.dof(); ++j) {
    const ArmJoint& joint = model_.joints[static_cast<std::size_t>(j)];
    auto fail = [&](const char* what, double value, bool velocity) {
      std::ostringstream msg;
      msg << "arm simulation diverged at t = " << time() << " s (sample " << state_.sample << ") on backend "
          << backend_->name() << ": " << JointName(model_, j) << " " << what << " = " << value << " "
          << Unit(joint, velocity);
      throw CheckFailed(msg.str());
    };
    if (!std::isfinite(q[j])) fail("q", q[j], false);
    if (!std::isfinite(qd[j]) || std::abs(qd[j]) > options_.max_speed) fail("qd", qd[j], true);
  }
}

void ArmSimulation::DriveTorques(std::int64_t step, Eigen::VectorXd* drive) const {
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

void ArmSimulation::FrictionTorques(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau,
                                    double h, Eigen::VectorXd* friction) const {
  friction->setZero(model_.dof());
  if (friction_joints_.empty()) return;
  // Velocities at the end of the step without friction, and how a torque on one joint
  // changes them: h M^-1.
  const Eigen::LLT<Eigen::MatrixXd> llt(MassMatrix(model_, q));
  const Eigen::VectorXd free_end = qd + h * llt.solve(tau - BiasForces(model_, q, qd));
  const Eigen::MatrixXd response = h * llt.solve(Eigen::MatrixXd::Identity(model_.dof(), model_.dof()));
  // Projected Gauss-Seidel: each joint's friction given the others', until it settles.
  for (int sweep = 0; sweep < kFrictionSweeps; ++sweep) {
    double change = 0, size = 0;
    for (int j : friction_joints_) {
      const double w = response(j, j);
      const double v = free_end[j] - response.row(j).dot(*friction) + w * (*friction)[j];
      const double f = JointFriction(model_.joints[static_cast<std::size_t>(j)], effects_[static_cast<std::size_t>(j)],
                                     v, w, qd[j]);
      change = std::max(change, std::abs(f - (*friction)[j]));
      size = std::max(size, std::abs(f));
      (*friction)[j] = f;
    }
    if (friction_joints_.size() == 1 || change <= kFrictionTolerance * (1 + size)) break;
  }
}

ArmSample ArmSimulation::Step(const ArmController& controller) {
  CheckState();
  const int n = model_.dof();
  ArmSample out;
  out.t = time();
  out.q = backend_->q();
  out.qd = backend_->qd();
  out.command = controller ? controller(out.t, out.q, out.qd) : Eigen::VectorXd::Zero(n);
  if (out.command.size() != n) {
    throw std::invalid_argument("arm controller sent " + std::to_string(out.command.size()) +
                                " torques for an arm with " + std::to_string(n) + " joints");
  }
  for (int j = 0; j < n; ++j) {
    if (!std::isfinite(out.command[j])) {
      std::ostringstream msg;
      msg << "arm controller sent a non-finite torque to " << JointName(model_, j) << " at t = " << out.t
          << " s: " << out.command[j];
      throw CheckFailed(msg.str());
    }
  }

  // The command delay line, then the time_delay history (kept as long as the longest
  // time_delay reaches back).
  const std::int64_t first_step = state_.sample * substeps_;
  state_.arrived.emplace_back(first_step, state_.commands_in_flight.Push(out.command));
  const double oldest_needed = static_cast<double>(first_step) - max_delay_steps_;
  while (state_.arrived.size() >= 2 && static_cast<double>(state_.arrived[1].first) <= oldest_needed) {
    state_.held_before = state_.arrived.front().second;
    state_.arrived.erase(state_.arrived.begin());
  }

  const double h = model_.sample_time / substeps_;
  Eigen::VectorXd drive(n), link(n), friction(n);
  out.applied = Eigen::VectorXd::Zero(n);
  for (int s = 0; s < substeps_; ++s) {
    DriveTorques(first_step + s, &drive);
    out.applied += drive / substeps_;
    const Eigen::VectorXd& q = backend_->q();
    const Eigen::VectorXd& qd = backend_->qd();
    link = drive;
    if (flexible_) {
      for (int j = 0; j < n; ++j) {
        const JointEffects& e = effects_[static_cast<std::size_t>(j)];
        if (!e.flexible()) continue;
        // The spring between motor and link carries the drive to the link; the motor
        // follows by semi-implicit Euler with the spring torque of the step's start.
        const double spring =
            e.stiffness * (state_.motor_q[j] - q[j]) + e.flex_damping * (state_.motor_qd[j] - qd[j]);
        link[j] = spring;
        state_.motor_qd[j] += h * (drive[j] - spring) / e.motor_inertia;
        state_.motor_q[j] += h * state_.motor_qd[j];
      }
    }
    FrictionTorques(q, qd, link, h, &friction);
    backend_->Step(link - friction, h);
  }
  ++state_.sample;
  return out;
}

ArmTrajectory ArmSimulation::Run(int samples, const ArmController& controller,
                                 const std::function<void(int, int)>& progress) {
  const int n = model_.dof();
  ArmTrajectory run;
  run.backend = backend_->name();
  run.sample_time = model_.sample_time;
  const int rows = std::max(0, samples);
  run.t.resize(rows);
  run.q.resize(rows, n);
  run.qd.resize(rows, n);
  run.command.resize(rows, n);
  run.applied.resize(rows, n);
  for (int k = 0; k < rows; ++k) {
    const ArmSample s = Step(controller);
    run.t[k] = s.t;
    run.q.row(k) = s.q.transpose();
    run.qd.row(k) = s.qd.transpose();
    run.command.row(k) = s.command.transpose();
    run.applied.row(k) = s.applied.transpose();
    if (progress && (k % 1024 == 0 || k + 1 == rows)) progress(k + 1, rows);
  }
  return run;
}

ArmSimulationState ArmSimulation::Save() const {
  ArmSimulationState s = state_;
  s.backend = backend_->Save();
  return s;
}

void ArmSimulation::Restore(const ArmSimulationState& state) {
  const int n = model_.dof();
  if (state.commands_in_flight.length() != model_.delay_samples || state.held_before.size() != n ||
      state.motor_q.size() != n || state.motor_qd.size() != n) {
    throw std::invalid_argument("arm simulation: state of another arm");
  }
  backend_->Restore(state.backend);
  state_ = state;
}

}  // namespace twinsim

#include "sim/arm_simulation.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/interrupt.h"

namespace twinsim {
namespace {

std::string Unit(const ArmJoint& j, bool velocity) {
  const bool revolute = j.type == JointType::kRevolute;
  if (velocity) return revolute ? "rad/s" : "m/s";
  return revolute ? "rad" : "m";
}

std::string JointName(const ArmModel& model, int j) {
  return "joint " + std::to_string(j + 1) + " '" + model.joints[static_cast<std::size_t>(j)].name + "'";
}

}  // namespace

bool ArmSimulationOptions::IsValid(std::string* why) const {
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
    throw InputError("arm simulation: model '" + model_.name + "': " + problems);
  }
  Reset(Eigen::VectorXd::Zero(model_.dof()), Eigen::VectorXd::Zero(model_.dof()));
}

void ArmSimulation::Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_before) {
  const int n = model_.dof();
  const Eigen::VectorXd held = tau_before.size() == 0 ? Eigen::VectorXd::Zero(n) : tau_before;
  if (held.size() != n || !held.allFinite()) {
    throw std::invalid_argument("arm simulation: Reset needs " + std::to_string(n) + " finite torques before t = 0");
  }
  backend_->Reset(q, qd, held);
  state_ = ArmSimulationState{};
  state_.commands_in_flight = DelayLine<Eigen::VectorXd>(model_.delay_samples, held);
  state_.last_good_q = backend_->q();
  state_.last_good_qd = backend_->qd();
}

void ArmSimulation::CheckState() {
  const Eigen::VectorXd& q = backend_->q();
  const Eigen::VectorXd& qd = backend_->qd();
  for (int j = 0; j < model_.dof(); ++j) {
    const ArmJoint& joint = model_.joints[static_cast<std::size_t>(j)];
    auto fail = [&](const char* what, double value, bool velocity) {
      std::ostringstream msg;
      msg << "arm simulation diverged at t = " << time() << " s (sample " << state_.sample << ") on backend "
          << backend_->name() << ": " << JointName(model_, j) << " " << what << " = " << value << " "
          << Unit(joint, velocity) << "; last good state at t = " << state_.last_good_t << " s:";
      for (int i = 0; i < model_.dof(); ++i) {
        const ArmJoint& other = model_.joints[static_cast<std::size_t>(i)];
        msg << (i ? "," : "") << " q" << i + 1 << " = " << state_.last_good_q[i] << " " << Unit(other, false)
            << ", qd" << i + 1 << " = " << state_.last_good_qd[i] << " " << Unit(other, true);
      }
      throw CheckFailed(msg.str());
    };
    if (!std::isfinite(q[j])) fail("q", q[j], false);
    if (!std::isfinite(qd[j]) || std::abs(qd[j]) > options_.max_speed) fail("qd", qd[j], true);
  }
  state_.last_good_t = time();
  state_.last_good_q = q;
  state_.last_good_qd = qd;
}

ArmSample ArmSimulation::Step(const ArmController& controller) {
  ArmSample out;
  StepInto(controller, &out);
  return out;
}

void ArmSimulation::StepInto(const ArmController& controller, ArmSample* out) {
  ThrowIfInterrupted();
  CheckState();
  const int n = model_.dof();
  out->t = time();
  out->q = backend_->q();
  out->qd = backend_->qd();
  if (controller) {
    out->command = controller(out->t, out->q, out->qd);
  } else {
    out->command.setZero(n);
  }
  if (out->command.size() != n) {
    throw std::invalid_argument("arm controller sent " + std::to_string(out->command.size()) +
                                " torques for an arm with " + std::to_string(n) + " joints");
  }
  for (int j = 0; j < n; ++j) {
    if (!std::isfinite(out->command[j])) {
      std::ostringstream msg;
      msg << "arm controller sent a non-finite torque to " << JointName(model_, j) << " at t = " << out->t
          << " s: " << out->command[j];
      throw CheckFailed(msg.str());
    }
  }

  // The command delay line; the backend takes it from there.
  state_.commands_in_flight.Push(out->command, &delayed_);
  backend_->Step(delayed_, &out->applied);
  ++state_.sample;
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
  ArmSample s;
  for (int k = 0; k < rows; ++k) {
    StepInto(controller, &s);
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
  if (state.commands_in_flight.length() != model_.delay_samples) {
    throw std::invalid_argument("arm simulation: state of another arm");
  }
  backend_->Restore(state.backend);
  state_ = state;
}

}  // namespace twinsim

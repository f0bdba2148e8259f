#include "learning/omni_residual.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <sstream>

#include "core/error.h"
#include "robots/omni/omni_model_yaml_writer.h"
#include "sim/newtonian_omni_backend.h"

namespace twinsim {

NominalOmniTrack::NominalOmniTrack(const OmniModel& model, const std::string& engine, double frame_rate, int substeps,
                                   int errors)
    : model_(model),
      engine_(engine),
      frame_rate_(frame_rate),
      substeps_(substeps),
      errors_(static_cast<std::size_t>(std::max(errors, 0)), Eigen::Vector3d::Zero()) {
  FrameTiming timing;
  timing.frame_rate = frame_rate;
  timing.physics_substeps = substeps > 0 ? substeps : DefaultPhysicsSubsteps(frame_rate);
  FieldModel field;
  field.walls = false;  // the robot's own motion only: the field is not part of the correction
  backend_ = std::make_unique<NewtonianOmniBackend>(MakeOmniEngine(engine, {model}, field), std::vector<OmniModel>{model},
                                                    timing);
}

NominalOmniTrack::NominalOmniTrack(const NominalOmniTrack& other)
    : NominalOmniTrack(other.model_, other.engine_, other.frame_rate_, other.substeps_,
                       static_cast<int>(other.errors_.size())) {
  Restore(other.Save());
}

NominalOmniTrack& NominalOmniTrack::operator=(const NominalOmniTrack& other) {
  if (this != &other) *this = NominalOmniTrack(other);
  return *this;
}

void NominalOmniTrack::Reset(const Pose2& pose, const Twist2& velocity) {
  backend_->Reset(0, pose, velocity);
  predicted_ = pose;
  for (Eigen::Vector3d& e : errors_) e.setZero();
}

Pose2 NominalOmniTrack::Step(const Twist2& acting) {
  const Pose2 from = backend_->pose(0);
  backend_->StepFrame({acting});
  predicted_ = backend_->pose(0);
  if (!IsFinite(predicted_)) {
    std::ostringstream msg;
    msg << "the residual predictor's nominal model (" << engine_ << ") diverged in one frame from x = " << from.x
        << " m, y = " << from.y << " m, theta = " << from.theta << " rad under the command (" << acting.vx << ", "
        << acting.vy << ", " << acting.omega << ")";
    throw CheckFailed(msg.str());
  }
  if (!errors_.empty()) {
    errors_.erase(errors_.begin());
    errors_.push_back(Eigen::Vector3d::Zero());
  }
  return predicted_;
}

void NominalOmniTrack::Correct(const Pose2& pose) {
  if (!errors_.empty())
    errors_.back() = Eigen::Vector3d(pose.x - predicted_.x, pose.y - predicted_.y, WrapAngle(pose.theta - predicted_.theta));
  backend_->MoveBody(0, pose);
  predicted_ = pose;
}

Pose2 NominalOmniTrack::Lookahead(const Twist2* acting, int frames) {
  const NominalTrackState saved = Save();
  Pose2 p = backend_->pose(0);
  for (int j = 0; j < frames; ++j) p = Step(acting[j]);
  Restore(saved);
  return p;
}

NominalTrackState NominalOmniTrack::Save() const { return NominalTrackState{backend_->Save().robots, predicted_, errors_}; }

void NominalOmniTrack::Restore(const NominalTrackState& state) {
  backend_->Restore(OmniBackendState{state.backend});
  predicted_ = state.predicted;
  errors_ = state.errors;
}

std::string NominalModelFingerprint(const OmniModel& model) {
  // FNV-1a (64 bit) of the complete model file, which names every parameter.
  // Which engine the model was fitted on is not a parameter of its physics: a model whose
  // fitted_on alone differs keeps its residual predictors.
  OmniModel physics = model;
  physics.fitted_on.clear();
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : FormatOmniModelYaml(physics)) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char text[32];
  std::snprintf(text, sizeof text, "%016" PRIx64, h);
  return text;
}

}  // namespace twinsim

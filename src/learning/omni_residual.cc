#include "learning/omni_residual.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "robots/omni/omni_model_yaml_writer.h"
#include "sim/newtonian_omni_backend.h"

namespace twinsim {

NominalOmniTrack::NominalOmniTrack(const OmniModel& model, const std::string& engine, double frame_rate, int substeps,
                                   int errors, OmniReplayState state)
    : model_(model),
      engine_(engine),
      frame_rate_(frame_rate),
      substeps_(substeps),
      state_(state),
      errors_(static_cast<std::size_t>(std::max(errors, 0)), Eigen::Vector3d::Zero()) {
  FrameTiming timing;
  timing.frame_rate = frame_rate;
  timing.physics_substeps = substeps > 0 ? substeps : DefaultPhysicsSubsteps(frame_rate);
  FieldModel field;
  field.walls = false;  // the robot's own motion only: the field is not part of the correction
  auto backend = MakeNewtonianOmniBackend(engine, {model}, field, timing);
  if (state == OmniReplayState::kObserver) {
    // The track is handed the commands that act (after the model's delay), one frame at a
    // time: the filter's own delay line is not used (OmniObserver::PredictFrame).
    observer_ = std::make_unique<OmniObserver>(model, std::move(backend));
  } else {
    backend_ = std::move(backend);
  }
}

NominalOmniTrack::NominalOmniTrack(const NominalOmniTrack& other)
    : NominalOmniTrack(other.model_, other.engine_, other.frame_rate_, other.substeps_,
                       static_cast<int>(other.errors_.size()), other.state_) {
  Restore(other.Save());
}

NominalOmniTrack& NominalOmniTrack::operator=(const NominalOmniTrack& other) {
  if (this != &other) *this = NominalOmniTrack(other);
  return *this;
}

Pose2 NominalOmniTrack::pose() const { return observer_ ? observer_->backend().pose(0) : backend_->pose(0); }

Twist2 NominalOmniTrack::velocity() const {
  return observer_ ? observer_->Estimate().velocity : backend_->velocity(0);
}

void NominalOmniTrack::Reset(const Pose2& pose, const Twist2& velocity) {
  before_follow_.reset();
  if (observer_) {
    observer_->Start(pose, velocity);
  } else {
    backend_->Reset(0, pose, velocity);
  }
  predicted_ = pose;
  for (Eigen::Vector3d& e : errors_) e.setZero();
}

Pose2 NominalOmniTrack::Step(const Twist2& acting) {
  const Pose2 from = pose();
  before_follow_.reset();  // a new frame: the last one's Follow stands
  bool diverged = false;
  if (observer_) {
    try {
      observer_->PredictFrame(acting);
    } catch (const CheckFailed&) {
      diverged = true;  // the filter's own check: said below as the tracker's is
    }
  } else {
    backend_->StepFrame({acting});
  }
  predicted_ = pose();
  if (diverged || !IsFinite(predicted_)) {
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
  if (observer_) {
    if (before_follow_) {
      observer_->Restore(*before_follow_);
      before_follow_.reset();
    }
    observer_->CorrectFrame(pose);
    predicted_ = this->pose();
  } else {
    backend_->MoveBody(0, pose);
    predicted_ = pose;
  }
}

void NominalOmniTrack::Follow(const Pose2& pose) {
  if (!observer_) {
    Correct(pose);
    return;
  }
  if (!before_follow_) before_follow_ = observer_->Save();
  observer_->MovePose(pose);
}

Pose2 NominalOmniTrack::Lookahead(const Twist2* acting, int frames) {
  const NominalTrackState saved = Save();
  Pose2 p = pose();
  if (observer_) {
    // The filter's prediction ahead, its covariance not needed: the slip carried on,
    // decaying, as PredictAhead does.
    try {
      for (int j = 0; j < frames && IsFinite(p); ++j) {
        observer_->PredictFrame(acting[j], false);
        p = pose();
      }
    } catch (const CheckFailed&) {
      p = Pose2{NAN, NAN, NAN};  // the filter's own check: said below
    }
    Restore(saved);
    if (!IsFinite(p)) {
      std::ostringstream msg;
      msg << "the residual predictor's nominal model (" << engine_ << ") diverged within " << frames
          << " frames of its observer's estimate at x = " << saved.predicted.x << " m, y = " << saved.predicted.y << " m";
      throw CheckFailed(msg.str());
    }
    return p;
  }
  for (int j = 0; j < frames; ++j) p = Step(acting[j]);
  Restore(saved);
  return p;
}

NominalTrackState NominalOmniTrack::Save() const {
  NominalTrackState s;
  if (observer_) {
    s.observer = observer_->Save();
  } else {
    s.backend = backend_->Save().robots;
  }
  s.before_follow = before_follow_;
  s.predicted = predicted_;
  s.errors = errors_;
  return s;
}

void NominalOmniTrack::Restore(const NominalTrackState& state) {
  if (observer_) {
    if (!state.observer) throw std::invalid_argument("NominalOmniTrack::Restore: a tracker's state for an observer track");
    observer_->Restore(*state.observer);
  } else {
    if (state.observer) throw std::invalid_argument("NominalOmniTrack::Restore: an observer's state for a tracker");
    backend_->Restore(OmniBackendState{state.backend});
  }
  before_follow_ = state.before_follow;
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

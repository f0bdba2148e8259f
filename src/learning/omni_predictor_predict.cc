// Using an omni predictor: its one-frame and H-frame predictions (plain and residual),
// the bounds that hold it, the check of its use and its weights' draws
// (learning/omni_predictor.h). Training is in omni_predictor.cc, the file in
// omni_predictor_file.cc.
#include "learning/omni_predictor.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.h"
#include "robots/omni/omni_effects.h"

namespace twinsim {

Eigen::Vector3d OmniPredictor::PredictDelta(const double* inputs) const {
  const long n = info_.layout.num_inputs();
  const Eigen::Map<const Eigen::VectorXd> x(inputs, n);
  if (info_.kind == "mlp") return mlp_.Predict(x) - mlp_at_rest_;
  // No member scratch: one predictor is shared by the threads of an ensemble (run
  // --samples --jobs) and by robots of one field.
  return weights_ * (x - input_mean_).cwiseQuotient(input_scale_) + bias_;
}

void OmniPredictor::DrawWeights(const OmniPredictor& estimate, const Eigen::VectorXd& z) {
  const std::vector<Eigen::MatrixXd>& d = estimate.weight_uncertainty_.directions;
  if (z.size() != static_cast<long>(d.size())) throw std::invalid_argument("DrawWeights: one number per direction expected");
  weights_ = estimate.weights_;
  for (std::size_t l = 0; l < d.size(); ++l) weights_ += z[static_cast<long>(l)] * d[l];
}

void OmniPredictor::SetWeightUncertainty(RidgeWeightUncertainty u) {
  if (!u.directions.empty() && info_.kind != "linear")
    throw std::invalid_argument("SetWeightUncertainty: only a linear predictor has weights' directions");
  weight_uncertainty_ = std::move(u);
}

void OmniPredictor::SetEnsemble(std::vector<Mlp> members) {
  if (!members.empty() && info_.kind != "mlp") throw std::invalid_argument("SetEnsemble: only a network has members");
  ensemble_ = std::move(members);
  ensemble_at_rest_.clear();
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(info_.layout.num_inputs());
  for (const Mlp& member : ensemble_) ensemble_at_rest_.push_back(member.Predict(rest));
}

void OmniPredictor::DrawMember(const OmniPredictor& estimate, int k) {
  if (k < 0 || k > static_cast<int>(estimate.ensemble_.size())) throw std::invalid_argument("DrawMember: no such member");
  if (k == 0) {
    mlp_ = estimate.mlp_;
    mlp_at_rest_ = estimate.mlp_at_rest_;
  } else {
    mlp_ = estimate.ensemble_[static_cast<std::size_t>(k - 1)];
    mlp_at_rest_ = estimate.ensemble_at_rest_[static_cast<std::size_t>(k - 1)];
  }
}

namespace {

// Room for a predictor's inputs: on the stack for the usual sizes.
class InputBuffer {
 public:
  explicit InputBuffer(int size) {
    if (size > kOnStack) big_.resize(static_cast<std::size_t>(size));
  }
  double* data() { return big_.empty() ? small_ : big_.data(); }

 private:
  static constexpr int kOnStack = 256;
  double small_[kOnStack];
  std::vector<double> big_;
};

}  // namespace

Pose2 BoundStep(const OmniPredictorInfo& info, const Pose2& from, const Pose2& to, bool* bounded) {
  if (!(info.max_step > 0)) return to;  // no bounds known
  Eigen::Vector3d d = EncodeDelta(from, to);
  const double step = std::hypot(d[0], d[1]), step_limit = kBoundFactor * info.max_step;
  const double turn_limit = kBoundFactor * std::max(info.max_turn, 1e-6);
  bool changed = false;
  if (!(step <= step_limit)) {  // NaN too
    const double k = std::isfinite(step) ? step_limit / step : 0;
    d[0] = std::isfinite(step) ? d[0] * k : 0;
    d[1] = std::isfinite(step) ? d[1] * k : 0;
    changed = true;
  }
  if (!(std::abs(d[2]) <= turn_limit)) {
    d[2] = std::isfinite(d[2]) ? std::clamp(d[2], -turn_limit, turn_limit) : 0;
    changed = true;
  }
  if (!changed) return to;
  if (bounded) *bounded = true;
  return ApplyDelta(from, d);
}

namespace {

// One pass over the inputs against `info`'s training range: whether every one lies within
// it widened by kInputMargin of its span (InputsSeen), and how far beyond it they went at
// most (InputExcess).
struct InputReach {
  bool seen = true;
  double excess = 0;
};
InputReach ReachOf(const OmniPredictorInfo& info, const double* inputs) {
  InputReach r;
  for (std::size_t i = 0; i < info.input_low.size(); ++i) {
    const double x = inputs[i], low = info.input_low[i], high = info.input_high[i], span = high - low;
    if (x >= low && x <= high) continue;  // inside (a NaN is not)
    const double margin = kInputMargin * span + 1e-9;
    if (!(x >= low - margin && x <= high + margin)) r.seen = false;
    const double out = std::max(low - x, x - high);
    const double e = std::isnan(x) ? 1.0 : span > 0 ? out / span : out > 1e-9 ? 1.0 : 0.0;
    r.excess = std::max(r.excess, std::min(e, kLargestInputExcess));  // an infinite input: far, but a number
  }
  return r;
}

// Whether the inputs `x` left the training range, and how far, where asked.
void CheckInputs(const OmniPredictorInfo& info, const double* x, bool* unseen, double* excess) {
  if (!unseen && !excess) return;
  const InputReach r = ReachOf(info, x);
  if (unseen) *unseen = !r.seen;
  if (excess) *excess = r.excess;
}

}  // namespace

bool InputsSeen(const OmniPredictorInfo& info, const double* inputs) { return ReachOf(info, inputs).seen; }

double InputExcess(const OmniPredictorInfo& info, const double* inputs) { return ReachOf(info, inputs).excess; }

Pose2 OmniPredictor::Predict(const Pose2* poses, const Twist2* commands, bool* unseen, double* excess) const {
  if (residual())
    throw std::logic_error("OmniPredictor::Predict: a residual predictor needs its nominal model's track");
  InputBuffer x(info_.layout.num_inputs());
  EncodeInputs(info_.layout, poses, commands, x.data());
  CheckInputs(info_, x.data(), unseen, excess);
  return ApplyDelta(poses[info_.layout.history - 1], PredictDelta(x.data()));
}

NominalOmniTrack OmniPredictor::MakeNominalTrack(const OmniModel& model) const {
  if (!residual()) throw std::logic_error("OmniPredictor::MakeNominalTrack: not a residual predictor");
  return NominalOmniTrack(model, info_.nominal_engine, info_.frame_rate, info_.nominal_substeps,
                          info_.layout.nominal_errors, info_.nominal_state);
}

Pose2 OmniPredictor::Corrected(const Pose2* poses, const Twist2* commands, const Twist2& nominal_velocity,
                               const Pose2& nominal_end, const std::vector<Eigen::Vector3d>& errors,
                               bool* unseen, double* excess) const {
  InputBuffer x(info_.layout.num_inputs());
  const Eigen::Vector3d nominal =
      EncodeResidualInputs(info_.layout, poses, commands, nominal_end, nominal_velocity, errors, x.data());
  CheckInputs(info_, x.data(), unseen, excess);
  return ApplyDelta(poses[info_.layout.history - 1], nominal + PredictDelta(x.data()));
}

Pose2 OmniPredictor::Predict(const Pose2* poses, const Twist2* commands, NominalOmniTrack* track, bool* unseen,
                             double* excess) const {
  if (!residual()) return Predict(poses, commands, unseen, excess);
  const FeatureLayout& layout = info_.layout;
  const Twist2 velocity = track->velocity();
  const Pose2 end = track->Lookahead(commands + layout.history - 1, layout.horizon);
  return Corrected(poses, commands, velocity, end, track->errors(), unseen, excess);
}

Pose2 OmniPredictor::Step(const Pose2* poses, const Twist2* commands, NominalOmniTrack* track, bool* unseen,
                          double* excess) const {
  const FeatureLayout& layout = info_.layout;
  if (layout.horizon != 1) throw std::logic_error("OmniPredictor::Step: a 1-frame predictor is needed");
  if (!residual()) return Predict(poses, commands, unseen, excess);
  const Twist2 velocity = track->velocity();
  const std::vector<Eigen::Vector3d> errors = track->errors();  // before the step shifts them
  const Pose2 end = track->Step(commands[layout.history - 1]);
  const Pose2 next = Corrected(poses, commands, velocity, end, errors, unseen, excess);
  // A prediction the nominal model cannot be put at (not finite, or faster than any
  // robot: 50 m/s, 1000 rad/s) has run away; say so before an engine chokes on it.
  const Pose2& now = poses[layout.history - 1];
  const double dt = 1.0 / info_.frame_rate;
  if (!IsFinite(next) || std::hypot(next.x - now.x, next.y - now.y) > 50 * dt || std::abs(next.theta - now.theta) > 1000 * dt) {
    std::ostringstream msg;
    msg << "the residual predictor ran away in one frame from x = " << now.x << " m, y = " << now.y
        << " m, theta = " << now.theta << " rad to x = " << next.x << " m, y = " << next.y << " m, theta = " << next.theta
        << " rad (its nominal model predicted x = " << end.x << " m, y = " << end.y << " m)";
    throw CheckFailed(msg.str());
  }
  track->Follow(next);
  return next;
}

void OmniPredictor::CheckUse(const OmniModel& model, double frame_rate, int horizon, const std::string& use) const {
  const SourceLocation where{path_};
  if (info_.model_name != model.name)
    throw InputError(where, "predictor was trained for model '" + info_.model_name + "', not '" + model.name +
                                "' (" + use + ")");
  if (std::abs(info_.frame_rate - frame_rate) > kSameCameraRate * frame_rate) {
    std::ostringstream msg;
    msg << "predictor was trained at " << info_.frame_rate << " fps, " << use << " runs at " << frame_rate << " fps";
    throw InputError(where, msg.str());
  }
  if (info_.layout.horizon != horizon)
    throw InputError(where, "predictor predicts " + std::to_string(info_.layout.horizon) + " frame(s) ahead, " + use +
                                " needs " + std::to_string(horizon));
  const int delay = model.command_delay_frames + model.vision_delay_frames;
  if (info_.layout.command_lag != delay)
    throw InputError(where, "predictor assumes a delay of " + std::to_string(info_.layout.command_lag) +
                                " frames, model '" + model.name + "' has " + std::to_string(delay));
  if (residual() && NominalModelFingerprint(model) != info_.nominal_fingerprint)
    throw InputError(where, "residual predictor was trained over another version of model '" + model.name +
                                "' (its parameters or effects differ; fingerprint " + info_.nominal_fingerprint +
                                ", this model's " + NominalModelFingerprint(model) + "): train it again over this one (" +
                                use + ")");
}

}  // namespace twinsim

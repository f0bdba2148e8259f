#include "backends/learned/learned_omni_backend.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.h"

namespace twinsim {
namespace {

class LearnedOmniBackend final : public OmniBackend {
 public:
  LearnedOmniBackend(const std::vector<OmniModel>& robots, const FrameTiming& timing,
                     std::shared_ptr<const OmniPredictor> predictor)
      : timing_(timing), predictor_(std::move(predictor)), current_(predictor_.get()), layout_(predictor_->info().layout) {
    robots_.resize(robots.size());
    for (std::size_t i = 0; i < robots.size(); ++i) {
      predictor_->CheckUse(robots[i], timing.frame_rate, 1, "the learned backend");
      if (predictor_->residual()) tracks_.push_back(predictor_->MakeNominalTrack(robots[i]));
      Reset(static_cast<int>(i), Pose2{}, Twist2{});
    }
  }

  std::string name() const override { return "learned"; }
  int num_robots() const override { return static_cast<int>(robots_.size()); }
  const FrameTiming& timing() const override { return timing_; }

  void Reset(int robot, const Pose2& pose, const Twist2& velocity) override {
    OmniRobotState& s = At(robot);
    const int h = layout_.history;
    s.pose_history.assign(static_cast<std::size_t>(h), pose);
    s.command_history.assign(static_cast<std::size_t>(h), velocity);
    // A robot that has moved steadily at `velocity` (robot frame) until now.
    const double dt = timing_.frame_dt();
    for (int j = 0; j < h; ++j) {
      const double back = (h - 1 - j) * dt;
      const double theta = pose.theta - velocity.omega * back;
      const Twist2 field = BodyToField(velocity, 0.5 * (theta + pose.theta));
      s.pose_history[static_cast<std::size_t>(j)] = Pose2{pose.x - field.vx * back, pose.y - field.vy * back, theta};
    }
    if (!tracks_.empty()) tracks_[static_cast<std::size_t>(robot)].Reset(pose, velocity);
  }

  void MoveBody(int robot, const Pose2& pose) override {
    At(robot).pose_history.back() = pose;
    if (!tracks_.empty()) tracks_[static_cast<std::size_t>(robot)].Correct(pose);
  }

  // A slip, not a measurement: the residual's model follows it (the tracker's: as a
  // measurement; the observer's: its pose moved, its filter untouched).
  void PushBody(int robot, const Pose2& pose) override {
    At(robot).pose_history.back() = pose;
    if (!tracks_.empty()) tracks_[static_cast<std::size_t>(robot)].Follow(pose);
  }

  void StepFrame(const std::vector<Twist2>& commands) override {
    if (static_cast<int>(commands.size()) != num_robots())
      throw std::invalid_argument("StepFrame: one command per robot expected");
    for (int i = 0; i < num_robots(); ++i) {
      OmniRobotState& s = At(i);
      s.command_history.erase(s.command_history.begin());
      s.command_history.push_back(commands[static_cast<std::size_t>(i)]);
      bool unseen = false;
      double excess = 0;
      const Pose2 predicted =
          tracks_.empty()
              ? current_->Predict(s.pose_history.data(), s.command_history.data(), &unseen, &excess)
              : current_->Step(s.pose_history.data(), s.command_history.data(), &tracks_[static_cast<std::size_t>(i)],
                               &unseen, &excess);
      unseen_steps_ += unseen ? 1 : 0;
      largest_excess_ = std::max(largest_excess_, excess);
      // A predictor outside what it learned (speeds, inputs) is held to the robot's
      // bounds seen in training instead of running away (learning/omni_predictor.h).
      bool bounded = false;
      const Pose2 next = BoundStep(predictor_->info(), s.pose_history.back(), predicted, &bounded);
      if (bounded) {
        ++bounded_steps_;
        if (!tracks_.empty()) tracks_[static_cast<std::size_t>(i)].Follow(next);
      }
      s.pose_history.erase(s.pose_history.begin());
      s.pose_history.push_back(next);
    }
  }

  Pose2 pose(int robot) const override { return robots_.at(static_cast<std::size_t>(robot)).pose_history.back(); }

  Twist2 velocity(int robot) const override {
    const OmniRobotState& s = robots_.at(static_cast<std::size_t>(robot));
    const Eigen::Vector3d d = EncodeDelta(s.pose_history[s.pose_history.size() - 2], s.pose_history.back());
    const double dt = timing_.frame_dt();
    // The last frame's motion, in the robot frame of the newest pose.
    const Twist2 v{d[0] / dt, d[1] / dt, d[2] / dt};
    Twist2 out = v;
    Rotate(-d[2], v.vx, v.vy, &out.vx, &out.vy);
    return out;
  }

  // A linear predictor's weights drawn from their uncertainty, or one of a network's
  // ensemble (each member as likely).
  bool DrawParameters(Rng* rng) override {
    const int directions = static_cast<int>(predictor_->weight_uncertainty().directions.size());
    const int members = static_cast<int>(predictor_->ensemble().size()) + 1;
    if (directions == 0 && members == 1) return false;
    if (!rng) {
      current_ = predictor_.get();
      return true;
    }
    if (!drawn_) drawn_ = std::make_unique<OmniPredictor>(*predictor_);
    if (directions > 0) {
      Eigen::VectorXd z(directions);
      for (int l = 0; l < directions; ++l) z[l] = rng->Gaussian();
      drawn_->DrawWeights(*predictor_, z);
    } else {
      drawn_->DrawMember(*predictor_, static_cast<int>(rng->Index(static_cast<std::uint64_t>(members))));
    }
    current_ = drawn_.get();
    return true;
  }

  double TakeInputExcess() override {
    if (predictor_->info().input_low.empty()) return -1;  // no ranges to measure against
    const double largest = largest_excess_;
    largest_excess_ = 0;
    return largest;
  }

  long bounded_steps() const override { return bounded_steps_; }
  long unseen_input_steps() const override { return unseen_steps_; }

  OmniBackendState Save() const override {
    OmniBackendState state{robots_};
    for (std::size_t i = 0; i < tracks_.size(); ++i)
      state.robots[i].nominal = std::make_shared<const NominalTrackState>(tracks_[i].Save());
    return state;
  }
  void Restore(const OmniBackendState& state) override {
    if (state.robots.size() != robots_.size())
      throw std::invalid_argument("Restore: state has the wrong number of robots");
    robots_ = state.robots;
    for (std::size_t i = 0; i < tracks_.size(); ++i) {
      if (!robots_[i].nominal) throw std::invalid_argument("Restore: state lacks the residual predictor's track");
      tracks_[i].Restore(*robots_[i].nominal);
      robots_[i].nominal.reset();
    }
  }

 private:
  OmniRobotState& At(int robot) { return robots_.at(static_cast<std::size_t>(robot)); }

  FrameTiming timing_;
  std::shared_ptr<const OmniPredictor> predictor_;
  // The predictor stepping the robots: predictor_, or drawn_ after DrawParameters drew its
  // weights (a copy made on the first draw, its weights moved on each).
  const OmniPredictor* current_;
  std::unique_ptr<OmniPredictor> drawn_;
  FeatureLayout layout_;
  std::vector<OmniRobotState> robots_;
  std::vector<NominalOmniTrack> tracks_;  // a residual predictor's nominal model per robot; empty otherwise
  long bounded_steps_ = 0;
  long unseen_steps_ = 0;  // steps whose inputs left the training range
  double largest_excess_ = 0;  // since the last TakeInputExcess
};

}  // namespace

std::unique_ptr<OmniBackend> MakeLearnedOmniBackend(const std::vector<OmniModel>& robots, const FrameTiming& timing,
                                                    std::shared_ptr<const OmniPredictor> predictor) {
  if (!predictor) throw InputError("the learned backend needs a predictor: pass --predictor FILE");
  return std::make_unique<LearnedOmniBackend>(robots, timing, std::move(predictor));
}

}  // namespace twinsim

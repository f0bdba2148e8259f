// A field whose robots run on different backends (issue 32: each robot with its own
// model and backend): one sub-backend per group of robots, each its own world, behind
// the one OmniBackend the loop steps.
//
// The field's robots are numbered 0..n-1 (the scene's order); each group holds a
// backend of its own robots and says which field robot each of them is. Every call is
// passed to the backend of the robot named, StepFrame to every backend with its robots'
// commands, and Save() returns one state in field order, so the loop, the ball and
// Save/Restore see one field.
//
// Robots of one group share their backend's world and collide with each other (on ode
// and bullet); robots of different groups are in different worlds and pass through each
// other. MakeOmniBackend(per_robot, ...) (backends/omni_backend_factory.h) builds one
// only for a field whose robots do not all run on the same backend.
//
//   std::vector<OmniBackendGroup> groups;
//   groups.push_back({MakeOmniBackend("ode", {a, b}, field, timing), {0, 2}});
//   groups.push_back({MakeOmniBackend("analytic", {c}, field, timing), {1}});
//   GroupedOmniBackend backend(std::move(groups), {"blue0", "yellow0", "blue1"});
#pragma once

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "sim/omni_backend.h"

namespace twinsim {

// One backend and the field robots it moves: its robot j is field robot robots[j].
struct OmniBackendGroup {
  std::unique_ptr<OmniBackend> backend;
  std::vector<int> robots;
};

class GroupedOmniBackend final : public OmniBackend {
 public:
  // `labels` name the field's robots in name() (one per robot). Throws
  // std::invalid_argument unless the groups' robots are 0..n-1 each exactly once, each
  // backend has as many robots as its group lists, the backends' timings are the same,
  // and there is one label per robot.
  GroupedOmniBackend(std::vector<OmniBackendGroup> groups, std::vector<std::string> labels);

  // "mixed: ode (blue0, blue1), analytic (yellow0)": each backend with its robots, in
  // the order of the groups.
  std::string name() const override { return name_; }
  std::string robot_backend(int robot) const override;
  int num_robots() const override { return static_cast<int>(where_.size()); }
  const FrameTiming& timing() const override { return groups_.front().backend->timing(); }

  void Reset(int robot, const Pose2& pose, const Twist2& velocity) override;
  void MoveBody(int robot, const Pose2& pose) override;
  void PushBody(int robot, const Pose2& pose) override;
  bool has_velocity_state() const override;
  void SetVelocity(int robot, const Twist2& velocity) override;
  void StepFrame(const std::vector<Twist2>& commands) override;
  Pose2 pose(int robot) const override;
  Twist2 velocity(int robot) const override;
  // Every group's grip check together.
  GripCheck grip() const override {
    GripCheck total;
    for (const OmniBackendGroup& g : groups_) total += g.backend->grip();
    return total;
  }

  // The largest over the groups that measure it (-1 where none does).
  double TakeInputExcess() override {
    double largest = -1;
    for (OmniBackendGroup& g : groups_) largest = std::max(largest, g.backend->TakeInputExcess());
    return largest;
  }

  // Every group draws (or goes back to its estimate); true when any does.
  bool DrawParameters(Rng* rng) override {
    bool any = false;
    for (OmniBackendGroup& g : groups_) any = g.backend->DrawParameters(rng) || any;
    return any;
  }

  // The robots' states in field order (each as its own backend saves it).
  OmniBackendState Save() const override;
  // Throws std::invalid_argument for a state of another number of robots (and as the
  // sub-backends do for one of another field).
  void Restore(const OmniBackendState& state) override;

  int num_groups() const { return static_cast<int>(groups_.size()); }
  const OmniBackendGroup& group(int g) const { return groups_.at(static_cast<std::size_t>(g)); }

 private:
  // Where field robot i lives: its group and its index in that group's backend.
  struct Place {
    int group = -1;
    int index = -1;
  };
  const Place& At(int robot) const;

  std::vector<OmniBackendGroup> groups_;
  std::vector<Place> where_;  // per field robot
  std::string name_;
};

}  // namespace twinsim

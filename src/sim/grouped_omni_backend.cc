#include "sim/grouped_omni_backend.h"

#include <stdexcept>

namespace twinsim {

GroupedOmniBackend::GroupedOmniBackend(std::vector<OmniBackendGroup> groups, std::vector<std::string> labels)
    : groups_(std::move(groups)) {
  if (groups_.empty()) throw std::invalid_argument("GroupedOmniBackend: no group");
  std::size_t n = 0;
  for (const OmniBackendGroup& g : groups_) {
    if (!g.backend) throw std::invalid_argument("GroupedOmniBackend: a group without a backend");
    if (g.backend->num_robots() != static_cast<int>(g.robots.size()))
      throw std::invalid_argument("GroupedOmniBackend: a backend's robots and its group's list differ in number");
    n += g.robots.size();
  }
  if (labels.size() != n) throw std::invalid_argument("GroupedOmniBackend: one label per robot expected");
  where_.assign(n, Place{});
  const FrameTiming& t = groups_.front().backend->timing();
  for (std::size_t gi = 0; gi < groups_.size(); ++gi) {
    const OmniBackendGroup& g = groups_[gi];
    const FrameTiming& u = g.backend->timing();
    // One loop steps every backend one frame at a time: their frames must be the same.
    if (u.frame_rate != t.frame_rate || u.physics_substeps != t.physics_substeps)
      throw std::invalid_argument("GroupedOmniBackend: the backends' timings differ");
    for (std::size_t j = 0; j < g.robots.size(); ++j) {
      const int i = g.robots[j];
      if (i < 0 || static_cast<std::size_t>(i) >= n || where_[static_cast<std::size_t>(i)].group >= 0)
        throw std::invalid_argument("GroupedOmniBackend: the groups' robots are not 0..n-1 each once");
      where_[static_cast<std::size_t>(i)] = Place{static_cast<int>(gi), static_cast<int>(j)};
    }
  }
  name_ = "mixed: ";
  for (std::size_t gi = 0; gi < groups_.size(); ++gi) {
    if (gi > 0) name_ += ", ";
    name_ += groups_[gi].backend->name() + " (";
    for (std::size_t j = 0; j < groups_[gi].robots.size(); ++j)
      name_ += (j > 0 ? ", " : "") + labels[static_cast<std::size_t>(groups_[gi].robots[j])];
    name_ += ")";
  }
}

const GroupedOmniBackend::Place& GroupedOmniBackend::At(int robot) const {
  return where_.at(static_cast<std::size_t>(robot));
}

std::string GroupedOmniBackend::robot_backend(int robot) const {
  const Place& p = At(robot);
  return groups_[static_cast<std::size_t>(p.group)].backend->robot_backend(p.index);
}

void GroupedOmniBackend::Reset(int robot, const Pose2& pose, const Twist2& velocity) {
  const Place& p = At(robot);
  groups_[static_cast<std::size_t>(p.group)].backend->Reset(p.index, pose, velocity);
}

void GroupedOmniBackend::MoveBody(int robot, const Pose2& pose) {
  const Place& p = At(robot);
  groups_[static_cast<std::size_t>(p.group)].backend->MoveBody(p.index, pose);
}

void GroupedOmniBackend::PushBody(int robot, const Pose2& pose) {
  const Place& p = At(robot);
  groups_[static_cast<std::size_t>(p.group)].backend->PushBody(p.index, pose);
}

bool GroupedOmniBackend::has_velocity_state() const {
  for (const OmniBackendGroup& g : groups_)
    if (!g.backend->has_velocity_state()) return false;
  return true;
}

void GroupedOmniBackend::SetVelocity(int robot, const Twist2& velocity) {
  const Place& p = At(robot);
  groups_[static_cast<std::size_t>(p.group)].backend->SetVelocity(p.index, velocity);
}

void GroupedOmniBackend::StepFrame(const std::vector<Twist2>& commands) {
  if (commands.size() != where_.size()) throw std::invalid_argument("StepFrame: one command per robot expected");
  for (OmniBackendGroup& g : groups_) {
    std::vector<Twist2> own;
    own.reserve(g.robots.size());
    for (int i : g.robots) own.push_back(commands[static_cast<std::size_t>(i)]);
    g.backend->StepFrame(own);
  }
}

Pose2 GroupedOmniBackend::pose(int robot) const {
  const Place& p = At(robot);
  return groups_[static_cast<std::size_t>(p.group)].backend->pose(p.index);
}

Twist2 GroupedOmniBackend::velocity(int robot) const {
  const Place& p = At(robot);
  return groups_[static_cast<std::size_t>(p.group)].backend->velocity(p.index);
}

OmniBackendState GroupedOmniBackend::Save() const {
  OmniBackendState state;
  state.robots.resize(where_.size());
  for (const OmniBackendGroup& g : groups_) {
    OmniBackendState own = g.backend->Save();
    for (std::size_t j = 0; j < g.robots.size(); ++j)
      state.robots[static_cast<std::size_t>(g.robots[j])] = std::move(own.robots.at(j));
  }
  return state;
}

void GroupedOmniBackend::Restore(const OmniBackendState& state) {
  if (state.robots.size() != where_.size())
    throw std::invalid_argument("Restore: state has the wrong number of robots");
  for (OmniBackendGroup& g : groups_) {
    OmniBackendState own;
    own.robots.reserve(g.robots.size());
    for (int i : g.robots) own.robots.push_back(state.robots[static_cast<std::size_t>(i)]);
    g.backend->Restore(own);
  }
}

}  // namespace twinsim

// GroupedOmniBackend on its own: robot indices mapped to each group's backend and back,
// the state in field order, and groups that do not make one field refused.
#include "sim/grouped_omni_backend.h"

#include <gtest/gtest.h>

#include "backends/omni_backend_factory.h"
#include "core/error.h"
#include "test_util.h"

namespace twinsim {
namespace {

std::unique_ptr<OmniBackend> Analytic(int robots, const FrameTiming& timing = FrameTiming{}) {
  return MakeOmniBackend("analytic", std::vector<OmniModel>(static_cast<std::size_t>(robots), testing::Omni4()),
                         FieldModel{}, timing);
}

std::vector<OmniBackendGroup> Groups(std::vector<int> first, std::vector<int> second) {
  std::vector<OmniBackendGroup> g;
  g.push_back({Analytic(static_cast<int>(first.size())), std::move(first)});
  g.push_back({Analytic(static_cast<int>(second.size())), std::move(second)});
  return g;
}

TEST(GroupedOmniBackend, EachFieldRobotIsItsGroupsRobot) {
  // Field robots 0 and 2 in the first group, 1 in the second.
  GroupedOmniBackend b(Groups({0, 2}, {1}), {"a", "b", "c"});
  EXPECT_EQ(b.name(), "mixed: analytic (a, c), analytic (b)");
  EXPECT_EQ(b.num_robots(), 3);
  for (int i = 0; i < 3; ++i) b.Reset(i, Pose2{double(i), 0, 0}, Twist2{});
  EXPECT_EQ(b.group(0).backend->pose(1).x, 2.0);  // field robot 2
  EXPECT_EQ(b.group(1).backend->pose(0).x, 1.0);  // field robot 1
  // Commands reach the robot they are for: only field robot 1 drives.
  for (int k = 0; k < 30; ++k) b.StepFrame({Twist2{}, Twist2{1, 0, 0}, Twist2{}});
  EXPECT_EQ(b.pose(0).x, 0.0);
  EXPECT_GT(b.pose(1).x, 1.3);
  EXPECT_EQ(b.pose(2).x, 2.0);
  EXPECT_GT(b.velocity(1).vx, 0.5);
  b.MoveBody(2, Pose2{2, 1, 0});
  EXPECT_EQ(b.pose(2).y, 1.0);
  // The state is in field order, and restores into the right robots.
  const OmniBackendState saved = b.Save();
  ASSERT_EQ(saved.robots.size(), 3u);
  EXPECT_EQ(saved.robots[1].body.pose.x, b.pose(1).x);
  EXPECT_EQ(saved.robots[2].body.pose.y, 1.0);
  for (int k = 0; k < 10; ++k) b.StepFrame({Twist2{0, 1, 0}, Twist2{}, Twist2{}});
  const Pose2 after = b.pose(0);
  b.Restore(saved);
  EXPECT_EQ(b.pose(0).y, 0.0);
  EXPECT_EQ(b.pose(1).x, saved.robots[1].body.pose.x);
  for (int k = 0; k < 10; ++k) b.StepFrame({Twist2{0, 1, 0}, Twist2{}, Twist2{}});
  EXPECT_EQ(b.pose(0).y, after.y);
  OmniBackendState two = saved;
  two.robots.pop_back();
  EXPECT_THROW(b.Restore(two), std::invalid_argument);
  EXPECT_THROW(b.StepFrame({Twist2{}}), std::invalid_argument);
}

TEST(GroupedOmniBackend, GroupsThatAreNotOneFieldAreRefused) {
  EXPECT_THROW(GroupedOmniBackend(Groups({0, 1}, {1}), {"a", "b", "c"}), std::invalid_argument);  // 1 twice
  EXPECT_THROW(GroupedOmniBackend(Groups({0, 3}, {1}), {"a", "b", "c"}), std::invalid_argument);  // no 2
  EXPECT_THROW(GroupedOmniBackend(Groups({0}, {1}), {"a"}), std::invalid_argument);               // labels
  std::vector<OmniBackendGroup> count;
  count.push_back({Analytic(2), {0}});
  EXPECT_THROW(GroupedOmniBackend(std::move(count), {"a"}), std::invalid_argument);
  FrameTiming at60;
  at60.frame_rate = 60;
  std::vector<OmniBackendGroup> timing;
  timing.push_back({Analytic(1), {0}});
  timing.push_back({Analytic(1, at60), {1}});
  EXPECT_THROW(GroupedOmniBackend(std::move(timing), {"a", "b"}), std::invalid_argument);
}

TEST(GroupedOmniBackend, TheFactoryGroupsOnlyWhenTheBackendsDiffer) {
  const std::vector<OmniModel> models(3, testing::Omni4());
  const std::vector<std::string> labels = {"a", "b", "c"};
  const auto same = MakeOmniBackend({{"analytic", nullptr}, {"analytic", nullptr}, {"analytic", nullptr}}, models,
                                    labels, FieldModel{}, FrameTiming{});
  EXPECT_EQ(same->name(), "analytic");
  EXPECT_EQ(dynamic_cast<const GroupedOmniBackend*>(same.get()), nullptr);
  const std::vector<std::string> built = AvailableOmniBackends();
  const std::string other = built.front() == "analytic" ? built[1] : built.front();
  ASSERT_NE(other, "learned");
  const auto mixed = MakeOmniBackend({{other, nullptr}, {"analytic", nullptr}, {other, nullptr}}, models, labels,
                                     FieldModel{}, FrameTiming{});
  EXPECT_EQ(mixed->name(), "mixed: " + other + " (a, c), analytic (b)");
  EXPECT_EQ(mixed->robot_backend(1), "analytic");
  EXPECT_EQ(mixed->robot_backend(2), other);
  EXPECT_THROW(MakeOmniBackend({{"analytic", nullptr}}, models, labels, FieldModel{}, FrameTiming{}),
               std::invalid_argument);
  // A learned robot without a predictor is refused as the learned backend refuses it.
  EXPECT_THROW(MakeOmniBackend({{"analytic", nullptr}, {"learned", nullptr}, {"analytic", nullptr}}, models, labels,
                               FieldModel{}, FrameTiming{}),
               InputError);
}

}  // namespace
}  // namespace twinsim

// One conformance suite over every physics engine built into this binary (the learned
// backend, which needs a trained predictor, has its own tests in learned_backend_test.cc).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "backends/omni_backend_factory.h"
#include "core/math_constants.h"
#include "robots/omni/omni_kinematics.h"
#include "robots/omni/omni_log.h"
#include "scene/command_source.h"
#include "sim/newtonian_omni_backend.h"
#include "scene/scene_run.h"
#include "sim/omni_simulation.h"
#include "backends/engine_drives.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::Omni4;

class BackendConformance : public ::testing::TestWithParam<std::string> {};

CommandSpec Steps(std::vector<CommandSpec::Segment> segments) {
  CommandSpec spec;
  spec.type = "sequence";
  spec.segments = std::move(segments);
  return spec;
}

using testing::Drive;
using testing::Quiet;

TEST_P(BackendConformance, RestStaysAtRest) {
  const SimulationResult r = Drive(GetParam(), Quiet(Omni4()), Steps({{3.0, Twist2{}, false}}), 3.0);
  const FrameRecord& last = r.frames[0].back();
  EXPECT_LT(std::hypot(last.truth.x, last.truth.y), 1e-3) << "drifted in 3 s";
  EXPECT_LT(std::abs(last.truth.theta), 1e-3);
  EXPECT_LT(std::hypot(last.truth_velocity.vx, last.truth_velocity.vy), 1e-3);
}

struct AxisCase {
  Twist2 command;
  const char* label;
};

TEST_P(BackendConformance, ReachesCommandedVelocityOnEveryAxis) {
  for (const AxisCase& c : {AxisCase{{1.0, 0, 0}, "forward"}, AxisCase{{0, 1.0, 0}, "sideways"},
                            AxisCase{{0, 0, 3.0}, "rotation"}, AxisCase{{1.2, 1.2, 0}, "45 degrees"}}) {
    const SimulationResult r = Drive(GetParam(), Quiet(Omni4()), Steps({{2.0, c.command, false}}), 1.9);
    const Twist2& v = r.frames[0].back().truth_velocity;
    EXPECT_NEAR(v.vx, c.command.vx, 0.02 + 0.02 * std::abs(c.command.vx)) << c.label;
    EXPECT_NEAR(v.vy, c.command.vy, 0.02 + 0.02 * std::abs(c.command.vy)) << c.label;
    EXPECT_NEAR(v.omega, c.command.omega, 0.05 + 0.02 * std::abs(c.command.omega)) << c.label;
  }
}

TEST_P(BackendConformance, AgreesWithTheAnalyticModelOnSimpleDrives) {
  // Tolerances: the engines' contacts are compliant and their rollers slide with Coulomb
  // friction, the analytic wheels are rigid; over 2-3 m of driving they must stay
  // within 2 cm and 1 degree of each other.
  if (GetParam() == "analytic") GTEST_SKIP() << "the reference itself";
  const OmniModel model = Quiet(Omni4());
  struct Case {
    const char* label;
    CommandSpec spec;
  };
  const CommandSpec drive45 = testing::TestDrive45();
  for (const Case& c : {Case{"forward", Steps({{2.0, {1.5, 0, 0}, false}})},
                        Case{"sideways", Steps({{2.0, {0, 1.5, 0}, false}})},
                        Case{"rotation", Steps({{2.0, {0, 0, 4.0}, false}})},
                        Case{"45 degree test drive", drive45}}) {
    const SimulationResult engine = Drive(GetParam(), model, c.spec, 3.0);
    const SimulationResult reference = Drive("analytic", model, c.spec, 3.0);
    const auto [max_position, max_heading] = testing::LargestTruthDifference(engine, reference);
    EXPECT_LT(max_position, 0.02) << c.label;
    EXPECT_LT(max_heading, 1.0 * kPi / 180) << c.label;
  }
}

// Torques for a constant body wrench from rest: v(t) = M_eff^{-1} (F + F_g + F_r) t, while
// the wheels roll without slipping (forces well under the friction limit) and the
// rollers slide radially against Coulomb friction F_r = -sum mu_r N_i sign(s_i) e_i; F_g
// the weight's pull along a sloping floor, at the centre of mass.
void ExpectRigidBodyAcceleration(const std::string& engine_name, const OmniModel& m, const FieldModel& field,
                                 const Eigen::Vector3d& wrench) {
  OmniKinematics kin(m);
  // The rigid-body mass matrix about the centre, written out here from the model's
  // masses (the wheels and chassis.com put the centre of mass off the centre), plus the
  // wheels' spin.
  const double mt = m.chassis_mass + m.num_wheels() * m.wheel_mass;
  double xc = m.chassis_mass * m.chassis_com.x() / mt, yc = m.chassis_mass * m.chassis_com.y() / mt;
  for (double a : m.wheel_angles) {
    xc += m.wheel_mass * m.wheel_distance * std::cos(a) / mt;
    yc += m.wheel_mass * m.wheel_distance * std::sin(a) / mt;
  }
  const double chassis_iz = m.chassis_inertia_z > 0 ? m.chassis_inertia_z
                                                    : 0.5 * m.chassis_mass * m.chassis_radius * m.chassis_radius;
  const double iz = chassis_iz + m.chassis_mass * m.chassis_com.squaredNorm() +
                    m.num_wheels() * (m.wheel_inertia_diametral + m.wheel_mass * m.wheel_distance * m.wheel_distance);
  Eigen::Matrix3d mass;
  mass << mt, 0, -mt * yc, 0, mt, mt * xc, -mt * yc, mt * xc, iz;
  mass += m.wheel_spin_inertia * kin.wheels_from_body().transpose() * kin.wheels_from_body();
  // The robot starts at heading 0, so the field's downhill pull is the body's.
  const Eigen::Vector2d pull = mt * kGravity * std::sin(field.slope) *
                               Eigen::Vector2d(std::cos(field.slope_direction), std::sin(field.slope_direction));
  const Eigen::Vector3d load = wrench + Eigen::Vector3d(pull.x(), pull.y(), xc * pull.y() - yc * pull.x());

  // The closed form holds while no wheel slips: each wheel's force well under its grip
  // (static load; the acceleration moves some load between wheels).
  const Eigen::VectorXd wheel_force = kin.WheelTorques(wrench) / m.wheel_radius;
  for (int i = 0; i < m.num_wheels(); ++i)
    ASSERT_LT(std::abs(wheel_force[i]), 0.6 * m.wheel_friction * m.wheel_load[i]) << "wheel " << i << " would slip";

  std::unique_ptr<OmniEngine> engine = MakeOmniEngine(engine_name, {m}, field);
  OmniBodyState s;
  s.wheel_speeds = Eigen::VectorXd::Zero(m.num_wheels());
  engine->SetState(0, s);
  const double dt = 1.0 / 300;
  for (int i = 0; i < 60; ++i) {  // let the contacts settle
    engine->SetWheelTorques(0, Eigen::VectorXd::Zero(m.num_wheels()));
    engine->Step(dt);
  }
  s = engine->GetState(0);
  const Twist2 v0 = s.velocity;
  engine->SetWheelTorques(0, kin.WheelTorques(wrench));
  const int steps = 90;
  for (int i = 0; i < steps; ++i) engine->Step(dt);
  const Twist2 v = engine->GetState(0).velocity;
  const Eigen::Vector3d direction = mass.inverse() * load;
  Eigen::Vector3d roller = Eigen::Vector3d::Zero();
  for (int i = 0; i < m.num_wheels(); ++i) {
    const Eigen::Vector3d e(std::cos(m.wheel_angles[i]), std::sin(m.wheel_angles[i]), 0);
    const double slip = e.dot(direction);
    if (std::abs(slip) > 1e-6 * direction.norm()) roller -= m.roller_friction * m.wheel_load[i] * (slip > 0 ? 1 : -1) * e;
  }
  const Eigen::Vector3d expected = mass.inverse() * (load + roller) * (steps * dt);
  const Eigen::Vector3d got(v.vx - v0.vx, v.vy - v0.vy, v.omega - v0.omega);
  EXPECT_LT((got - expected).norm(), 0.03 * expected.norm() + 1e-3)
      << engine_name << ", wrench " << wrench.transpose() << ", slope " << field.slope << ": expected "
      << expected.transpose() << ", got " << got.transpose();
}

TEST_P(BackendConformance, OpenLoopWrenchMatchesRigidBodyAcceleration) {
  for (const Eigen::Vector3d& wrench : {Eigen::Vector3d(5, 0, 0), Eigen::Vector3d(0, 5, 0), Eigen::Vector3d(0, 0, 0.15)})
    ExpectRigidBodyAcceleration(GetParam(), Quiet(Omni4()), FieldModel{}, wrench);
}

// chassis.com: the chassis' centre of mass 2.5 cm off the centre (a battery to one side).
// Every engine moves the robot's centre as the rigid body about it predicts; the pose
// they report is the centre's, not the body's origin.
TEST_P(BackendConformance, OffCentreChassisMatchesRigidBodyAcceleration) {
  OmniModel m = Quiet(Omni4());
  m.chassis_com = Eigen::Vector2d(0.02, -0.015);
  m.Finalize();
  ASSERT_EQ(m.Validate(), "");
  // A force at the centre would spin the robot (the closed form leaves out the turning
  // frame): each force comes with the torque that keeps the yaw rate at zero.
  const OmniKinematics kin(m);
  const Eigen::MatrixXd& wheels = kin.wheels_from_body();
  const Eigen::Matrix3d inverse = (m.RigidBodyMass() + m.wheel_spin_inertia * wheels.transpose() * wheels).inverse();
  // 2 N, not 5: the rear left wheel carries 1.95 N here, and 5 N sideways makes it slip
  // (the engines' wheels can, the closed form's cannot; measured).
  for (Eigen::Vector3d wrench : {Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(0, 2, 0)}) {
    wrench.z() = -(inverse(2, 0) * wrench.x() + inverse(2, 1) * wrench.y()) / inverse(2, 2);
    ExpectRigidBodyAcceleration(GetParam(), m, FieldModel{}, wrench);
  }
  ExpectRigidBodyAcceleration(GetParam(), m, FieldModel{}, Eigen::Vector3d(0, 0, 0.15));
  // At rest, placed and read back: the centre, not the body's origin.
  std::unique_ptr<OmniEngine> engine = MakeOmniEngine(GetParam(), {m}, FieldModel{});
  OmniBodyState s;
  s.pose = Pose2{0.3, -0.2, 0.7};
  s.velocity = Twist2{0.4, -0.1, 1.5};
  s.wheel_speeds = OmniKinematics(m).WheelSpeeds(s.velocity);
  engine->SetState(0, s);
  const OmniBodyState back = engine->GetState(0);
  EXPECT_NEAR(back.pose.x, 0.3, 1e-12);
  EXPECT_NEAR(back.pose.y, -0.2, 1e-12);
  EXPECT_NEAR(back.velocity.vx, 0.4, 1e-12);
  EXPECT_NEAR(back.velocity.vy, -0.1, 1e-12);
}

// A floor sloping 3 degrees downhill towards 10 degrees: with no wheel torque the robot
// rolls off as the weight's pull along the floor, less the rollers' friction, predicts.
TEST_P(BackendConformance, SlopingFloorPullsAsTheWeightAlongIt) {
  FieldModel field;
  field.slope = 3 * kPi / 180;
  field.slope_direction = 10 * kPi / 180;  // no roller sliding near zero (a stuck roller)
  ExpectRigidBodyAcceleration(GetParam(), Quiet(Omni4()), field, Eigen::Vector3d::Zero());
}

TEST_P(BackendConformance, StepCommandAppearsExactlyAfterTheModelsDelay) {
  for (auto [cmd_delay, vision_delay] : {std::pair{2, 2}, std::pair{0, 0}, std::pair{1, 3}, std::pair{3, 0}}) {
    OmniModel m = Quiet(Omni4());
    m.command_delay_frames = cmd_delay;
    m.vision_delay_frames = vision_delay;
    const int step_frame = 10;
    const SimulationResult r = Drive(GetParam(), m, Steps({{step_frame / 30.0 - 1e-9, {}, false}, {1.0, {1.0, 0, 0}, false}}), 1.0);
    const auto& f = r.frames[0];
    ASSERT_EQ(f[step_frame].command.vx, 1.0);
    ASSERT_EQ(f[step_frame - 1].command.vx, 0.0);
    // Moved: more than 0.1 mm in one frame (the engines' contacts settle by a few um
    // after the start; the commanded drive moves about 1 mm in its first frame).
    int first_moved = -1;
    for (std::size_t k = 1; k < f.size() && first_moved < 0; ++k)
      if (std::abs(f[k].seen.x - f[k - 1].seen.x) > 1e-4) first_moved = static_cast<int>(k);
    EXPECT_EQ(first_moved, step_frame + cmd_delay + vision_delay + 1)
        << "command delay " << cmd_delay << ", vision delay " << vision_delay;
  }
}

TEST_P(BackendConformance, SameSeedGivesByteIdenticalLogs) {
  OmniModel m = Omni4();
  m.vision_drop_probability = 0.05;
  CommandSpec random;
  random.type = "random";
  auto log = [&](std::uint64_t seed) {
    const SimulationResult r = Drive(GetParam(), m, random, 4.0, seed);
    return FormatOmniLog(ObserverLog(r.frames[0]));
  };
  const std::string a = log(3), b = log(3), c = log(4);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST_P(BackendConformance, RestoringASavedStateReplaysExactly) {
  FrameTiming timing;
  const OmniModel m = Omni4();
  CommandSpec random;
  random.type = "random";
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", m, Pose2{}, MakeCommandSource(random, 9, 0, 10, Pose2{})});
  Simulation sim(std::move(robots), MakeOmniBackend(GetParam(), {m}, FieldModel{}, timing), 9);
  for (int k = 0; k < 40; ++k) sim.Step();
  const SimulationState saved = sim.Save();
  std::vector<FrameRecord> first;
  for (int k = 0; k < 30; ++k) first = sim.Step();
  sim.Restore(saved);
  std::vector<FrameRecord> second;
  for (int k = 0; k < 30; ++k) second = sim.Step();
  // Bit for bit, except that ODE's API re-normalises a restored quaternion, which can
  // change its last bit: 30 frames later that stays below a nanometre.
  const double tolerance = GetParam() == "ode" ? 1e-9 : 0.0;
  EXPECT_NEAR(first[0].truth.x, second[0].truth.x, tolerance);
  EXPECT_NEAR(first[0].truth.y, second[0].truth.y, tolerance);
  EXPECT_NEAR(first[0].truth.theta, second[0].truth.theta, tolerance);
  EXPECT_NEAR(first[0].seen.x, second[0].seen.x, tolerance);
  EXPECT_EQ(first[0].command.vx, second[0].command.vx);
}

TEST_P(BackendConformance, ManyRobotsRunSideBySide) {
  FrameTiming timing;
  const OmniModel m = Quiet(Omni4());
  std::vector<SimRobot> robots;
  std::vector<OmniModel> models;
  for (int i = 0; i < 11; ++i) {
    robots.push_back(SimRobot{"r" + std::to_string(i), m, Pose2{-3.0 + 0.5 * i, 0, 0},
                              MakeCommandSource(Steps({{1.0, {0, 1.0, 0}, false}}), 1, i, 1, Pose2{})});
    models.push_back(m);
  }
  Simulation sim(std::move(robots), MakeOmniBackend(GetParam(), models, FieldModel{}, timing), 1);
  SimulationResult r = sim.Run(31);
  for (int i = 0; i < 11; ++i) {
    // All robots moved alike along +y; none disturbed another.
    EXPECT_NEAR(r.frames[i].back().truth.y, r.frames[0].back().truth.y, 1e-3);
    EXPECT_NEAR(r.frames[i].back().truth.x, -3.0 + 0.5 * i, 2e-3);
  }
}

INSTANTIATE_TEST_SUITE_P(AllBuilt, BackendConformance, ::testing::ValuesIn(AvailableOmniEngines()),
                         [](const auto& info) { return info.param; });

}  // namespace
}  // namespace twinsim

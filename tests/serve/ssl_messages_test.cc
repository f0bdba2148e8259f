// The league's messages as twinsim writes and reads them: round trips through bytes,
// and RobotControl / SimulatorCommand read into moves, teleports and refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>

#include "core/math_constants.h"
#include "robots/omni/omni_model.h"
#include "serve/grsim_packet.h"
#include "serve/robot_control.h"
#include "serve/simulator_control.h"
#include "serve/vision_packets.h"
#include "ssl_simulation_custom_erforce_realism.pb.h"
#include "ssl_simulation_robot_control.pb.h"
#include "test_util.h"

namespace twinsim {
namespace {

TeamRoster TwoBlueOneYellow() {
  return TeamRoster({TeamRobot{TeamColor::kBlue, 0}, TeamRobot{TeamColor::kBlue, 1}, TeamRobot{TeamColor::kYellow, 3}});
}

std::string LocalCommand(unsigned id, float forward, float left, float angular) {
  RobotControl control;
  RobotCommand* c = control.add_robot_commands();
  c->set_id(id);
  MoveLocalVelocity* v = c->mutable_move_command()->mutable_local_velocity();
  v->set_forward(forward);
  v->set_left(left);
  v->set_angular(angular);
  return control.SerializeAsString();
}

TEST(SslMessages, DetectionPacketRoundTripsInMillimetresAndRadians) {
  const SSL_WrapperPacket sent =
      DetectionPacket({Sighting{TeamRobot{TeamColor::kBlue, 2}, Pose2{1.25, -0.5, 0.75}},
                       Sighting{TeamRobot{TeamColor::kYellow, 7}, Pose2{-3, 2, -1}}},
                      42, 1.5, 1.6);
  SSL_WrapperPacket read;
  ASSERT_TRUE(read.ParseFromString(sent.SerializeAsString()));
  ASSERT_TRUE(read.has_detection());
  const SSL_DetectionFrame& f = read.detection();
  EXPECT_EQ(f.frame_number(), 42u);
  EXPECT_EQ(f.t_capture(), 1.5);
  EXPECT_EQ(f.t_sent(), 1.6);
  EXPECT_EQ(f.camera_id(), 0u);
  ASSERT_EQ(f.robots_blue_size(), 1);
  ASSERT_EQ(f.robots_yellow_size(), 1);
  EXPECT_EQ(f.robots_blue(0).robot_id(), 2u);
  EXPECT_FLOAT_EQ(f.robots_blue(0).x(), 1250.0f);
  EXPECT_FLOAT_EQ(f.robots_blue(0).y(), -500.0f);
  EXPECT_FLOAT_EQ(f.robots_blue(0).orientation(), 0.75f);
  EXPECT_EQ(f.robots_yellow(0).robot_id(), 7u);
  EXPECT_FLOAT_EQ(f.robots_yellow(0).x(), -3000.0f);
}

TEST(SslMessages, GeometryIsTheFieldInsideTheBoundary) {
  FieldModel field;  // 10.4 x 7.4 m inside the walls
  SSL_WrapperPacket read;
  ASSERT_TRUE(read.ParseFromString(GeometryPacket(field, 0.3).SerializeAsString()));
  ASSERT_TRUE(read.has_geometry());
  EXPECT_EQ(read.geometry().field().field_length(), 9800);
  EXPECT_EQ(read.geometry().field().field_width(), 6800);
  EXPECT_EQ(read.geometry().field().boundary_width(), 300);
  EXPECT_EQ(read.geometry().calib_size(), 1);
  EXPECT_GE(read.geometry().field().field_lines_size(), 6);
}

TEST(SslMessages, WireBytesMatchTheSpecificationsFieldNumbers) {
  // RobotCommand{id = 1 (field 1, varint), move_command (field 2) {local_velocity
  // (field 2) {forward = 1.0f (field 1, fixed32)}}} as the specification numbers them.
  RobotCommand c;
  c.set_id(1);
  c.mutable_move_command()->mutable_local_velocity()->set_forward(1.0f);
  c.mutable_move_command()->mutable_local_velocity()->set_left(0);
  c.mutable_move_command()->mutable_local_velocity()->set_angular(0);
  const std::string bytes = c.SerializeAsString();
  const std::string expected("\x08\x01\x12\x11\x12\x0f\x0d\x00\x00\x80\x3f\x15\x00\x00\x00\x00\x1d\x00\x00\x00\x00", 21);
  EXPECT_EQ(bytes, expected);
  // SSL_DetectionFrame.t_capture is field 2 (double), robots_blue field 7.
  SSL_DetectionFrame f;
  f.set_frame_number(0);
  f.set_t_capture(0);
  f.set_t_sent(0);
  f.set_camera_id(0);
  f.add_robots_blue();
  EXPECT_NE(f.SerializePartialAsString().find('\x3a'), std::string::npos);  // (7 << 3) | 2
}

TEST(RobotControl, LocalAndGlobalVelocitiesBecomeMovesForTheTeamsOwnRobots) {
  const TeamRoster roster = TwoBlueOneYellow();
  RobotControlResult r = ReadRobotControl(LocalCommand(1, 1.5f, -0.5f, 2.0f), TeamColor::kBlue, roster);
  ASSERT_TRUE(r.parsed);
  EXPECT_EQ(r.refused, 0);
  ASSERT_EQ(r.moves.size(), 1u);
  EXPECT_EQ(r.moves[0].first, 1);
  EXPECT_FALSE(r.moves[0].second.global);
  EXPECT_DOUBLE_EQ(r.moves[0].second.velocity.vx, 1.5);
  EXPECT_DOUBLE_EQ(r.moves[0].second.velocity.vy, -0.5);
  EXPECT_EQ(r.response.errors_size(), 0);
  ASSERT_EQ(r.response.feedback_size(), 1);
  EXPECT_EQ(r.response.feedback(0).id(), 1u);

  RobotControl global;
  RobotCommand* c = global.add_robot_commands();
  c->set_id(3);
  MoveGlobalVelocity* g = c->mutable_move_command()->mutable_global_velocity();
  g->set_vel_x(1);
  g->set_vel_y(0);
  g->set_vel_angular(0);
  r = ReadRobotControl(global.SerializeAsString(), TeamColor::kYellow, roster);
  ASSERT_EQ(r.moves.size(), 1u);
  EXPECT_EQ(r.moves[0].first, 2);
  // Along the field's x axis is to the right of a robot heading +y (pi/2).
  const Twist2 local = LocalVelocity(r.moves[0].second, kPi / 2);
  EXPECT_NEAR(local.vx, 0, 1e-12);
  EXPECT_NEAR(local.vy, -1, 1e-12);
}

TEST(RobotControl, RefusesTheOtherTeamsRobotsUnknownIdsBadValuesAndWheels) {
  const TeamRoster roster = TwoBlueOneYellow();
  RobotControl control;
  auto add = [&](unsigned id, float forward) {
    RobotCommand* c = control.add_robot_commands();
    c->set_id(id);
    MoveLocalVelocity* v = c->mutable_move_command()->mutable_local_velocity();
    v->set_forward(forward);
    v->set_left(0);
    v->set_angular(0);
    return c;
  };
  add(3, 1);     // yellow's robot, from the blue port
  add(9, 1);     // nobody's
  add(0, 1e9f);  // beyond the limits
  RobotCommand* wheels = control.add_robot_commands();
  wheels->set_id(1);
  MoveWheelVelocity* w = wheels->mutable_move_command()->mutable_wheel_velocity();
  w->set_front_right(1);
  w->set_back_right(1);
  w->set_back_left(1);
  w->set_front_left(1);
  add(1, 0.5f)->set_kick_speed(3);  // moves, but there is no ball to kick
  const RobotControlResult r = ReadRobotControl(control.SerializeAsString(), TeamColor::kBlue, roster);
  ASSERT_TRUE(r.parsed);
  EXPECT_EQ(r.refused, 4);
  ASSERT_EQ(r.moves.size(), 1u);
  EXPECT_EQ(r.moves[0].first, 1);
  std::vector<std::string> codes;
  for (const SimulatorError& e : r.response.errors()) codes.push_back(e.code());
  EXPECT_EQ(codes, (std::vector<std::string>{"TWINSIM_OTHER_TEAM", "TWINSIM_UNKNOWN_ROBOT", "TWINSIM_BAD_VALUE",
                                             "TWINSIM_UNSUPPORTED", "TWINSIM_NO_BALL"}));
  EXPECT_NE(r.response.errors(0).message().find("robot 3 is a yellow robot"), std::string::npos)
      << r.response.errors(0).message();
  EXPECT_NE(r.response.errors(3).message().find("send local or global velocity"), std::string::npos)
      << r.response.errors(3).message();
}

// A datagram asking for a hundred errors (unknown robots) is answered with the first 16
// and one entry counting the other 84: the answer stays short.
TEST(RobotControl, AnAnswerListsSixteenErrorsAndCountsTheRest) {
  RobotControl control;
  for (unsigned id = 20; id < 120; ++id) {
    RobotCommand* c = control.add_robot_commands();
    c->set_id(id);
    c->mutable_move_command()->mutable_local_velocity()->set_forward(1);
    c->mutable_move_command()->mutable_local_velocity()->set_left(0);
    c->mutable_move_command()->mutable_local_velocity()->set_angular(0);
  }
  const std::string bytes = control.SerializeAsString();
  const RobotControlResult r = ReadRobotControl(bytes, TeamColor::kBlue, TwoBlueOneYellow());
  EXPECT_EQ(r.refused, 100);
  ASSERT_EQ(r.response.errors_size(), kMaxErrorsPerAnswer + 1);
  EXPECT_EQ(r.response.errors(15).code(), "TWINSIM_UNKNOWN_ROBOT");
  EXPECT_EQ(r.response.errors(16).code(), "TWINSIM_MORE_ERRORS");
  EXPECT_EQ(r.response.errors(16).message(), "... and 84 more errors, not listed (the first 16 are)");
  EXPECT_LT(r.response.ByteSizeLong(), bytes.size());
}

TEST(RobotControl, AnEmptyMoveCommandIsRefusedWithAnError) {
  // Counted as refused and named in the answer (it was counted with no error before).
  const TeamRoster roster = TwoBlueOneYellow();
  RobotControl control;
  RobotCommand* c = control.add_robot_commands();
  c->set_id(1);
  c->mutable_move_command();
  const RobotControlResult r = ReadRobotControl(control.SerializeAsString(), TeamColor::kBlue, roster);
  ASSERT_TRUE(r.parsed);
  EXPECT_EQ(r.refused, 1);
  EXPECT_TRUE(r.moves.empty());
  ASSERT_EQ(r.response.errors_size(), 1);
  EXPECT_EQ(r.response.errors(0).code(), "TWINSIM_BAD_VALUE");
  EXPECT_NE(r.response.errors(0).message().find("an empty move_command"), std::string::npos)
      << r.response.errors(0).message();
}

std::string WheelCommand(unsigned id, float front_right, float back_right, float back_left, float front_left) {
  RobotControl control;
  RobotCommand* c = control.add_robot_commands();
  c->set_id(id);
  MoveWheelVelocity* w = c->mutable_move_command()->mutable_wheel_velocity();
  w->set_front_right(front_right);
  w->set_back_right(back_right);
  w->set_back_left(back_left);
  w->set_front_left(front_left);
  return control.SerializeAsString();
}

TEST(RobotControl, WheelVelocitiesBecomeTheBodyVelocityTheyRollAt) {
  // omni4's wheels sit at 57, 135, 225 and 303 degrees: front left, back left, back
  // right, front right. Driving forward at 1 m/s, wheel i's rim moves at
  // -sin(alpha_i) m/s (models/omni4.yaml's convention, docs/models.md), worked by hand:
  const OmniModel omni4 = LoadOmniModel(testing::SourcePath("models/omni4.yaml"));
  const TeamRoster roster({TeamRobot{TeamColor::kBlue, 0, WheelMapFor(omni4)}});
  const auto rim = [](double deg) { return static_cast<float>(-std::sin(deg * kPi / 180)); };
  RobotControlResult r = ReadRobotControl(WheelCommand(0, rim(303), rim(225), rim(135), rim(57)), TeamColor::kBlue, roster);
  ASSERT_EQ(r.moves.size(), 1u) << r.response.DebugString();
  EXPECT_FALSE(r.moves[0].second.global);
  EXPECT_NEAR(r.moves[0].second.velocity.vx, 1, 1e-6);
  EXPECT_NEAR(r.moves[0].second.velocity.vy, 0, 1e-6);
  EXPECT_NEAR(r.moves[0].second.velocity.omega, 0, 1e-6);
  // Turning on the spot at 2 rad/s: every rim moves at b * omega, counter-clockwise positive.
  const float spin = static_cast<float>(2 * omni4.wheel_distance);
  r = ReadRobotControl(WheelCommand(0, spin, spin, spin, spin), TeamColor::kBlue, roster);
  ASSERT_EQ(r.moves.size(), 1u);
  EXPECT_NEAR(r.moves[0].second.velocity.vx, 0, 1e-6);
  EXPECT_NEAR(r.moves[0].second.velocity.omega, 2, 1e-5);
  // Speeds no rigid motion rolls at come back as the least-squares fit (the robot's own
  // odometry): one wheel alone gives a quarter of its share.
  r = ReadRobotControl(WheelCommand(0, 0, 0, 0, 1), TeamColor::kBlue, roster);
  ASSERT_EQ(r.moves.size(), 1u);
  EXPECT_LT(r.moves[0].second.velocity.vx, 0);  // the front-left wheel alone pushes backwards-left
  // Bad values are refused like a bad velocity.
  r = ReadRobotControl(WheelCommand(0, NAN, 0, 0, 0), TeamColor::kBlue, roster);
  EXPECT_TRUE(r.moves.empty());
  ASSERT_EQ(r.response.errors_size(), 1);
  EXPECT_EQ(r.response.errors(0).code(), "TWINSIM_BAD_VALUE");
}

TEST(RobotControl, OnlyFourWheelsOnePerQuadrantTakeWheelVelocities) {
  EXPECT_FALSE(WheelMapFor(LoadOmniModel(testing::SourcePath("models/omni3.yaml"))).has_value());
  const OmniModel skewed = LoadOmniModelFromString(
      "extends: " + testing::SourcePath("models/omni4.yaml") + "\nname: skewed\nwheels: {angles_deg: [30, 60, 225, 303]}\n",
      "skewed.yaml");
  EXPECT_FALSE(WheelMapFor(skewed).has_value());  // two front-left wheels
  EXPECT_TRUE(WheelMapFor(LoadOmniModel(testing::SourcePath("models/omni4.yaml"))).has_value());
}

TEST(RobotControl, GarbageIsAnsweredNeverThrown) {
  const TeamRoster roster = TwoBlueOneYellow();
  const std::string garbage("\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\x01", 12);
  const RobotControlResult r = ReadRobotControl(garbage, TeamColor::kBlue, roster);
  EXPECT_FALSE(r.parsed);
  ASSERT_EQ(r.response.errors_size(), 1);
  EXPECT_EQ(r.response.errors(0).code(), "TWINSIM_MALFORMED");
  // A RobotCommand without its required id is not a RobotControl either.
  RobotControl partial;
  partial.add_robot_commands();
  EXPECT_FALSE(ReadRobotControl(partial.SerializePartialAsString(), TeamColor::kBlue, roster).parsed);
  // Every prefix of a valid message is read or refused, never a crash.
  const std::string valid = LocalCommand(0, 1, 0, 0);
  for (std::size_t n = 0; n <= valid.size(); ++n) ReadRobotControl(valid.substr(0, n), TeamColor::kBlue, roster);
}

TEST(SimulatorControl, TeleportsKnownRobotsAndRefusesTheRest) {
  const TeamRoster roster = TwoBlueOneYellow();
  SimulatorCommand command;
  SimulatorControl* control = command.mutable_control();
  TeleportRobot* t = control->add_teleport_robot();
  t->mutable_id()->set_id(3);
  t->mutable_id()->set_team(YELLOW);
  t->set_x(1.0f);
  t->set_orientation(0.5f);
  TeleportRobot* unknown = control->add_teleport_robot();
  unknown->mutable_id()->set_id(5);
  unknown->mutable_id()->set_team(BLUE);
  TeleportRobot* outside = control->add_teleport_robot();
  outside->mutable_id()->set_id(0);
  outside->mutable_id()->set_team(BLUE);
  outside->set_x(50.0f);
  control->mutable_teleport_ball()->set_x(0);
  const SimulatorCommandResult r = ReadSimulatorCommand(command.SerializeAsString(), roster, FieldModel{});
  ASSERT_TRUE(r.parsed);
  ASSERT_EQ(r.teleports.size(), 1u);
  EXPECT_EQ(r.teleports[0].robot, 2);
  const Pose2 moved = TeleportedPose(r.teleports[0], Pose2{-2, 0.25, 0});
  EXPECT_DOUBLE_EQ(moved.x, 1.0);
  EXPECT_DOUBLE_EQ(moved.y, 0.25);  // kept
  EXPECT_FLOAT_EQ(static_cast<float>(moved.theta), 0.5f);
  EXPECT_EQ(r.refused, 3);
  std::vector<std::string> codes;
  for (const SimulatorError& e : r.response.errors()) codes.push_back(e.code());
  EXPECT_EQ(codes, (std::vector<std::string>{"TWINSIM_NO_BALL", "TWINSIM_UNKNOWN_ROBOT", "TWINSIM_BAD_VALUE"}));
}

TeleportRobot* AddTeleport(SimulatorControl* control, Team team, unsigned id) {
  TeleportRobot* t = control->add_teleport_robot();
  t->mutable_id()->set_id(id);
  t->mutable_id()->set_team(team);
  return t;
}

std::vector<std::string> CodesOf(const SimulatorResponse& response) {
  std::vector<std::string> codes;
  for (const SimulatorError& e : response.errors()) codes.push_back(e.code());
  return codes;
}

TEST(SimulatorControl, PresentAddsAndRemovesAndARobotOffTheFieldNeedsIt) {
  const TeamRoster roster = TwoBlueOneYellow();
  const std::vector<bool> present = {true, false, true};  // blue 1 is off the field
  SimulatorCommand command;
  SimulatorControl* control = command.mutable_control();
  AddTeleport(control, BLUE, 1)->set_x(1.0f);  // off the field, no present: refused
  TeleportRobot* forced = AddTeleport(control, BLUE, 1);
  forced->set_present(true);
  forced->set_by_force(true);  // cannot be added by force: refused
  TeleportRobot* add = AddTeleport(control, BLUE, 1);
  add->set_present(true);
  add->set_x(1.0f);
  add->set_y(-1.0f);
  AddTeleport(control, BLUE, 1)->set_x(2.0f);  // now on the field: a plain teleport
  TeleportRobot* remove = AddTeleport(control, YELLOW, 3);
  remove->set_present(false);
  remove->set_x(50.0f);  // ignored with present: false
  AddTeleport(control, YELLOW, 3)->set_x(0.0f);  // removed just before: refused
  TeleportRobot* pull = AddTeleport(control, BLUE, 0);
  pull->set_by_force(true);
  pull->set_x(1.0f);
  const SimulatorCommandResult r =
      ReadSimulatorCommand(command.SerializeAsString(), roster, FieldModel{}, false, &present);
  ASSERT_TRUE(r.parsed);
  EXPECT_EQ(CodesOf(r.response),
            (std::vector<std::string>{"TWINSIM_NOT_PRESENT", "TWINSIM_NOT_PRESENT", "TWINSIM_NOT_PRESENT"}));
  EXPECT_EQ(r.refused, 3);
  ASSERT_EQ(r.teleports.size(), 4u);
  EXPECT_EQ(r.teleports[0].robot, 1);
  EXPECT_EQ(r.teleports[0].present, std::optional<bool>(true));
  EXPECT_FLOAT_EQ(static_cast<float>(*r.teleports[0].y), -1.0f);
  EXPECT_EQ(r.teleports[1].robot, 1);
  EXPECT_FALSE(r.teleports[1].present.has_value());
  EXPECT_EQ(r.teleports[2].robot, 2);
  EXPECT_EQ(r.teleports[2].present, std::optional<bool>(false));
  EXPECT_EQ(r.teleports[3].robot, 0);
  EXPECT_TRUE(r.teleports[3].by_force);
  // Without presence flags every robot is on the field.
  const SimulatorCommandResult all = ReadSimulatorCommand(command.SerializeAsString(), roster, FieldModel{});
  EXPECT_EQ(CodesOf(all.response), (std::vector<std::string>{"TWINSIM_NOT_PRESENT"}));  // yellow 3 after its removal
}

TEST(SimulatorControl, BallMovesByForceAndSafelyAreRead) {
  const TeamRoster roster = TwoBlueOneYellow();
  SimulatorCommand command;
  TeleportBall* t = command.mutable_control()->mutable_teleport_ball();
  t->set_x(1.0f);
  t->set_by_force(true);
  t->set_teleport_safely(true);
  const SimulatorCommandResult r = ReadSimulatorCommand(command.SerializeAsString(), roster, FieldModel{}, true);
  EXPECT_EQ(r.refused, 0);
  ASSERT_TRUE(r.ball.has_value());
  EXPECT_TRUE(r.ball->by_force);
  EXPECT_TRUE(r.ball->safely);
}

TEST(SimulatorControl, ConfigTakesTheVisionPortAndCameraNoiseAndNamesWhatItRefuses) {
  const TeamRoster roster = TwoBlueOneYellow();
  SimulatorCommand command;
  SimulatorConfig* config = command.mutable_config();
  config->set_vision_port(10777);
  RealismConfigErForce realism_message;
  RealismConfigErForce* realism = &realism_message;
  realism->set_stddev_robot_p(0.002f);
  realism->set_stddev_robot_phi(0.01f);
  realism->set_stddev_ball_p(0.003f);
  realism->set_vision_delay(30000000);
  // The realism config as the protocol sends it: a google.protobuf.Any.
  auto pack = [&] {
    config->mutable_realism_config()->clear_custom();
    config->mutable_realism_config()->add_custom()->PackFrom(realism_message);
  };
  pack();
  const SimulatorCommandResult r = ReadSimulatorCommand(command.SerializeAsString(), roster, FieldModel{});
  EXPECT_EQ(r.config.vision_port, std::optional<int>(10777));
  EXPECT_FLOAT_EQ(static_cast<float>(r.config.robot_noise_xy.value_or(-1)), 0.002f);
  EXPECT_FLOAT_EQ(static_cast<float>(r.config.robot_noise_theta.value_or(-1)), 0.01f);
  // The ball's noise on a field without a ball: no ball; the vision delay: unsupported.
  ASSERT_EQ(CodesOf(r.response), (std::vector<std::string>{"TWINSIM_NO_BALL", "TWINSIM_UNSUPPORTED"}));
  EXPECT_NE(r.response.errors(0).message().find("config.realism_config.custom[0].stddev_ball_p"),
            std::string::npos)
      << r.response.errors(0).message();
  EXPECT_FALSE(r.config.ball_noise_xy.has_value());
  // With a ball, the ball's camera noise and missed detections are taken; a probability
  // over 1 is a bad value.
  realism->set_missing_ball_detections(0.25f);
  pack();
  const SimulatorCommandResult with_ball =
      ReadSimulatorCommand(command.SerializeAsString(), roster, FieldModel{}, /*has_ball=*/true);
  EXPECT_EQ(CodesOf(with_ball.response), (std::vector<std::string>{"TWINSIM_UNSUPPORTED"}));
  EXPECT_FLOAT_EQ(static_cast<float>(with_ball.config.ball_noise_xy.value_or(-1)), 0.003f);
  EXPECT_FLOAT_EQ(static_cast<float>(with_ball.config.ball_drop.value_or(-1)), 0.25f);
  realism->set_missing_ball_detections(1.5f);
  pack();
  const SimulatorCommandResult over =
      ReadSimulatorCommand(command.SerializeAsString(), roster, FieldModel{}, /*has_ball=*/true);
  EXPECT_EQ(CodesOf(over.response), (std::vector<std::string>{"TWINSIM_BAD_VALUE", "TWINSIM_UNSUPPORTED"}));
  EXPECT_FALSE(over.config.ball_drop.has_value());
  EXPECT_NE(r.response.errors(1).message().find("config.realism_config.custom[0].vision_delay"),
            std::string::npos)
      << r.response.errors(1).message();

  // Geometry and robot specs are named and refused; a port out of range and a negative
  // noise are bad values; nothing of them is taken.
  SimulatorCommand rest;
  SimulatorConfig* c = rest.mutable_config();
  *c->mutable_geometry() = GeometryPacket(FieldModel{}, 0.3).geometry();
  c->add_robot_specs()->mutable_id()->set_id(0);
  c->mutable_robot_specs(0)->mutable_id()->set_team(BLUE);
  c->set_vision_port(70000);
  RealismConfigErForce negative;
  negative.set_stddev_robot_p(-1);
  c->mutable_realism_config()->add_custom()->PackFrom(negative);
  const SimulatorCommandResult bad = ReadSimulatorCommand(rest.SerializeAsString(), roster, FieldModel{});
  ASSERT_TRUE(bad.parsed);
  EXPECT_EQ(CodesOf(bad.response), (std::vector<std::string>{"TWINSIM_UNSUPPORTED", "TWINSIM_UNSUPPORTED",
                                                             "TWINSIM_BAD_VALUE", "TWINSIM_BAD_VALUE"}));
  EXPECT_NE(bad.response.errors(0).message().find("config.geometry"), std::string::npos);
  EXPECT_NE(bad.response.errors(1).message().find("config.robot_specs"), std::string::npos);
  EXPECT_FALSE(bad.config.vision_port.has_value());
  EXPECT_FALSE(bad.config.robot_noise_xy.has_value());
  EXPECT_EQ(bad.refused, 4);
}

TEST(RobotControl, ARobotOffTheFieldIsRefusedAndTheOthersCommanded) {
  const TeamRoster roster = TwoBlueOneYellow();
  const std::vector<bool> present = {true, false, true};
  RobotControl control;
  for (unsigned id : {0u, 1u}) {
    RobotCommand* c = control.add_robot_commands();
    c->set_id(id);
    c->mutable_move_command()->mutable_local_velocity()->set_forward(1);
    c->mutable_move_command()->mutable_local_velocity()->set_left(0);
    c->mutable_move_command()->mutable_local_velocity()->set_angular(0);
  }
  const RobotControlResult r = ReadRobotControl(control.SerializeAsString(), TeamColor::kBlue, roster, nullptr, &present);
  ASSERT_EQ(r.response.errors_size(), 1);
  EXPECT_EQ(r.response.errors(0).code(), "TWINSIM_NOT_PRESENT");
  EXPECT_NE(r.response.errors(0).message().find("blue robot 1 is off the field"), std::string::npos);
  EXPECT_EQ(r.refused, 1);
  ASSERT_EQ(r.moves.size(), 1u);
  EXPECT_EQ(r.moves[0].first, 0);
  EXPECT_EQ(r.response.feedback_size(), 1);
}

// The fuzz target's seeds (tests/fuzz/corpus/serve_packet/, dispatched as
// fuzz/serve_packet_fuzz.cc does: the first byte picks the reader) are read here too, with
// every prefix, so that a reader that throws fails the ordinary suite; and the seeds for
// robots off the field, moves by force and configuration mean what they are named.
TEST(SimulatorControl, TheFuzzSeedsAreReadWithoutThrowing) {
  const TeamRoster roster({TeamRobot{TeamColor::kBlue, 0}, TeamRobot{TeamColor::kBlue, 1},
                           TeamRobot{TeamColor::kYellow, 0}, TeamRobot{TeamColor::kYellow, 3}});
  const FieldModel field;
  const std::vector<bool> contact = {true, false, false, true}, present = {true, true, true, false};
  auto read = [&](const std::string& datagram) -> std::vector<std::string> {
    const std::string bytes = datagram.substr(1);
    std::vector<std::string> codes;
    auto collect = [&](const auto& response) {
      for (const SimulatorError& e : response.errors()) codes.push_back(e.code());
    };
    switch (static_cast<unsigned char>(datagram[0]) % 5) {
      case 0: collect(ReadRobotControl(bytes, TeamColor::kBlue, roster).response); break;
      case 1: collect(ReadRobotControl(bytes, TeamColor::kYellow, roster, &contact, &present).response); break;
      case 2: collect(ReadSimulatorCommand(bytes, roster, field, false).response); break;
      case 3: collect(ReadSimulatorCommand(bytes, roster, field, true, &present).response); break;
      default: {
        const GrSimPacket packet = ReadGrSimPacket(bytes, [](TeamColor, unsigned id) { return id < 2 ? 0.027 : 0.0; });
        if (packet.commands) {
          collect(ReadRobotControl(packet.commands->SerializeAsString(), packet.team, roster, &contact, &present)
                      .response);
        }
        if (packet.replacement) {
          collect(ReadSimulatorCommand(packet.replacement->SerializeAsString(), roster, field, true, &present)
                      .response);
        }
        break;
      }
    }
    return codes;
  };
  const std::string dir = testing::SourcePath("tests/fuzz/corpus/serve_packet");
  std::map<std::string, std::vector<std::string>> codes;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string seed = testing::ReadText(entry.path().string());
    ASSERT_FALSE(seed.empty()) << entry.path();
    for (std::size_t n = 1; n < seed.size(); ++n) EXPECT_NO_THROW(read(seed.substr(0, n))) << entry.path() << " " << n;
    codes[entry.path().filename().string()] = read(seed);
  }
  ASSERT_EQ(codes.count("simulator_present"), 1u);
  EXPECT_EQ(codes["simulator_present"], std::vector<std::string>{});
  EXPECT_EQ(codes["simulator_by_force"], std::vector<std::string>{});
  // Geometry refused, the ball's camera noise on a field read without a ball, one more
  // realism field refused.
  EXPECT_EQ(codes["simulator_config"], (std::vector<std::string>{"TWINSIM_UNSUPPORTED", "TWINSIM_NO_BALL",
                                                                 "TWINSIM_UNSUPPORTED"}));
  EXPECT_EQ(codes["control_not_present"], std::vector<std::string>{"TWINSIM_NOT_PRESENT"});
  // grSim: yellow 0 on local velocity with a kick and the spinner, and wheels for
  // yellow 1 (blue's id); the replacement turns yellow 3 (off already) off, puts blue 0
  // at the centre and moves the ball, all accepted, with the same commands.
  EXPECT_EQ(codes["grsim_commands"], std::vector<std::string>{"TWINSIM_OTHER_TEAM"});
  EXPECT_EQ(codes["grsim_replacement"], std::vector<std::string>{"TWINSIM_OTHER_TEAM"});
}

}  // namespace
}  // namespace twinsim

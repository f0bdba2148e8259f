// The league's messages as the official ssl-simulation-protocol files number them,
// written and read here byte by byte from those numbers, not from the project's
// generated code (issue 43): a team whose bindings come from the official files sends
// these bytes and parses the answers this way.
//   RobotControl          robot_commands = 1
//   RobotCommand          id = 1 (uint32), move_command = 2
//   RobotMoveCommand      local_velocity = 2
//   MoveLocalVelocity     forward = 1, left = 2, angular = 3 (float)
//   RobotControlResponse  errors = 1, feedback = 2
//   RobotFeedback         id = 1 (uint32, required), dribbler_ball_contact = 2
//   SimulatorError        code = 1, message = 2 (strings)
//   SimulatorCommand      control = 1, config = 2
//   SimulatorConfig       realism_config = 3, vision_port = 4
//   RealismConfig         custom = 1 (repeated google.protobuf.Any: type_url = 1, value = 2)
//   RealismConfigErForce  stddev_robot_p = 2, stddev_robot_phi = 3 (float), vision_delay = 13 (int64)
//   SimulatorResponse     errors = 1
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "serve/protobuf_wire.h"
#include "serve/robot_control.h"
#include "serve/simulator_control.h"

namespace twinsim {
namespace {

using testing::BytesField;
using testing::FloatField;
using testing::Varint;
using testing::VarintField;

// One field of a message as it comes off the wire.
struct WireField {
  int number = 0;
  int wire = 0;
  std::uint64_t varint = 0;  // wire 0
  std::string bytes;         // wire 2
};

// The fields of `message`, in order; fails the test on bytes that are not protobuf.
std::vector<WireField> Fields(const std::string& message) {
  std::vector<WireField> out;
  std::size_t i = 0;
  auto varint = [&]() {
    std::uint64_t v = 0;
    for (int shift = 0; i < message.size(); shift += 7) {
      const auto b = static_cast<unsigned char>(message[i++]);
      v |= static_cast<std::uint64_t>(b & 0x7f) << shift;
      if (!(b & 0x80)) return v;
    }
    ADD_FAILURE() << "a varint runs past the end";
    return v;
  };
  while (i < message.size()) {
    const std::uint64_t key = varint();
    WireField f;
    f.number = static_cast<int>(key >> 3);
    f.wire = static_cast<int>(key & 7);
    if (f.wire == 0) {
      f.varint = varint();
    } else if (f.wire == 2) {
      const std::uint64_t n = varint();
      f.bytes = message.substr(i, n);
      i += n;
    } else if (f.wire == 5) {
      i += 4;
    } else if (f.wire == 1) {
      i += 8;
    } else {
      ADD_FAILURE() << "wire type " << f.wire;
      return out;
    }
    out.push_back(f);
  }
  return out;
}

// The errors of an answer (RobotControlResponse or SimulatorResponse: field 1), each as
// (code, message).
std::vector<std::pair<std::string, std::string>> Errors(const std::string& answer) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const WireField& f : Fields(answer)) {
    if (f.number != 1) continue;
    EXPECT_EQ(f.wire, 2);
    std::pair<std::string, std::string> e;
    for (const WireField& g : Fields(f.bytes)) {
      EXPECT_EQ(g.wire, 2) << "SimulatorError's fields are strings";
      if (g.number == 1) e.first = g.bytes;
      if (g.number == 2) e.second = g.bytes;
      EXPECT_LE(g.number, 2) << "SimulatorError has code = 1 and message = 2 only";
    }
    out.push_back(e);
  }
  return out;
}

TeamRoster Roster() { return TeamRoster({TeamRobot{TeamColor::kBlue, 0}, TeamRobot{TeamColor::kBlue, 1}}); }

std::string LocalMove(unsigned id, float forward, float left, float angular) {
  const std::string velocity = FloatField(1, forward) + FloatField(2, left) + FloatField(3, angular);
  return BytesField(1, VarintField(1, id) + BytesField(2, BytesField(2, velocity)));
}

TEST(OfficialWire, ARobotControlAnswerCarriesPlainIdsAndStringErrors) {
  const std::string bytes = LocalMove(1, 1.5f, -0.5f, 2.0f) + LocalMove(9, 1, 0, 0);
  const RobotControlResult r = ReadRobotControl(bytes, TeamColor::kBlue, Roster());
  ASSERT_EQ(r.moves.size(), 1u);
  EXPECT_FLOAT_EQ(static_cast<float>(r.moves[0].second.velocity.vx), 1.5f);
  const std::string answer = r.response.SerializeAsString();
  std::vector<std::uint64_t> ids;
  for (const WireField& f : Fields(answer)) {
    if (f.number != 2) continue;
    for (const WireField& g : Fields(f.bytes)) {
      if (g.number != 1) continue;
      EXPECT_EQ(g.wire, 0) << "RobotFeedback.id is a uint32 varint, not a message";
      ids.push_back(g.varint);
    }
  }
  EXPECT_EQ(ids, (std::vector<std::uint64_t>{1}));
  const auto errors = Errors(answer);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].first, "TWINSIM_UNKNOWN_ROBOT");
  EXPECT_NE(errors[0].second.find("no blue robot 9"), std::string::npos) << errors[0].second;
}

std::string Realism(const std::string& type_url, const std::string& value, unsigned port) {
  const std::string any = BytesField(1, type_url) + BytesField(2, value);
  const std::string config = BytesField(3, BytesField(1, any)) + VarintField(4, port);
  return BytesField(2, config);
}

TEST(OfficialWire, TheRealismConfigIsAnAnyHoldingTheErForceMessage) {
  const std::string erforce = FloatField(2, 0.002f) + FloatField(3, 0.01f);
  const SimulatorCommandResult r =
      ReadSimulatorCommand(Realism("type.googleapis.com/RealismConfigErForce", erforce, 10777), Roster(), FieldModel{});
  ASSERT_TRUE(r.parsed);
  EXPECT_EQ(r.refused, 0);
  EXPECT_EQ(r.config.vision_port, std::optional<int>(10777));
  EXPECT_FLOAT_EQ(static_cast<float>(r.config.robot_noise_xy.value_or(-1)), 0.002f);
  EXPECT_FLOAT_EQ(static_cast<float>(r.config.robot_noise_theta.value_or(-1)), 0.01f);
  EXPECT_TRUE(Errors(r.response.SerializeAsString()).empty());

  // A field of it twinsim does not model (vision_delay, 13, int64): named and refused.
  const SimulatorCommandResult delay = ReadSimulatorCommand(
      Realism("type.googleapis.com/RealismConfigErForce", erforce + VarintField(13, 30000000), 10777), Roster(),
      FieldModel{});
  auto errors = Errors(delay.response.SerializeAsString());
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].first, "TWINSIM_UNSUPPORTED");
  EXPECT_NE(errors[0].second.find("config.realism_config.custom[0].vision_delay"), std::string::npos)
      << errors[0].second;

  // Another simulator's realism message: refused naming its type.
  const SimulatorCommandResult other =
      ReadSimulatorCommand(Realism("type.googleapis.com/grsim.Realism", "", 10777), Roster(), FieldModel{});
  errors = Errors(other.response.SerializeAsString());
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].first, "TWINSIM_UNSUPPORTED");
  EXPECT_NE(errors[0].second.find("type.googleapis.com/grsim.Realism"), std::string::npos) << errors[0].second;
  EXPECT_EQ(other.config.vision_port, std::optional<int>(10777));  // the rest of the config is taken

  // The right type with bytes that are not it: malformed.
  const SimulatorCommandResult broken =
      ReadSimulatorCommand(Realism("type.googleapis.com/RealismConfigErForce", "\xff\xff", 10777), Roster(), FieldModel{});
  errors = Errors(broken.response.SerializeAsString());
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].first, "TWINSIM_MALFORMED");
}

}  // namespace
}  // namespace twinsim

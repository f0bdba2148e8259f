#include "serve/simulator_control.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include <google/protobuf/any.pb.h>
#include <google/protobuf/descriptor.h>

#include "serve/robot_control.h"
#include "ssl_simulation_custom_erforce_realism.pb.h"

namespace twinsim {

Pose2 TeleportedPose(const RobotTeleport& t, const Pose2& current) {
  return Pose2{t.x.value_or(current.x), t.y.value_or(current.y), WrapAngle(t.theta.value_or(current.theta))};
}

BallState TeleportedBall(const BallTeleport& t, const BallState& current, double radius) {
  BallState b = current;
  if (t.x) b.position.x() = *t.x;
  if (t.y) b.position.y() = *t.y;
  b.position.z() = std::max(radius, t.z.value_or(radius));
  b.velocity = Eigen::Vector3d(t.vx.value_or(0), t.vy.value_or(0), t.vz.value_or(0));
  // Rolling: the spin that matches the velocity on the floor, w = z x v / r.
  b.spin = Eigen::Vector3d::Zero();
  if (t.roll) b.spin = Eigen::Vector3d(-b.velocity.y(), b.velocity.x(), 0) / radius;
  return b;
}

namespace {

// The camera noise twinsim serve takes from a RealismConfigErForce; every other field of
// it is refused by name.
constexpr double kMaxNoiseXy = 1;       // m, stddev_robot_p and stddev_ball_p beyond are refused
constexpr double kMaxNoiseTheta = 3.2;  // rad, stddev_robot_phi

using Refuse = std::function<void(const std::string& code, const std::string& message)>;

// The camera's noise on the robots (the models' vision.noise_xy, noise_theta) and on the
// ball (the scene's ball.vision), and the chance of a frame without the ball, from one
// realism message into *config; `at` names it in errors ("config.realism_config.custom[0].").
void TakeRealism(const RealismConfigErForce& realism, const std::string& at, bool has_ball, const Refuse& refuse,
                 ConfigChange* config) {
  auto take = [&](bool has, double v, const char* name, double most, const char* unit, bool of_ball,
                  std::optional<double>* out) {
    if (!has) return;
    if (of_ball && !has_ball) {
      refuse("TWINSIM_NO_BALL", at + name + ": the scene has no ball");
    } else if (std::isfinite(v) && v >= 0 && v <= most) {
      *out = v;
    } else {
      refuse("TWINSIM_BAD_VALUE", at + name + " " + std::to_string(v) + unit + " is not in 0.." + std::to_string(most));
    }
  };
  take(realism.has_stddev_robot_p(), realism.stddev_robot_p(), "stddev_robot_p", kMaxNoiseXy, " m", false,
       &config->robot_noise_xy);
  take(realism.has_stddev_robot_phi(), realism.stddev_robot_phi(), "stddev_robot_phi", kMaxNoiseTheta, " rad", false,
       &config->robot_noise_theta);
  take(realism.has_stddev_ball_p(), realism.stddev_ball_p(), "stddev_ball_p", kMaxNoiseXy, " m", true,
       &config->ball_noise_xy);
  take(realism.has_missing_ball_detections(), realism.missing_ball_detections(), "missing_ball_detections", 1, "", true,
       &config->ball_drop);
  // Every other realism setting (delays, losses of commands and answers, ...) is named
  // and refused.
  static const char* const kTaken[] = {"stddev_robot_p", "stddev_robot_phi", "stddev_ball_p", "missing_ball_detections"};
  std::vector<const google::protobuf::FieldDescriptor*> fields;
  realism.GetReflection()->ListFields(realism, &fields);
  for (const google::protobuf::FieldDescriptor* f : fields) {
    if (std::find(std::begin(kTaken), std::end(kTaken), f->name()) != std::end(kTaken)) continue;
    refuse("TWINSIM_UNSUPPORTED", at + f->name() + ": not supported; the camera takes stddev_robot_p, "
                                  "stddev_robot_phi, stddev_ball_p and missing_ball_detections only");
  }
}

}  // namespace

SimulatorCommandResult ReadSimulatorCommand(const std::string& bytes, const TeamRoster& roster, const FieldModel& field,
                                            bool has_ball, const std::vector<bool>* present) {
  SimulatorCommandResult result;
  SimulatorCommand command;
  if (!command.ParseFromString(bytes)) {
    AddError(&result.response, "TWINSIM_MALFORMED",
             "the datagram of " + std::to_string(bytes.size()) + " bytes is not a SimulatorCommand");
    return result;
  }
  result.parsed = true;
  auto refuse = [&](const std::string& code, const std::string& message) {
    ++result.refused;
    AddError(&result.response, code, message);
  };
  if (command.has_config()) {
    const SimulatorConfig& config = command.config();
    if (config.has_geometry())
      refuse("TWINSIM_UNSUPPORTED", "config.geometry: the field's size and walls come from the scene file (field:) and "
                                    "cannot change while it is served");
    if (config.robot_specs_size() > 0)
      refuse("TWINSIM_UNSUPPORTED", "config.robot_specs: the robots' bodies, wheels and limits come from their model "
                                    "files (the scene's model:) and cannot change while it is served");
    if (config.has_vision_port()) {
      const unsigned port = config.vision_port();
      if (port >= 1 && port <= 65535) {
        result.config.vision_port = static_cast<int>(port);
      } else {
        refuse("TWINSIM_BAD_VALUE", "config.vision_port " + std::to_string(port) + " is not in 1..65535");
      }
    }
    if (config.has_realism_config()) {
      // Each payload an Any: the ER-Force realism message is taken, anything else named
      // and refused.
      const RealismConfig& realism_config = config.realism_config();
      for (int k = 0; k < realism_config.custom_size(); ++k) {
        const google::protobuf::Any& any = realism_config.custom(k);
        const std::string at = "config.realism_config.custom[" + std::to_string(k) + "]";
        RealismConfigErForce realism;
        if (!any.Is<RealismConfigErForce>()) {
          refuse("TWINSIM_UNSUPPORTED", at + ": '" + any.type_url() +
                                            "' is not a realism config twinsim knows (type.googleapis.com/"
                                            "RealismConfigErForce, the protocol's proto/erforce/)");
        } else if (!any.UnpackTo(&realism)) {
          refuse("TWINSIM_MALFORMED", at + ": its value is not a RealismConfigErForce");
        } else {
          TakeRealism(realism, at + ".", has_ball, refuse, &result.config);
        }
      }
    }
  }
  if (!command.has_control()) return result;
  const SimulatorControl& control = command.control();
  if (control.has_teleport_ball()) {
    const TeleportBall& t = control.teleport_ball();
    BallTeleport ball;
    if (t.has_x()) ball.x = t.x();
    if (t.has_y()) ball.y = t.y();
    if (t.has_z()) ball.z = t.z();
    if (t.has_vx()) ball.vx = t.vx();
    if (t.has_vy()) ball.vy = t.vy();
    if (t.has_vz()) ball.vz = t.vz();
    ball.roll = t.roll();
    ball.by_force = t.by_force();
    ball.safely = t.teleport_safely();
    const Eigen::Vector3d v(ball.vx.value_or(0), ball.vy.value_or(0), ball.vz.value_or(0));
    const bool finite = std::isfinite(ball.x.value_or(0)) && std::isfinite(ball.y.value_or(0)) &&
                        std::isfinite(ball.z.value_or(0)) && v.allFinite();
    if (!has_ball) {
      refuse("TWINSIM_NO_BALL", "teleport_ball: the field has no ball (the scene has no `ball:`)");
    } else if (!finite || std::abs(ball.x.value_or(0)) >= field.length / 2 ||
               std::abs(ball.y.value_or(0)) >= field.width / 2 || ball.z.value_or(0) < 0 || ball.z.value_or(0) > 10 ||
               v.norm() > kMaxKickSpeed) {
      refuse("TWINSIM_BAD_VALUE", "teleport_ball: the place is not finite or outside the " +
                                      std::to_string(field.length) + " x " + std::to_string(field.width) +
                                      " m field (z in 0..10 m), or the velocity not finite or beyond " +
                                      std::to_string(kMaxKickSpeed) + " m/s");
    } else {
      result.ball = ball;
    }
  }
  if (control.has_simulation_speed()) {
    const double speed = control.simulation_speed();
    if (std::isfinite(speed) && speed >= 0.01 && speed <= 100) {
      result.simulation_speed = speed;
    } else {
      refuse("TWINSIM_BAD_VALUE", "simulation_speed " + std::to_string(speed) + " is not in 0.01..100");
    }
  }
  // Who is on the field, as the teleports read so far leave it.
  std::vector<bool> on_field = present ? *present : std::vector<bool>(static_cast<std::size_t>(roster.size()), true);
  on_field.resize(static_cast<std::size_t>(roster.size()), true);
  for (const TeleportRobot& t : control.teleport_robot()) {
    const bool yellow = t.id().team() == YELLOW;
    if (t.id().team() != YELLOW && t.id().team() != BLUE) {
      refuse("TWINSIM_UNKNOWN_ROBOT", "teleport_robot: the robot id names no team (blue or yellow)");
      continue;
    }
    const TeamColor team = yellow ? TeamColor::kYellow : TeamColor::kBlue;
    const std::string robot = std::string(TeamName(team)) + " robot " + std::to_string(t.id().id());
    const int index = roster.Find(team, t.id().id());
    if (index < 0) {
      refuse("TWINSIM_UNKNOWN_ROBOT", "teleport_robot: no " + robot + " on the field");
      continue;
    }
    const auto k = static_cast<std::size_t>(index);
    RobotTeleport teleport;
    teleport.robot = index;
    if (t.has_present() && !t.present()) {
      // Removed: where and how fast do not matter.
      teleport.present = false;
      on_field[k] = false;
      result.teleports.push_back(teleport);
      continue;
    }
    if (t.has_present()) teleport.present = true;
    teleport.by_force = t.by_force();
    if (!on_field[k] && !t.has_present()) {
      refuse("TWINSIM_NOT_PRESENT", "teleport_robot " + robot + ": the robot is off the field; send present: true "
                                    "to add it");
      continue;
    }
    if (!on_field[k] && teleport.by_force) {
      refuse("TWINSIM_NOT_PRESENT", "teleport_robot " + robot + ": the robot is off the field and cannot be moved "
                                    "by force; add it without by_force");
      continue;
    }
    if (t.has_x()) teleport.x = t.x();
    if (t.has_y()) teleport.y = t.y();
    if (t.has_orientation()) teleport.theta = t.orientation();
    teleport.field_velocity = Twist2{t.v_x(), t.v_y(), t.v_angular()};
    const bool finite = std::isfinite(teleport.x.value_or(0)) && std::isfinite(teleport.y.value_or(0)) &&
                        std::isfinite(teleport.theta.value_or(0)) && IsFinite(teleport.field_velocity);
    const bool inside = std::abs(teleport.x.value_or(0)) < field.length / 2 &&
                        std::abs(teleport.y.value_or(0)) < field.width / 2;
    const bool slow = std::hypot(teleport.field_velocity.vx, teleport.field_velocity.vy) <= kMaxCommandSpeed &&
                      std::abs(teleport.field_velocity.omega) <= kMaxCommandOmega;
    if (!finite || !inside || !slow) {
      refuse("TWINSIM_BAD_VALUE", "teleport_robot " + robot + ": the place is not finite or outside the " +
                                      std::to_string(field.length) + " x " + std::to_string(field.width) +
                                      " m field, or the velocity not finite or beyond the command limits");
      continue;
    }
    on_field[k] = true;
    result.teleports.push_back(teleport);
  }
  return result;
}

}  // namespace twinsim

// The ball of a Small Size League field: a solid sphere that slides, rolls, bounces and
// flies (docs/ball.md). A BallModel is its static description, read from a scene's
// `ball:` section (docs/scenes.md) and validated once; BallState is all that changes.
//
//   BallModel ball;                               // the league's ball: 21.5 mm, 46 g
//   ball.rolling_friction = 0.05;                 // a rolling ball slows at 5/7 * 0.05 * g
//   std::string why; if (!ball.IsValid(&why)) ...
#pragma once

#include <Eigen/Core>
#include <string>

#include <yaml-cpp/yaml.h>

#include "io/yaml_reader.h"

namespace twinsim {

struct BallModel {
  double radius = 0.0215;          // m (the league's golf ball)
  double mass = 0.046;             // kg
  double sliding_friction = 0.35;  // 1, Coulomb coefficient against the floor while it slides
  // 1: a torque rolling_friction * N * radius opposes the roll (N the normal force), so a
  // rolling ball slows at 5/7 * rolling_friction * g on a level floor.
  double rolling_friction = 0.05;
  double restitution = 0.5;        // 1, bounce off robots and walls (normal speed ratio)
  double floor_restitution = 0.5;  // 1, bounce off the floor
  double robot_friction = 0.3;     // 1, Coulomb coefficient against robots and walls
  // 1: air drag coefficient C_d, the force -1/2 rho C_d pi r^2 |v| v (rho 1.2 kg/m^3);
  // 0.47 is a smooth sphere's, 0 switches drag off.
  double drag = 0.47;

  // Moment of inertia of a solid sphere, 2/5 m r^2 (kg m^2).
  double inertia() const { return 0.4 * mass * radius * radius; }
  // False, with every problem in *why, for values out of range.
  bool IsValid(std::string* why) const;
};

inline constexpr double kAirDensity = 1.2;  // kg/m^3

// How the camera sees the ball (a scene's `ball.vision`): Gaussian noise on the
// captured centre and a chance of losing the ball in a frame (then no ball is
// delivered for it). The defaults see it exactly, every frame.
struct BallVision {
  double noise_xy = 0;          // m, standard deviation along x and along y
  double noise_z = 0;           // m, standard deviation of the height
  double drop_probability = 0;  // per frame
  bool any() const { return noise_xy > 0 || noise_z > 0 || drop_probability > 0; }
};

// Everything that changes about the ball, field frame.
struct BallState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m, the centre (z = radius: on the floor)
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // m/s
  Eigen::Vector3d spin = Eigen::Vector3d::Zero();      // rad/s, angular velocity
};

// Reads the ball's parameters from the keys of `m` (radius, mass, sliding_friction,
// rolling_friction, restitution, floor_restitution, robot_friction, drag), each checked
// for its range; problems go to m's error list with file:line:column. Leaves other keys
// for the caller, who calls m.Finish().
void ReadBallModel(YamlMap& m, BallModel* ball);

}  // namespace twinsim

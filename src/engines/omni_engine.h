// A physics engine that simulates omni robots on a field at the level of wheel torques.
//
// This is the seam between twinsim and ODE, Bullet or the analytic rigid-body model.
// An engine knows bodies, joints and contacts only; the on-board controller, motors,
// encoders and the delay loop live above it (NewtonianOmniBackend, Simulation), so every
// engine sees exactly the same torques at exactly the same times. Engines' own types
// (dReal, btVector3) stay inside their folder.
//
// Frames: the field frame has z up, the floor is the plane z = 0. Robot i's pose is its
// chassis centre projected on the floor and its yaw. Body velocities are in the robot
// frame (x forward, y left). Wheel conventions are those of omni_model.h.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/pose.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

// The field: a floor with walls around it, level unless it slopes.
struct FieldModel {
  double length = 10.4;       // m, inside the walls along field x
  double width = 7.4;         // m, inside the walls along field y
  double wall_height = 0.1;   // m
  double wall_thickness = 0.05;  // m
  bool walls = true;
  // A floor that slopes by `slope` rad, downhill towards `slope_direction` rad (field
  // frame). The engines tilt gravity instead of the floor: on a plane the same forces,
  // and the field's coordinates stay those of the floor.
  double slope = 0;
  double slope_direction = 0;

  // The four walls as boxes standing on the floor, each {centre x, centre y, size x,
  // size y} (m, wall_height tall); the walls along x reach over the corners.
  std::array<std::array<double, 4>, 4> WallBoxes() const {
    const double t = wall_thickness, half_l = 0.5 * length, half_w = 0.5 * width;
    return {{{half_l + 0.5 * t, 0, t, width + 2 * t},
             {-half_l - 0.5 * t, 0, t, width + 2 * t},
             {0, half_w + 0.5 * t, length + 2 * t, t},
             {0, -half_w - 0.5 * t, length + 2 * t, t}}};
  }

  // Gravity (m/s^2) in the floor's frame: (g sin s cos d, g sin s sin d, -g cos s).
  Eigen::Vector3d Gravity() const {
    return kGravity * Eigen::Vector3d(std::sin(slope) * std::cos(slope_direction),
                                      std::sin(slope) * std::sin(slope_direction), -std::cos(slope));
  }
};

// Where an engine whose wheels cannot slip (the analytic model) leaves its validity: the
// steps on which some wheel needed a contact force (its rolling force and the rollers'
// friction together) beyond wheel_friction times its static load. There a real robot,
// ODE and Bullet slip; the model goes on rolling.
struct GripCheck {
  long steps = 0;     // robot-steps checked (0: the engine does not check, it slips)
  long beyond = 0;    // robot-steps on which a wheel needed more grip than it has
  double worst = 0;   // the largest force over grip seen (above 1 where beyond > 0)
  GripCheck& operator+=(const GripCheck& other) {
    steps += other.steps;
    beyond += other.beyond;
    worst = std::max(worst, other.worst);
    return *this;
  }
};

// A pass of the grip worth a word: some step needing this many times the grip, or this
// share of the steps needing more than it.
inline constexpr double kGripWorthSaying = 1.05;
inline constexpr double kGripShareWorthSaying = 0.01;

// Empty when nothing passed the grip by what is worth a word (above); else one sentence
// for the user: on what share of the steps the analytic model's wheels needed more grip
// than they have, and what to do.
std::string DescribeGrip(const GripCheck& grip);

// Everything that changes about one robot's bodies, enough to put it back exactly.
struct OmniBodyState {
  Pose2 pose;                  // field frame
  Twist2 velocity;             // robot frame
  Eigen::VectorXd wheel_speeds;  // n, rad/s relative to the chassis (about a_i)
};

class OmniEngine {
 public:
  virtual ~OmniEngine() = default;
  virtual std::string name() const = 0;
  virtual int num_robots() const = 0;

  // Places robot i: chassis on the floor at `state.pose`, moving with `state.velocity`
  // (robot frame), wheels spinning at `state.wheel_speeds` and level, contact caches
  // cleared. After SetState the engine must behave as if freshly built in that state.
  virtual void SetState(int robot, const OmniBodyState& state) = 0;
  virtual OmniBodyState GetState(int robot) const = 0;

  // Robot i's wheel speeds (rad/s about a_i, relative to the chassis) into *out (n):
  // what GetState() returns, without the rest, for the per-step encoder read.
  virtual void GetWheelSpeeds(int robot, Eigen::VectorXd* out) const { *out = GetState(robot).wheel_speeds; }
  // Robot i's pose and velocity: what GetState() returns without its wheel speeds, for
  // the reads of every frame and step (an engine whose state is planar overrides it and
  // allocates nothing).
  virtual Pose2 GetPose(int robot) const { return GetState(robot).pose; }
  virtual Twist2 GetVelocity(int robot) const { return GetState(robot).velocity; }

  // Moves robot i rigidly in the plane so that its pose becomes `pose`: every body keeps
  // its height, tilt, spin and contact state, velocities turn with it. (The default
  // levels the robot through SetState; engines with 3D state override it.)
  virtual void MoveRobot(int robot, const Pose2& pose) {
    OmniBodyState s = GetState(robot);
    s.pose = pose;
    SetState(robot, s);
  }

  // Every number of robot i's bodies (3D poses and velocities of chassis and wheels),
  // opaque to callers, so that RestoreExact() puts the robot back bit for bit where
  // SetState() would only level it on the floor. Engines whose planar state is the
  // whole state return an empty vector.
  virtual std::vector<double> SaveExact(int robot) const { return {}; }
  // Restores what SaveExact() returned (after a SetState() to the same planar state).
  virtual void RestoreExact(int robot, const std::vector<double>& snapshot) {}

  // Net torque on each wheel's hinge for the next Step() (N·m, about a_i; the reaction
  // acts on the chassis). Holds until changed.
  virtual void SetWheelTorques(int robot, const Eigen::VectorXd& torques) = 0;

  // Advances the world by dt seconds.
  virtual void Step(double dt) = 0;
  // Every step's grip since construction (SetState and RestoreExact leave it): an
  // engine that cannot slip checks itself; those that slip return steps = 0.
  virtual GripCheck grip() const { return {}; }
};

// Builds the engine called `name` ("analytic", "ode", "bullet") for the given robots.
// Throws InputError when the name is unknown or the engine was not compiled in.
std::unique_ptr<OmniEngine> MakeOmniEngine(const std::string& name,
                                           const std::vector<OmniModel>& robots,
                                           const FieldModel& field);
// Names of the engines compiled into this build.
std::vector<std::string> AvailableOmniEngines();

}  // namespace twinsim

// A physics engine for the ball (ODE or Bullet): a sphere on the floor, inside the
// field's walls, among the robots' chassis (docs/ball.md).
//
// The robots are kinematic bodies here: each is the chassis cylinder cut by its flat
// front (OmniModel::FrontDistance), placed every step where the robots' own engine has
// put it and moving with its velocity. The ball bounces and slides off them, they never
// feel the ball (one-way coupling: a 46 g ball against a 2.5 kg robot; docs/ball.md
// measures the impulse this leaves out). So the ball runs beside any robot backend
// (ode, bullet, analytic, learned) and never changes how the robots move.
//
// Like OmniEngine, a BallEngine knows bodies and contacts only: kicks, the dribbler,
// rolling resistance and drag are forces and velocities set from above
// (sim/ball_field.h). Engines' own types stay inside their folder.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "core/pose.h"
#include "engines/omni_engine.h"
#include "robots/omni/ball_model.h"
#include "robots/omni/omni_model.h"

namespace twinsim {

class BallEngine {
 public:
  virtual ~BallEngine() = default;
  virtual std::string name() const = 0;

  // Puts the ball at `state`, contact caches cleared: after SetBall the engine behaves as
  // if freshly built in that state.
  virtual void SetBall(const BallState& state) = 0;
  virtual BallState GetBall() const = 0;

  // Places robot i's chassis at `pose` moving at `velocity` (field frame: m/s, m/s,
  // rad/s) for the next Step.
  virtual void SetRobot(int robot, const Pose2& pose, const Twist2& velocity) = 0;

  // A force (N, through the centre) and a torque (N·m) on the ball during the next Step
  // only.
  virtual void AddBallForce(const Eigen::Vector3d& force, const Eigen::Vector3d& torque) = 0;

  // Advances the ball by dt seconds.
  virtual void Step(double dt) = 0;
};

// The chassis' outline seen from above, robot frame, counter-clockwise (m, k x 2): the
// circle of chassis_radius as a polygon of `arc_segments` pieces, cut by the flat front
// at x = FrontDistance(). Both engines build the robots' shape from it.
std::vector<Eigen::Vector2d> ChassisOutline(const OmniModel& model, int arc_segments = 48);

// Builds the ball engine called `name` ("ode", "bullet") for a ball among `robots` on
// `field`. Throws InputError when the name is unknown or the engine was not compiled.
std::unique_ptr<BallEngine> MakeBallEngine(const std::string& name, const BallModel& ball,
                                           const std::vector<OmniModel>& robots, const FieldModel& field);
// Names of the ball engines compiled into this build.
std::vector<std::string> AvailableBallEngines();

}  // namespace twinsim

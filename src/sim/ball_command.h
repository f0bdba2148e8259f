// What a robot does to the ball besides driving (the league's RobotCommand: kick_speed,
// kick_angle, dribbler_speed), as the loop (sim/omni_simulation.h) delays it and the
// ball field (sim/ball_field.h) acts on it.
#pragma once

namespace twinsim {

// What a robot does to the ball, besides driving (the league's RobotCommand).
struct BallCommand {
  double kick_speed = 0;      // m/s, the ball's speed just after the kick (3-D); 0: no kick
  double kick_angle = 0;      // rad above the floor; 0: a flat kick, > 0: a chip
  double dribbler_speed = 0;  // rpm; > 0: the dribbler pulls the ball
};

}  // namespace twinsim

// The learned model's inputs and outputs (seed 000, section 4).
//
// Inputs at frame i: the last `history` = 6 frames j = i-5..i, each as 7 numbers:
//   the pose of frame j relative to frame i, in the robot frame of frame i (dx, dy, m),
//   the heading difference as sin and cos (stored as cos - 1, so that a robot standing
//   still with zero commands has all-zero inputs), and the command acting at frame j
//   (vx, vy, omega in the robot's frame at the time it was sent).
// 6 x 7 = 42 inputs, as the seed has. The command "at" a frame is the one that acts on
// the robot then: the one logged D = command + vision delay frames earlier (the model's
// delay, stored in the layout). So a predictor learns the robot's dynamics, and the
// loop adds the delay exactly as for ODE and Bullet. For a horizon H > 1 the commands
// acting at frames i+1..i+H-1 follow (3 more numbers each): when H <= D they were all
// sent by frame i, so a behaviour can "predict away the delay" with what it knows.
//
// Output: the pose of frame i+H relative to frame i in the robot frame of frame i
// (dx m, dy m, dtheta rad).
//
// A residual predictor (learning/omni_residual.h) has further inputs after those, from
// the Newtonian model it corrects, carried along the poses: the model's own prediction
// of the pose change over the horizon (3, robot frame of frame i), its velocity at frame
// i (3, robot frame), and its last `nominal_errors` one-frame errors (3 each: measured
// pose minus the model's prediction of it, dx and dy rotated into the robot frame of
// frame i, dtheta; oldest first). Its output is the correction to the model's
// prediction: the pose change minus the model's.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/pose.h"
#include "robots/omni/omni_log.h"

namespace twinsim {

struct FeatureLayout {
  int history = 6;      // frames of history
  int horizon = 1;      // H, frames ahead
  int command_lag = 4;  // D, frames from logging a command to it acting
  bool residual = false;   // inputs from the Newtonian model follow; the output corrects it
  int nominal_errors = 0;  // residual only: the model's recent one-frame errors in the inputs

  static constexpr int kPerFrame = 7;
  static constexpr int kNumOutputs = 3;
  int num_seed_inputs() const { return kPerFrame * history + 3 * (horizon - 1); }
  int num_inputs() const { return num_seed_inputs() + (residual ? 6 + 3 * nominal_errors : 0); }
  int num_commands() const { return history + horizon - 1; }
};

// Writes the inputs into out (num_inputs()). poses: `history` poses, oldest first, the
// last is frame i. commands: num_commands() commands acting at frames i-history+1 ..
// i+H-1.
void EncodeInputs(const FeatureLayout& layout, const Pose2* poses, const Twist2* commands, double* out);

// Writes a residual predictor's inputs into out (num_inputs() numbers, see above): the
// seed's from `poses` and `commands` (as EncodeInputs), then its nominal model's:
// `nominal_end` is the model's prediction of the pose H frames after poses[history - 1],
// `nominal_velocity` its velocity there (robot frame), `errors` its recent errors (field
// frame, oldest first; the last nominal_errors are used). Returns the model's pose change
// (robot frame of poses[history - 1]), which the predictor's output corrects.
Eigen::Vector3d EncodeResidualInputs(const FeatureLayout& layout, const Pose2* poses, const Twist2* commands,
                                     const Pose2& nominal_end, const Twist2& nominal_velocity,
                                     const std::vector<Eigen::Vector3d>& errors, double* out);

// The pose change from `now` to `later` in the robot frame of `now` (dx, dy, dtheta).
Eigen::Vector3d EncodeDelta(const Pose2& now, const Pose2& later);
// The pose `delta` (robot frame of `now`) away from `now`.
Pose2 ApplyDelta(const Pose2& now, const Eigen::Vector3d& delta);

// Training samples: x (N x num_inputs), y (N x 3), in time order.
struct OmniDataset {
  Eigen::MatrixXd x;
  Eigen::MatrixXd y;
  int rows() const { return static_cast<int>(x.rows()); }
};

// A log laid out by frame index: poses and the command acting at each frame (logged
// `command_lag` frames earlier; unknown before that). A frame the camera did not measure
// (a lost frame, a repeated pose) holds the pose interpolated in time between the
// measured frames around it (held after the last), as a tracker would carry it.
struct FrameSequence {
  // Lost frames a training window may hold among its `history` (interpolated, as above);
  // its newest frame and its target are always measured. Real cameras lose one frame in
  // a few: windows of only measured frames left 34 of 3210 rows of a real SSL log.
  static constexpr int kMaxLostInWindow = 2;

  std::vector<Pose2> pose;
  std::vector<bool> observed;
  std::vector<Twist2> acting;
  int first_known_command = 0;  // the first frame whose acting command is in the log
  int frames() const { return static_cast<int>(pose.size()); }
  // True when frames [from, to] are all observed.
  bool Complete(int from, int to) const;
  // True when frames [from, to] may form a window: `to` and `from` observed, at most
  // kMaxLostInWindow frames between them not.
  bool Usable(int from, int to) const;
  // Frames a sample may use (its window and its target); empty: every frame. A caller
  // that holds rows out (the diagnosis's test blocks) leaves them out here, while the
  // frames around them still carry a residual predictor's nominal track along the log.
  std::vector<char> sampled;
  // True when frames [from, to] may all be used by a sample.
  bool Sampled(int from, int to) const;
};
FrameSequence ToFrameSequence(const OmniLog& log, const FeatureLayout& layout);

// Every usable window of a log: frames i-history+1..i (FrameSequence::Usable) and i+H
// measured, commands from frame 0 on (earlier ones are unknown). Appends to *data.
// Returns the number of samples added.
int AppendSamples(const OmniLog& log, const FeatureLayout& layout, OmniDataset* data);
// The same from a FrameSequence, for windows whose newest frame lies in [first, last].
int AppendSamples(const FrameSequence& seq, const FeatureLayout& layout, int first, int last, OmniDataset* data);

// Appends rows (x, y) to a dataset.
void AppendRows(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, OmniDataset* data);

}  // namespace twinsim

// The arm's process sensitivity, measured in closed loop (seed 001, section VII-B):
// per joint j and posture, the frequency response PS_j(jw) = Y_j(jw) / F_j(jw) from a
// feedforward torque f_j added to the tracking controller's output (after its feedback
// and model feedforward) to the joint's position y_j = q_j, with the feedback loop
// closed. For a rigid joint of inertia J under PD feedback (Kp, Kd) and a command delay
// of D samples, continuous-time, PS = e^{-sDTs} / (J s^2 + (Kd s + Kp) e^{-sDTs}); the
// tracking error e = q_ref - q changes by -PS f, which is why the ILC's learning filter
// is PS's inverse (control/iterative_learning.h).
//
// Measured by simulation as on the real arm: the arm holds each posture under the
// scene's controller while joint j alone gets a random-phase multisine torque
// (signal/multisine.h) for 1 + `periods` periods; the first period is dropped as the
// transient, the DFT of the others' position response is averaged over the periods and
// divided by the excitation's spectrum at the excited lines. One run per joint and
// posture on the chosen backend, with the plant's friction and effects: PS is the
// diagonal of the closed loop's response matrix, what a per-joint ILC needs.
//
// The coherence per line, gamma^2 = |sum_p Y_p|^2 / (P sum_p |Y_p|^2) over the P periods
// (the excitation repeats, so the input's spectrum is the same in each), is 1 where the
// response repeats from period to period and falls where noise or a transient that has
// not died out differ between them: the lines to trust. The nominal response of a joint
// is the average over the postures (seed 001, eq. 23).
//
//   FrfOptions o;                                   // 2..200 Hz, 0.5 s periods
//   ClosedLoopFrf frf = MeasureProcessSensitivity(plant, hat, {q_a, q_b}, tracking, o);
//   std::complex<double> ps = frf.response[joint][posture][line];  // rad/(N·m)
#pragma once

#include <Eigen/Core>
#include <complex>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "control/computed_torque.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

struct FrfOptions {
  double period = 0.5;       // s, one multisine period; the frequency resolution is 1 / period
  int periods = 4;           // periods averaged, after one more dropped as the transient
  double f_min = 2;          // Hz, lowest excited line
  double f_max = 200;        // Hz, highest excited line (below the Nyquist frequency)
  // RMS of the excitation as a fraction of the joint's effort_limit (of 1 N·m where
  // none is given): large against the Coulomb friction, small against the limit.
  double amplitude = 0.1;
  std::uint64_t seed = 1;    // the multisine's phases

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

struct ClosedLoopFrf {
  double sample_time = 0;                 // s
  Eigen::VectorXd frequency;              // lines, Hz
  std::vector<Eigen::VectorXd> postures;  // each dof, rad or m
  // response[j][p](i): PS of joint j at posture p and line i, rad/(N·m) (m/N).
  std::vector<std::vector<Eigen::VectorXcd>> response;
  // coherence[j][p](i): gamma^2 of joint j at posture p and line i, in [0, 1].
  std::vector<std::vector<Eigen::VectorXd>> coherence;

  // The average of joint j's responses over the postures (eq. 23 of seed 001).
  Eigen::VectorXcd Nominal(int joint) const;
  // The smallest coherence of joint j's postures at each line.
  Eigen::VectorXd WorstCoherence(int joint) const;
};

// Postures spanning joints `a` and `b` (0-based) over [low, high] each, `count` values
// evenly from end to end (count x count postures; the middle for count 1), the other
// joints at `base`; each clamped to the joint's limits (seed 001: 16 postures, 4 x 4
// over joints 2 and 3). Throws std::invalid_argument for joints that do not exist, a =
// b, count < 1, a base of the wrong size or low > high.
std::vector<Eigen::VectorXd> GridPostures(const ArmModel& arm, const Eigen::VectorXd& base, int a, int b, int count,
                                          const Eigen::VectorXd& low, const Eigen::VectorXd& high);

// Measures the process sensitivity of every joint at every posture, running
// `tracking` (its controller, gains and backend; its feedforward and dither are
// replaced) with model `hat` on `plant`. progress(done, total) is called after each
// run. Throws InputError for invalid options or a period shorter than 4 samples,
// std::invalid_argument for no postures or a posture of the wrong size; what
// RunTrackingTrial throws.
ClosedLoopFrf MeasureProcessSensitivity(const ArmModel& plant, const ArmModel& hat,
                                        const std::vector<Eigen::VectorXd>& postures, const TrackingOptions& tracking,
                                        const FrfOptions& options,
                                        const std::function<void(int, int)>& progress = {});

}  // namespace twinsim

// A periodic excitation trajectory for an arm: one finite Fourier series per joint
// (Swevers, Ganseman, Tukel, De Schutter, Van Brussel 1997; seed 001, section IV-A):
//
//   q_i(t)   = q0_i + sum_{l=1..N} a_il / (w l) sin(w l t) - b_il / (w l) cos(w l t)
//   qd_i(t)  =        sum_{l=1..N} a_il cos(w l t) + b_il sin(w l t)
//   qdd_i(t) =        sum_{l=1..N} -a_il w l sin(w l t) + b_il w l cos(w l t)
//
// with w = 2 pi f, f the fundamental frequency (0.1 Hz by default, a period of 10 s) and
// N harmonics. The coefficients a, b are velocity amplitudes; q, qd and qdd are exact
// (no numerical differentiation), and the motion repeats every 1/f seconds, so the same
// trajectory can be run trial after trial and averaged over whole periods.
//
//   FourierTrajectory traj = LoadFourierTrajectory("out/excitation.yaml");
//   JointMotion m = EvaluateFourier(traj, 1.25);          // q, qd, qdd at t = 1.25 s
//   SampledMotion s = SampleFourier(traj, 0.001, traj.period());
//
// The file format (docs/excitation.md):
//
//   fundamental_hz: 0.1        # f, Hz (required, > 0)
//   model: rrr                 # optional: the arm it was designed for (informative)
//   joints:                    # one entry per joint, base to tip (required)
//     - name: waist            # optional
//       q0: 0.12               # rad or m (required)
//       a: [0.5, -0.2, ...]    # rad/s or m/s, one per harmonic (required)
//       b: [0.1, 0.3, ...]     # rad/s or m/s, as many as a (required)
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "robots/arm/arm_model.h"

namespace twinsim {

struct FourierTrajectory {
  double fundamental = 0.1;  // Hz, f; the period is 1/f
  Eigen::VectorXd q0;        // n, rad or m: the offset of each joint
  Eigen::MatrixXd a;         // n x N, rad/s or m/s: qd's cosine amplitudes, column l-1 for harmonic l
  Eigen::MatrixXd b;         // n x N, rad/s or m/s: qd's sine amplitudes
  std::vector<std::string> joint_names;  // n or empty; written to and read from the file
  std::string model;                     // the arm it was designed for; informative

  int dof() const { return static_cast<int>(q0.size()); }
  int harmonics() const { return static_cast<int>(a.cols()); }
  double period() const { return 1.0 / fundamental; }  // s
  double omega() const;                                  // rad/s, 2 pi f
  // Empty when consistent (positive fundamental, at least one joint and one harmonic,
  // matching shapes, finite numbers), else every problem.
  std::string Validate() const;
};

// q, qd, qdd of every joint at one instant (n each).
struct JointMotion {
  Eigen::VectorXd q, qd, qdd;
};

// Rows are instants t_k = k * sample_time.
struct SampledMotion {
  std::vector<double> t;     // s
  Eigen::MatrixXd q, qd, qdd;  // samples x n
};

// A trajectory of n joints and N harmonics with every coefficient zero (q = 0).
FourierTrajectory ZeroFourierTrajectory(int dof, int harmonics, double fundamental);

// The trajectory's position, velocity and acceleration at time t (s), exact.
JointMotion EvaluateFourier(const FourierTrajectory& trajectory, double t);

// The trajectory at t_k = k * sample_time for every t_k < duration (s). Throws
// InputError for a non-positive sample time or duration.
SampledMotion SampleFourier(const FourierTrajectory& trajectory, double sample_time, double duration);

// The file text (the schema above); numbers with as many significant digits (15 to
// 17) as loading needs to give back the same doubles.
std::string FormatFourierTrajectoryYaml(const FourierTrajectory& trajectory);
// Writes the file atomically; throws InputError when it cannot be written.
void SaveFourierTrajectory(const FourierTrajectory& trajectory, const std::string& path);
// Reads the file. Throws InputError "path:line:column: ..." naming every problem:
// syntax, unknown or missing keys, non-numbers, a non-positive fundamental, lists of
// different lengths.
FourierTrajectory LoadFourierTrajectory(const std::string& path);
FourierTrajectory ParseFourierTrajectoryYaml(const std::string& text, const std::string& name);

// Throws InputError "`where`: ..." when the trajectory has not one joint per joint of
// `model` (`where` names the trajectory's file).
void CheckTrajectoryFitsModel(const FourierTrajectory& trajectory, const ArmModel& model, const std::string& where);

// The trajectory as a contract arm log (CONTRACT.md):
//   t,q1..qn,qd1..qdn,qdd1..qddn,qref1..qrefn,tau1..taun
// sampled at `sample_time` over `periods` whole periods; q = qref is the reference and
// tau the model's inverse dynamics along it (friction included): the torque a perfect
// feedforward would command. Throws InputError for a non-positive sample time or
// period count, or a trajectory that does not fit the model.
std::string FormatReferenceCsv(const ArmModel& model, const FourierTrajectory& trajectory, double sample_time,
                               int periods);

}  // namespace twinsim

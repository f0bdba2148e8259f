// Plants with hidden effects for the diagnosis tests: logs recorded from a model with
// effects switched on, with realistic sensor noise, handed to the diagnosis with the
// nominal model only (the code under test is never told what was hidden).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "diagnosis/diagnosis.h"
#include "engines/omni_engine.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"

namespace twinsim {
namespace testing {

// Records what `report` named and its held-out gaps beside the plant's own (`floor`) as
// properties of the running test (--gtest_output=xml), from which docs/diagnose.md's
// counts and confusion table are made.
void RecordDiagnosis(const DiagnosisReport& report, double floor);

// `options` for a model's own gaps only: no effect added, no adequacy check (the gap a
// plant reaches on its own logs, the floor each case is measured against).
DiagnosisOptions GapsOnly(DiagnosisOptions options = {});

// A torque on one joint (a function of that joint's q and qd, called once per control
// sample in order, so it may carry state).
using JointTorque = std::function<double(double q, double qd)>;
std::function<Eigen::VectorXd(const Eigen::VectorXd& q, const Eigen::VectorXd& qd)> OnJoint(int joint, JointTorque torque);

// Backlash: a loose part of `inertia` (kg m^2) riding on the joint with `play` rad of
// free travel either way, whose stops are springs of `frequency` Hz against the part
// (stiffness inertia (2 pi frequency)^2) with `damping_ratio`. While the joint turns
// steadily the part is carried against one stop (extra inertia); when the joint
// reverses it travels freely across the gap and strikes the other stop. The torque on
// the joint, averaged over each `sample_time`, integrated in 20 sub-steps from the
// part resting mid-gap at the first call. Outside the vocabulary: no effect carries
// state or a dead band.
JointTorque Backlash(double inertia, double play, double frequency, double damping_ratio, double sample_time);

struct ArmRecording {
  double counts_per_rev = 2e5;  // encoder counts per joint revolution (q quantised); 0: exact
  double torque_noise = 0.02;   // N·m, standard deviation on the logged command
  bool log_velocities = false;  // false: the log holds q and tau only, qd and qdd are derived
  double cutoff_hz = 10;        // Hz, the reader's cut-off for derived qd, qdd
  double bandwidth = 10;        // Hz, the computed-torque controller's
  // A torque the plant receives beyond the command, never logged: an effect outside
  // the vocabulary (TrainingTrialOptions::disturbance). Empty: none.
  std::function<Eigen::VectorXd(const Eigen::VectorXd& q, const Eigen::VectorXd& qd)> disturbance;
};

// A stop-and-go (even seeds) or multi-sine (odd seeds) tracking run of `plant` under
// computed torque over `hat` with a torque dither, as a real arm's controller logs it.
// Where `as_received` is given, it gets the same log (same noise) with the torque the
// plant received, the disturbance included: what a model that knew it would explain.
ArmLog RecordArmPlant(const ArmModel& plant, const ArmModel& hat, std::uint64_t seed, double seconds,
                      const ArmRecording& noise = {}, ArmLog* as_received = nullptr);

// The RRR arm of seed 001 (models/rrr.yaml) with `effects` (YAML list items, e.g.
// "{name: viscous_friction, joint: 2, b: 0.5}") added.
ArmModel RrrWith(const std::string& effects_yaml);

// A random drive of `plant` (camera noise as the shipped models: 1 mm, 0.005 rad) of
// `seconds` at 30 fps on the analytic backend, on `field` (a sloping floor: outside
// every model).
OmniLog RecordOmniPlant(const OmniModel& plant, double seconds, std::uint64_t seed, const FieldModel& field = FieldModel{});

// How an open-world plant is recorded: as a real SSL camera sees a robot.
struct OmniRecording {
  std::string backend = "ode";  // the engine that plays the plant
  double frame_rate = 60;       // Hz
  double jitter = 0.001;        // s, frame times move by up to this (uniform), the poses stay put
  double repeat_share = 0.06;   // share of frames whose pose repeats the previous one (no new measurement)
  double noise_xy = 0.001;      // m
  double noise_theta = 0.005;   // rad
  double max_speed = 1.5;       // m/s, commanded
  double max_omega = 4;         // rad/s, commanded
  double max_centripetal = 3;   // m/s^2, the commands' turn rate is capped by it at speed
};

// A random drive of `plant` recorded as `how` says, as if read from a file.
OmniLog RecordOmniOpenWorld(const OmniModel& plant, double seconds, std::uint64_t seed, const OmniRecording& how = {});

}  // namespace testing
}  // namespace twinsim

// The cut-off of the zero-phase filter that derives an arm log's velocities and
// accelerations from its positions (robots/arm/arm_log.h), chosen from the data: the
// cut-off must pass the motion's band and no more. A drive whose loop closes at 19 Hz
// moves and stops faster than the default 10 Hz passes: its derived accelerations miss
// the stops, and friction fitted to them comes out wrong (docs/identification.md).
//
// Each candidate, from `lowest_hz` up in octaves to a quarter of the sample rate, is
// judged as an identification engineer judges a filter: the logs are derived at it, the
// model is identified (IdentifyArmByLeastSquares) on the fit blocks, and its torques are compared with
// the measured ones on the held-out blocks (analysis/held_out_blocks.h), on the same rows
// for every candidate. The measured torque does not depend on the cut-off; only how well
// the derived motion explains it does. The lowest cut-off within `tolerance` of the best
// wins: a higher one passes more encoder noise for a gain the held-out rows cannot tell.
//
//   std::vector<ArmLog> logs = ...;  // read at any cut-off
//   DerivativeCutoffChoice c = DeriveAtChosenCutoff(model, &logs, {});
//   std::printf("%s\n", c.Brief().c_str());
#pragma once

#include <string>
#include <vector>

#include "identification/wls_identification.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// How a choice among candidates is made on held-out blocks (the cut-off here, the
// position friction's knots in analysis/position_friction_choice.h).
struct HeldOutChoiceOptions {
  double tolerance = 0.05;   // a candidate within this share of the best held-out error counts as as good
  double held_out = 0.4;     // share of the blocks held out (InHeldOutBlock)
  double block_seconds = 0;  // s; 0: HeldOutBlockSeconds' choice
  WlsIdentificationOptions identification;  // how each candidate's model is identified
  // True when usable; otherwise *why says what is wrong.
  bool IsValid(std::string* why) const;
};

struct DerivativeCutoffOptions : HeldOutChoiceOptions {
  double lowest_hz = ArmLogOptions{}.cutoff_hz;  // Hz, the first candidate (the default cut-off)
  // True when usable; otherwise *why says what is wrong.
  bool IsValid(std::string* why) const;
};

struct DerivativeCutoffChoice {
  double cutoff_hz = 0;               // Hz, the choice (0: every log holds qd and qdd as logged)
  std::vector<double> candidates_hz;  // Hz, in the order tried
  // Per candidate, the held-out torque error: per joint the error's mean square over the
  // measured torque's, averaged over joints (NaN where the identification failed).
  std::vector<double> held_out_error;
  std::string note;  // the first candidate whose identification failed, and why (if one did)
  // One line: the choice and each candidate's error.
  std::string Brief() const;
};

// The held-out torque error of `model` on `logs` (PredictArmCommands): per joint the
// error's mean square over the measured torque's on the rows in held-out blocks of
// `block` s (InHeldOutBlock with share `held_out`) between log i's first and last
// edge[i] rows, averaged over joints; with `rest_speed` (per joint) a joint's rows at
// rest (ArmRestRows) left out, as the least squares leaves them out: there its friction
// holds it anywhere within the band. What the cut-off (every row) and the position
// friction's knots (moving rows) are chosen by.
double ArmHeldOutTorqueError(const ArmModel& model, const std::vector<ArmLog>& logs, const std::vector<int>& edge,
                             double block, double held_out, const Eigen::VectorXd& rest_speed = {});

// The first of candidates' held-out `errors` (in their order of preference) within
// (1 + tolerance) times the least finite one; -1 when none is finite (NaN: a candidate
// that could not be identified).
int FirstCandidateNearBest(const std::vector<double>& errors, double tolerance);

// Chooses the cut-off for `logs` (read at any cut-off; each is derived again per
// candidate, their copies only) and the a-priori `model`. A candidate whose
// identification fails is skipped (its error NaN); where every one fails, lowest_hz is
// kept and the note says why. Throws InputError for invalid options
// or logs whose joint count differs from the model's.
DerivativeCutoffChoice ChooseDerivativeCutoff(const ArmModel& model, const std::vector<ArmLog>& logs,
                                              const DerivativeCutoffOptions& options);

// Chooses the cut-off for *logs as ChooseDerivativeCutoff does and derives them at it
// (DeriveArmLog); returns the choice. Throws as ChooseDerivativeCutoff.
DerivativeCutoffChoice DeriveAtChosenCutoff(const ArmModel& model, std::vector<ArmLog>* logs,
                                            const DerivativeCutoffOptions& options);

}  // namespace twinsim

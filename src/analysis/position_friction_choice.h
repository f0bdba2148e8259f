// How many knots a joint's Coulomb friction gets along its travel (position_friction,
// robots/arm/arm_effects.h), or its torque along the travel (position_torque), chosen from the data as the derivative cut-off is
// (analysis/derivative_cutoff.h): each candidate's model is identified by least squares
// on the fit blocks and its torques compared with the measured ones on the held-out
// blocks where the joints move (at rest a joint's friction holds it anywhere within its
// band, and the fit leaves those rows out too), on the same rows for every candidate.
// The fewest knots within `tolerance` of
// the best held-out error win, one level (no knots) first: a finer map of the friction
// must predict rows it was not fitted on better, by more than the tolerance, to be kept.
//
//   PositionFrictionChoice c = ChoosePositionFrictionKnots(model, logs, {});
//   options.position_friction_knots = c.knots;
//   std::printf("%s\n", c.Brief().c_str());
#pragma once

#include <string>
#include <vector>

#include "analysis/derivative_cutoff.h"
#include "identification/wls_identification.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// The held-out blocks and the identification as the cut-off's (its knots replaced by each
// candidate's), a tolerance of 2 %.
struct PositionFrictionChoiceOptions : HeldOutChoiceOptions {
  PositionFrictionChoiceOptions() { tolerance = 0.02; }
  std::vector<int> candidates = {0, 3, 5, 9};  // knots tried, in order of preference (0: one level)
  // Choose position_torque's knots (0: none) instead of position_friction's; the other
  // profile's knots as `identification` gives them.
  bool torque = false;
  // True when usable; otherwise *why says what is wrong.
  bool IsValid(std::string* why) const;
};

struct PositionFrictionChoice {
  int knots = 0;                       // the choice (0: one level, or no position torque)
  bool torque = false;                 // position_torque's knots (else position_friction's)
  std::vector<int> candidates;         // in the order tried
  std::vector<double> held_out_error;  // per candidate (ArmHeldOutTorqueError; NaN where it failed)
  std::string note;                    // the first candidate whose identification failed, and why
  // One line: the choice and each candidate's error.
  std::string Brief() const;
};

// Chooses the knots for `logs` (derived at their cut-off) and the a-priori `model`. A
// candidate whose identification fails is skipped (its error NaN); where every one
// fails, 0 is kept and the note says why. Throws InputError for invalid options or logs
// whose joint count differs from the model's.
PositionFrictionChoice ChoosePositionFrictionKnots(const ArmModel& model, const std::vector<ArmLog>& logs,
                                                   const PositionFrictionChoiceOptions& options);

}  // namespace twinsim

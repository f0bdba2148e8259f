// The whole-run output-error fit of an arm by multiple shooting
// (ArmOutputErrorOptions::whole_run; arm_output_error.h says what it fits and how it
// decides, docs/identification.md "Output error over whole runs" the equations).
// RefineArmByOutputError calls it; it is a header of its own so the windows' fit and
// the runs' fit each stay one file.
#pragma once

#include <vector>

#include "analysis/arm_output_error.h"

namespace twinsim {

class ArmFitCoordinates;

// Options already checked. Throws InputError for logs too short to cut into a fitted
// part of two segments and a held-out quarter.
ArmModel RefineArmByShooting(const ArmModel& start, const std::vector<ArmLog>& logs,
                             const ArmOutputErrorOptions& options, ArmOutputErrorSummary* summary);

// ArmOutputErrorStartCost of a whole-run fit: every segment simulated from its logged
// state, each joint's squared error over its spread of q, summed (no defects).
double ArmShootingStartCost(const ArmModel& model, const std::vector<ArmLog>& logs,
                            const ArmOutputErrorOptions& options);

// Both fits' parameters into *summary: per joint the scale at coordinates x, the
// frictions and offsets of `start` and `fitted`, the coordinates at a bound by name, and
// the standard errors of the coordinates `se` (ClusteredStandardErrors) in the values'
// terms (ArmFitCoordinates::ValueError).
void SummariseArmFit(const ArmFitCoordinates& coordinates, const ArmModel& start, const ArmModel& fitted,
                     const std::vector<double>& x, const std::vector<int>& at_bound, const std::vector<double>& se,
                     ArmOutputErrorSummary* summary);

// The low-speed friction's part of *summary: `with` the model it fitted (read when
// tried), whether it was tried and kept, and the plain fit's held-out RMSE.
void SummariseLowSpeedFriction(const ArmModel& with, bool tried, bool kept, const Eigen::VectorXd& check_plain,
                               ArmOutputErrorSummary* summary);

}  // namespace twinsim

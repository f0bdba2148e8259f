// The learned arm backend: an arm moved one sample at a time by a 1-sample predictor
// learned from logs of the real arm (learning/arm_predictor.h), inside the same loop as
// the Newtonian backends (sim/arm_simulation.h): the loop delays the commands by the
// model's delay_samples as always and hands it the command acting over each sample.
// The predictor has learned the arm's friction and effects with its bodies, so none are
// added on top (the model's effects are not applied). A residual predictor (the nominal model's step plus a learned correction) is used the
// same way: the backend attaches `model` to it as its nominal model.
//
// Its state is the predictor's window: the last `history` joint states and the torques
// that acted over them (ArmBackendState::engine holds the window, so Save/Restore are
// exact). Reset(q, qd, ...) fills the window with a steady motion at qd ending at q under
// the torque the model's inverse dynamics (with its friction) says that motion needs.
//
//   ArmPredictor p = ArmPredictor::Load("rrr.pred");
//   ArmSimulation sim(model, MakeLearnedArmBackend(model, p));
#pragma once

#include <memory>

#include "learning/arm_predictor.h"
#include "sim/arm_backend.h"

namespace twinsim {

// Throws InputError when the predictor does not fit `model` (ArmPredictor::CheckUse:
// another model, joint count, sample time, delay, or a horizon other than 1) or for a
// model that does not Validate().
std::unique_ptr<ArmBackend> MakeLearnedArmBackend(const ArmModel& model, const ArmPredictor& predictor);

}  // namespace twinsim

// Diagnosis of an arm model against measured arm logs (diagnosis.h, docs/diagnose.md).
//
// The residual is the contract's `replay` for arms: the measured command minus the
// command the model (inverse dynamics, friction and its effects; PredictArmCommands)
// needs for the logged motion, per joint. With a torque_saturation limit L on joint j,
// clip(u, L) - model is compared instead: the joint received the clipped command.
// The gap is its RMS over joints and held-out rows, N·m (N for prismatic joints).
//
// Rigid-body inverse dynamics are computed once per log; every candidate then only
// adds per-joint terms (friction laws, the payload through the last link's regressor
// columns, flexibility, offset, delay, saturation), so a fit costs milliseconds.
// Linear parameters start from least squares, the others from a grid; Ceres refines
// all of a fit's parameters together on the fit rows.
//
//   DiagnosisOptions options;
//   ArmModel repaired;
//   DiagnosisReport report = DiagnoseArm(model, logs, options, &repaired);
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "diagnosis/diagnosis.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// Diagnoses `model` on `logs` (each checked against the model; derived derivatives'
// edge rows left out). *repaired (if given) receives the model with the effects added.
// Throws InputError for logs that do not match the model, hold non-finite values or are
// too short to hold a block out, and for invalid options.
DiagnosisReport DiagnoseArm(const ArmModel& model, const std::vector<ArmLog>& logs, const DiagnosisOptions& options,
                            ArmModel* repaired = nullptr,
                            const std::function<void(const std::string&)>& progress = {});

// The inertial parameters [m, m c, I about the frame's origin] (10, as arm_regressor.h
// orders them) of a point mass `mass` (kg) at `position` (m).
Eigen::Matrix<double, 10, 1> PointMassParameters(double mass, const Eigen::Vector3d& position);

}  // namespace twinsim

// PredictArmCommands: the model's effects inverted into the commands the log's motion
// needed, in closed-form cases and against the arm simulation; and identification
// writing the torque offsets it estimates as torque_offset effects.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "analysis/arm_replay.h"
#include "control/computed_torque.h"
#include "identification/synthetic_arm_data.h"
#include "identification/wls_identification.h"
#include "io/csv_table.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model_yaml_writer.h"
#include "test_util.h"

namespace twinsim {
namespace {

using testing::SourcePath;

ArmModel Rrr(int delay_samples) {
  ArmModel m = LoadArmModel(SourcePath("models/rrr.yaml"));
  m.delay_samples = delay_samples;
  return m;
}

// The exact multi-sine motion at `rate_hz` for `seconds` (q, qd, qdd logged).
ArmLog ExactLog(const ArmModel& model, double seconds, double rate_hz) {
  const testing::MultiSine motion = testing::MakeMultiSine(model, 5);
  const int rows = static_cast<int>(std::lround(seconds * rate_hz)) + 1;
  ArmLog log;
  log.path = "exact.csv";
  log.dof = model.dof();
  log.t.resize(rows);
  log.q.resize(rows, log.dof), log.qd.resize(rows, log.dof), log.qdd.resize(rows, log.dof);
  log.tau.setZero(rows, log.dof);
  Eigen::VectorXd q, qd, qdd;
  for (int r = 0; r < rows; ++r) {
    log.t[r] = r / rate_hz;
    motion.At(log.t[r], &q, &qd, &qdd);
    log.q.row(r) = q.transpose(), log.qd.row(r) = qd.transpose(), log.qdd.row(r) = qdd.transpose();
  }
  log.qd_logged = log.qdd_logged = true;
  log.sample_period = 1 / rate_hz;
  return log;
}

TEST(ArmCommands, WithoutEffectsAndDelayTheyAreTheRigidTorques) {
  const ArmModel m = Rrr(0);
  const ArmLog log = ExactLog(m, 2, 200);
  EXPECT_LE((PredictArmCommands(m, log) - PredictArmTorques(m, log)).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(ArmCommands, AnOffsetShiftsTheCommandByExactlyMinusTau0) {
  ArmModel m = Rrr(0);
  const ArmLog log = ExactLog(m, 2, 200);
  const Eigen::MatrixXd rigid = PredictArmTorques(m, log);
  AddArmEffect({"torque_offset", 1, {{"tau0", 1.25}}}, 3, &m.effects);
  AddArmEffect({"torque_offset", 2, {{"tau0", -0.5}}}, 3, &m.effects);
  const Eigen::MatrixXd command = PredictArmCommands(m, log);
  EXPECT_LE((command.col(0) - rigid.col(0)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE(((command.col(1) - rigid.col(1)).array() + 1.25).abs().maxCoeff(), 1e-12);
  EXPECT_LE(((command.col(2) - rigid.col(2)).array() - 0.5).abs().maxCoeff(), 1e-12);
}

TEST(ArmCommands, DelaysSendTheCommandEarlierAndHoldTheLastRow) {
  // 2 samples of the model's delay (2 ms) plus a 7.5 ms time_delay on joint 3, on a
  // 1 kHz log: joint 1 and 2 need the torque 2 rows later, joint 3 9.5 rows later
  // (halfway between two rows: the mean of both).
  ArmModel m = Rrr(2);
  const ArmLog log = ExactLog(m, 1, 1000);
  AddArmEffect({"time_delay", 2, {{"delay", 0.0075}}}, 3, &m.effects);
  const Eigen::MatrixXd rigid = PredictArmTorques(m, log);
  ArmCommandSummary summary;
  const Eigen::MatrixXd command = PredictArmCommands(m, log, &summary);
  EXPECT_NEAR(summary.shift[0], 0.002, 1e-15);
  EXPECT_NEAR(summary.shift[2], 0.0095, 1e-15);
  const int rows = log.rows();
  for (int r : {0, 1, 100, 500, rows - 11}) {
    EXPECT_NEAR(command(r, 0), rigid(r + 2, 0), 1e-9) << r;
    EXPECT_NEAR(command(r, 1), rigid(r + 2, 1), 1e-9) << r;
    EXPECT_NEAR(command(r, 2), 0.5 * (rigid(r + 9, 2) + rigid(r + 10, 2)), 1e-9) << r;
  }
  // Beyond the log's end the last row is held.
  EXPECT_EQ(command(rows - 1, 0), rigid(rows - 1, 0));
  EXPECT_EQ(command(rows - 2, 2), rigid(rows - 1, 2));
}

TEST(ArmCommands, SaturationIsCountedNotClippedAndPayloadAndFrictionEffectsAct) {
  ArmModel m = Rrr(0);
  const ArmLog log = ExactLog(m, 2, 200);
  const Eigen::MatrixXd rigid = PredictArmTorques(m, log);
  ArmModel sat = m;
  AddArmEffect({"torque_saturation", 1, {{"limit", 5}}}, 3, &sat.effects);
  ArmCommandSummary summary;
  const Eigen::MatrixXd command = PredictArmCommands(sat, log, &summary);
  EXPECT_LE((command - rigid).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(summary.beyond_saturation[1], (rigid.col(1).array().abs() > 5).count());
  EXPECT_GT(summary.beyond_saturation[1], 0);
  // A payload is a point mass at the last link: the same as the rigid torques of the
  // model with the mass lumped in.
  ArmModel payload = m;
  AddArmEffect({"payload", -1, {{"mass", 0.45}, {"x", 0.35}}}, 3, &payload.effects);
  EXPECT_LE((PredictArmCommands(payload, log) - PredictArmTorques(ArmPlantModel(payload), log)).cwiseAbs().maxCoeff(),
            1e-12);
  // Friction effects add to the nominal friction: viscous b qd exactly.
  ArmModel viscous = m;
  AddArmEffect({"viscous_friction", 0, {{"b", 0.7}}}, 3, &viscous.effects);
  EXPECT_LE((PredictArmCommands(viscous, log).col(0) - rigid.col(0) - 0.7 * log.qd.col(0)).cwiseAbs().maxCoeff(),
            1e-12);
}

TEST(ArmCommands, AStiffFlexibleJointAddsTheMotorInertiasTorque) {
  // Undamped: the spring's deflection is N / k, so the drive is N + J_m (qdd + N'' / k).
  // Very stiff, the drive tends to N + J_m qdd (the motor rides with the link). Without
  // Coulomb friction on the joint: its jump at a reversal would need an infinite motor
  // acceleration (a jump of the spring's deflection).
  ArmModel m = Rrr(0);
  m.joints[2].coulomb = 0;
  const ArmLog log = ExactLog(m, 2, 1000);
  const Eigen::MatrixXd rigid = PredictArmTorques(m, log);
  AddArmEffect({"joint_flexibility", 2, {{"k", 1e7}, {"motor_inertia", 0.01}}}, 3, &m.effects);
  ArmCommandSummary summary;
  const Eigen::MatrixXd command = PredictArmCommands(m, log, &summary);
  EXPECT_TRUE(summary.flexible);
  EXPECT_LE((command.col(2) - rigid.col(2) - 0.01 * log.qdd.col(2)).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LE((command.leftCols(2) - rigid.leftCols(2)).cwiseAbs().maxCoeff(), 1e-12);
}

// `plant` (effects and delay) tracking the exact multi-sine with computed torque and
// the rigid model `hat`, simulated at 1 kHz on the analytic backend; logged as the
// contract's arm log (t, q, qd, tau: the commands sent) and read back.
struct SimulatedLog {
  TrackingTrial trial;
  ArmLog log;
};

SimulatedLog Simulate(const ArmModel& plant, const ArmModel& hat, double seconds, const std::string& dir,
                      double cutoff_hz) {
  const std::uint64_t seed = 5;
  const testing::MultiSine motion = testing::MakeMultiSine(hat, seed);
  ArmReference ref;
  ref.sample_time = plant.sample_time;
  const int rows = static_cast<int>(std::lround(seconds / plant.sample_time)) + 1;
  const int n = hat.dof();
  ref.t.resize(rows), ref.q.resize(rows, n), ref.qd.resize(rows, n), ref.qdd.resize(rows, n);
  Eigen::VectorXd q, qd, qdd;
  for (int r = 0; r < rows; ++r) {
    ref.t[r] = r * plant.sample_time;
    motion.At(ref.t[r], &q, &qd, &qdd);
    ref.q.row(r) = q.transpose(), ref.qd.row(r) = qd.transpose(), ref.qdd.row(r) = qdd.transpose();
  }
  TrackingOptions options;
  options.saturate = false;
  SimulatedLog out;
  out.trial = RunTrackingTrial(plant, hat, ref, options);
  std::string csv = "t,q1,q2,q3,qd1,qd2,qd3,tau1,tau2,tau3\n";
  for (int r = 0; r < rows; ++r) {
    csv += FormatCsvNumber(out.trial.t[r]);
    for (const Eigen::MatrixXd* m : {&out.trial.q, &out.trial.qd, &out.trial.command})
      for (int j = 0; j < n; ++j) csv += "," + FormatCsvNumber((*m)(r, j));
    csv += "\n";
  }
  ArmLogOptions log_options;
  log_options.cutoff_hz = cutoff_hz;
  out.log = ReadArmLog(testing::WriteText(dir + "/simulated.csv", csv), log_options);
  return out;
}

TEST(ArmCommands, ReplayOfASimulatedPlantWithEffectsGivesTheCommandsItWasSent) {
  const std::string dir = testing::TempDir("arm_commands_sim");
  const ArmModel hat = Rrr(1);
  ArmModel plant = hat;
  AddArmEffect({"torque_offset", 1, {{"tau0", 1.5}}}, 3, &plant.effects);
  AddArmEffect({"torque_offset", 2, {{"tau0", -0.4}}}, 3, &plant.effects);
  AddArmEffect({"time_delay", 0, {{"delay", 0.004}}}, 3, &plant.effects);
  AddArmEffect({"viscous_friction", 2, {{"b", 0.05}}}, 3, &plant.effects);
  AddArmEffect({"payload", -1, {{"mass", 0.3}, {"x", 0.35}}}, 3, &plant.effects);
  // A high cut-off keeps what the feedback puts into the motion.
  const SimulatedLog sim = Simulate(plant, hat, 6, dir, 200);
  const ArmLog& log = sim.log;
  const Eigen::MatrixXd with_effects = PredictArmCommands(plant, log);
  const Eigen::MatrixXd rigid_only = PredictArmTorques(hat, log);
  const int first = log.edge_samples + 10, rows = log.rows() - 2 * first;
  for (int j = 0; j < 3; ++j) {
    const auto sent = log.tau.col(j).segment(first, rows);
    const double scale = std::sqrt(sent.squaredNorm() / rows);
    const double error = std::sqrt((with_effects.col(j).segment(first, rows) - sent).squaredNorm() / rows);
    const double naive = std::sqrt((rigid_only.col(j).segment(first, rows) - sent).squaredNorm() / rows);
    std::printf("[measured] joint %d: command RMS %.4g N m, replay error %.4g N m (%.3f %%), without effects %.4g N m\n",
                j + 1, scale, error, 100 * error / scale, naive);
    // The commands come back to within 3.5 % of their RMS (what remains: the Coulomb
    // friction's reversals, the 1 ms hold -- the command acts over the sample after its
    // delay, the replay takes the torque needed at its start -- and the feedback's
    // content beyond the derivative filter), and at least 3 times closer than the
    // rigid model without its effects and delay.
    EXPECT_LT(error, 0.035 * scale) << "joint " << j + 1;
    EXPECT_LT(error, naive / 3) << "joint " << j + 1;
  }
}

TEST(ArmCommands, IdentifyWritesTheOffsetsAsTorqueOffsetEffectsWithTheContractsSign) {
  const std::string dir = testing::TempDir("arm_commands_identify");
  const ArmModel hat = Rrr(0);
  ArmModel plant = hat;
  AddArmEffect({"torque_offset", 1, {{"tau0", 1.5}}}, 3, &plant.effects);
  AddArmEffect({"torque_offset", 2, {{"tau0", -0.4}}}, 3, &plant.effects);
  // A low cut-off for identification: q-double-dot's noise stays small.
  const SimulatedLog sim = Simulate(plant, hat, 8, dir, 30);
  WlsIdentificationOptions options;
  options.torque_offsets = true;
  options.decimate = 4;
  WlsIdentificationSummary summary;
  // Start from a model that has an offset and a friction effect the fit replaces, and a
  // delay it keeps.
  ArmModel a_priori = hat;
  AddArmEffect({"torque_offset", 0, {{"tau0", 9}}}, 3, &a_priori.effects);
  AddArmEffect({"viscous_friction", 0, {{"b", 0.2}}}, 3, &a_priori.effects);
  AddArmEffect({"time_delay", 0, {{"delay", 0.0005}}}, 3, &a_priori.effects);
  const ArmModel identified = IdentifyArmByLeastSquares(a_priori, {sim.log}, options, &summary);
  std::printf("[measured] identified tau0 = %.4f / %.4f / %.4f N m (true 0 / 1.5 / -0.4)\n",
              identified.effects.joint(0).torque_offset, identified.effects.joint(1).torque_offset,
              identified.effects.joint(2).torque_offset);
  EXPECT_NEAR(identified.effects.joint(0).torque_offset, 0, 0.03);
  EXPECT_NEAR(identified.effects.joint(1).torque_offset, 1.5, 0.03);
  EXPECT_NEAR(identified.effects.joint(2).torque_offset, -0.4, 0.03);
  EXPECT_EQ(identified.effects.joint(0).viscous, 0);        // dropped: held by the joint's viscous
  EXPECT_EQ(identified.effects.joint(0).time_delay, 0.0005);  // kept
  // Written and loaded back, the model's commands replay the data.
  WriteArmModelYaml(dir + "/identified.yaml", identified);
  ArmModel loaded = LoadArmModel(dir + "/identified.yaml");
  loaded.effects.joints[0].time_delay = 0;  // the plant had none
  // As well as the plant's own model does (the sampled-data remainder of the test above).
  const Eigen::MatrixXd command = PredictArmCommands(loaded, sim.log);
  const Eigen::MatrixXd truth = PredictArmCommands(plant, sim.log);
  const int first = sim.log.edge_samples, rows = sim.log.rows() - 2 * first;
  for (int j = 0; j < 3; ++j) {
    const auto sent = sim.log.tau.col(j).segment(first, rows);
    const double error = std::sqrt((command.col(j).segment(first, rows) - sent).squaredNorm() / rows);
    const double plant_error = std::sqrt((truth.col(j).segment(first, rows) - sent).squaredNorm() / rows);
    std::printf("[measured] joint %d: replay error of the identified model %.4g N m, of the plant's %.4g N m\n", j + 1,
                error, plant_error);
    EXPECT_LT(error, 1.25 * plant_error + 0.01) << "joint " << j + 1;
  }
}

}  // namespace
}  // namespace twinsim

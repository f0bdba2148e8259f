#include "diagnosis/diagnosis_plants.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "backends/omni_backend_factory.h"
#include "control/arm_trials.h"
#include "core/math_constants.h"
#include "scene/command_source.h"
#include "sim/omni_simulation.h"
#include "test_util.h"

namespace twinsim {
namespace testing {

void RecordDiagnosis(const DiagnosisReport& report, double floor) {
  std::string named;
  for (const DiagnosedEffect& e : report.effects) {
    named += (named.empty() ? "" : "; ") + EffectLabel(e.name, e.joint);
    for (const auto& [key, value] : e.parameters) named += " " + key + "=" + FormatParameter(value);
  }
  ::testing::Test::RecordProperty("named", named.empty() ? "nothing" : named);
  ::testing::Test::RecordProperty("gaps", FormatParameter(report.gap_before) + " -> " +
                                              FormatParameter(report.gap_after) + ", plant " + FormatParameter(floor));
}

DiagnosisOptions GapsOnly(DiagnosisOptions options) {
  options.max_effects = 0;
  options.check_adequacy = false;
  return options;
}

std::function<Eigen::VectorXd(const Eigen::VectorXd& q, const Eigen::VectorXd& qd)> OnJoint(int joint, JointTorque torque) {
  return [joint, torque = std::move(torque)](const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    Eigen::VectorXd d = Eigen::VectorXd::Zero(q.size());
    d[joint] = torque(q[joint], qd[joint]);
    return d;
  };
}

std::vector<ArmLog> WithTorqueAddedBack(std::vector<ArmLog> logs, int joint, const JointTorque& torque) {
  for (ArmLog& log : logs) {
    for (int r = 0; r < log.rows(); ++r) log.tau(r, joint) += torque(log.q(r, joint), log.qd(r, joint));
  }
  return logs;
}

ArmLog RecordArmPlant(const ArmModel& plant, const ArmModel& hat, std::uint64_t seed, double seconds,
                      const ArmRecording& noise) {
  TrainingTrialOptions options;
  options.seconds = seconds;
  options.bandwidth = noise.bandwidth;
  options.dither = 0;  // a dither's fast response is lost to the derivative filter: it would read as noise
  options.disturbance = noise.disturbance;
  const ArmReference reference = seed % 2 == 0 ? RandomStopAndGoReference(hat, options, seed)
                                               : SampledReference(RandomTrainingTrajectory(hat, options, seed),
                                                                  hat.sample_time, seconds);
  ArmLog log = RecordArmTrial(plant, hat, reference, options, seed);
  std::mt19937_64 rng(seed * 7919 + 17);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const double count = noise.counts_per_rev > 0 ? 2 * kPi / noise.counts_per_rev : 0;
  for (int r = 0; r < log.rows(); ++r) {
    for (int j = 0; j < log.dof; ++j) {
      if (count > 0) log.q(r, j) = std::round(log.q(r, j) / count) * count;
      log.tau(r, j) += noise.torque_noise * gauss(rng);
    }
  }
  ArmLogOptions read;
  read.cutoff_hz = noise.cutoff_hz;
  return ParseArmLog(FormatArmLog(log, noise.log_velocities), "plant_" + std::to_string(seed) + ".csv", read);
}

ArmModel RrrWith(const std::string& effects_yaml) {
  std::string yaml = "extends: " + SourcePath("models/rrr.yaml") + "\nname: rrr_hidden\n";
  if (!effects_yaml.empty()) yaml += "effects:\n" + effects_yaml;
  return LoadArmModelFromYamlString(yaml, "hidden.yaml");
}

OmniLog RecordOmniPlant(const OmniModel& plant, double seconds, std::uint64_t seed) {
  OmniModel m = plant;
  m.vision_noise_xy = 0.001;
  m.vision_noise_theta = 0.005;
  CommandSpec drive = RandomDrive(1.5, 3, 1.5);
  return RecordLog(m, drive, seconds, seed, "analytic", "omni_plant_" + std::to_string(seed) + ".csv");
}

OmniLog RecordOmniOpenWorld(const OmniModel& plant, double seconds, std::uint64_t seed, const OmniRecording& how) {
  OmniModel m = plant;
  m.vision_noise_xy = how.noise_xy;
  m.vision_noise_theta = how.noise_theta;
  CommandSpec drive = RandomDrive(how.max_speed, how.max_centripetal, 1.5);
  drive.max_omega = how.max_omega;
  FrameTiming timing;
  timing.frame_rate = how.frame_rate;
  timing.physics_substeps = DefaultPhysicsSubsteps(how.frame_rate);
  std::vector<SimRobot> robots;
  robots.push_back(SimRobot{"r", m, Pose2{}, MakeCommandSource(drive, seed, 0, seconds, Pose2{})});
  Simulation sim(std::move(robots), MakeOmniBackend(how.backend, {m}, FieldModel{}, timing), seed);
  const SimulationResult r = sim.Run(static_cast<int>(seconds * how.frame_rate) + 1);
  std::mt19937_64 rng(seed * 104729 + 3);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<OmniLogRow> rows;
  for (const auto& f : r.frames[0]) {
    if (!f.observed) continue;
    OmniLogRow row{f.t + how.jitter * (2 * uniform(rng) - 1), f.seen, f.command};
    if (!rows.empty() && uniform(rng) < how.repeat_share) row.pose = rows.back().pose;  // the camera repeats itself
    rows.push_back(row);
  }
  return ParseOmniLog(FormatOmniLog(rows), "open_world_" + std::to_string(seed) + ".csv");
}

}  // namespace testing
}  // namespace twinsim

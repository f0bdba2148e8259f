#include "diagnosis/diagnosis_plants.h"

#include <gtest/gtest.h>

#include <algorithm>
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

JointTorque Backlash(double inertia, double play, double frequency, double damping_ratio, double sample_time) {
  constexpr int kSubsteps = 20;
  const double stiffness = inertia * std::pow(2 * kPi * frequency, 2);
  const double damping = 2 * damping_ratio * std::sqrt(stiffness * inertia);
  const double h = sample_time / kSubsteps;
  bool started = false;
  double p = 0, pd = 0;  // the part's angle and speed
  return [=](double q, double qd) mutable {
    if (!started) {
      p = q;
      pd = qd;
      started = true;
    }
    double mean = 0;
    for (int s = 0; s < kSubsteps; ++s) {
      const double gap = q - p;  // the joint moves on at qd within the sample
      const double pressed = gap - std::clamp(gap, -play, play);
      double on_part = 0;  // a stop pushes, never pulls
      if (pressed > 0) on_part = std::max(0.0, stiffness * pressed + damping * (qd - pd));
      if (pressed < 0) on_part = std::min(0.0, stiffness * pressed + damping * (qd - pd));
      pd += h * on_part / inertia;  // semi-implicit Euler
      p += h * pd;
      q += h * qd;
      mean -= on_part / kSubsteps;  // what the part pushes back on the joint
    }
    return mean;
  };
}

ArmLog RecordArmPlant(const ArmModel& plant, const ArmModel& hat, std::uint64_t seed, double seconds,
                      const ArmRecording& noise, ArmLog* as_received) {
  TrainingTrialOptions options;
  options.seconds = seconds;
  options.bandwidth = noise.bandwidth;
  options.dither = 0;  // a dither's fast response is lost to the derivative filter: it would read as noise
  options.disturbance = noise.disturbance;
  const ArmReference reference = seed % 2 == 0 ? RandomStopAndGoReference(hat, options, seed)
                                               : SampledReference(RandomTrainingTrajectory(hat, options, seed),
                                                                  hat.sample_time, seconds);
  Eigen::MatrixXd received;
  ArmLog log = RecordArmTrial(plant, hat, reference, options, seed, &received);
  std::mt19937_64 rng(seed * 7919 + 17);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const double count = noise.counts_per_rev > 0 ? 2 * kPi / noise.counts_per_rev : 0;
  for (int r = 0; r < log.rows(); ++r) {
    for (int j = 0; j < log.dof; ++j) {
      if (count > 0) log.q(r, j) = std::round(log.q(r, j) / count) * count;
      const double e = noise.torque_noise * gauss(rng);
      log.tau(r, j) += e;
      received(r, j) += e;
    }
  }
  ArmLogOptions read;
  read.cutoff_hz = noise.cutoff_hz;
  const std::string name = "plant_" + std::to_string(seed) + ".csv";
  if (as_received) {
    ArmLog with = log;
    with.tau = received;
    *as_received = ParseArmLog(FormatArmLog(with, noise.log_velocities), name, read);
  }
  return ParseArmLog(FormatArmLog(log, noise.log_velocities), name, read);
}

ArmModel RrrWith(const std::string& effects_yaml) {
  std::string yaml = "extends: " + SourcePath("models/rrr.yaml") + "\nname: rrr_hidden\n";
  if (!effects_yaml.empty()) yaml += "effects:\n" + effects_yaml;
  return LoadArmModelFromYamlString(yaml, "hidden.yaml");
}

OmniLog RecordOmniPlant(const OmniModel& plant, double seconds, std::uint64_t seed, const FieldModel& field) {
  OmniModel m = plant;
  m.vision_noise_xy = 0.001;
  m.vision_noise_theta = 0.005;
  CommandSpec drive = RandomDrive(1.5, 3, 1.5);
  return RecordLog(m, drive, seconds, seed, "analytic", "omni_plant_" + std::to_string(seed) + ".csv", field);
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

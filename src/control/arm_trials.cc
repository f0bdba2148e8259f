#include "control/arm_trials.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "backends/arm_backend_factory.h"
#include "control/computed_torque.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "core/rng.h"
#include "robots/arm/arm_dynamics.h"
#include "sim/arm_simulation.h"

namespace twinsim {
namespace {

Eigen::VectorXd OrDefault(const Eigen::VectorXd& v, int dof, std::initializer_list<double> rrr, const char* what) {
  if (v.size() == dof) return v;
  if (v.size() == 0 && dof == static_cast<int>(rrr.size())) {
    Eigen::VectorXd out(dof);
    int i = 0;
    for (double x : rrr) out[i++] = x;
    return out;
  }
  throw InputError(std::string("TrainingTrialOptions: ") + what + " needs one value per joint (" +
                   std::to_string(dof) + ")");
}

}  // namespace

bool TrainingTrialOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (!(seconds > 0) || !std::isfinite(seconds)) return fail("seconds must be positive");
  if (!(fundamental > 0) || !std::isfinite(fundamental)) return fail("fundamental must be positive");
  if (harmonics < 1 || harmonics > 50) return fail("harmonics must be 1 to 50");
  if (!(dither >= 0) || !std::isfinite(dither)) return fail("dither must not be negative");
  if (dither_hold < 1) return fail("dither_hold must be at least 1 sample");
  if (!(bandwidth > 0)) return fail("bandwidth must be positive");
  if (!center.allFinite() || !amplitude.allFinite() || (amplitude.array() < 0).any())
    return fail("center and amplitude must be finite, amplitudes not negative");
  return true;
}

FourierTrajectory RandomTrainingTrajectory(const ArmModel& model, const TrainingTrialOptions& options, std::uint64_t seed) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("TrainingTrialOptions: " + why);
  const int n = model.dof(), harmonics = options.harmonics;
  const Eigen::VectorXd center = OrDefault(options.center, n, {0.0, 0.35, -1.1}, "center");
  const Eigen::VectorXd amplitude = OrDefault(options.amplitude, n, {0.7, 0.45, 0.6}, "amplitude");
  FourierTrajectory traj = ZeroFourierTrajectory(n, harmonics, options.fundamental);
  traj.q0 = center;
  Rng rng = Rng::Derived(seed, 0x61726d);  // "arm"
  const double w = traj.omega();
  for (int i = 0; i < n; ++i) {
    // Random amplitudes falling as 1/l, scaled so that their sum is the largest excursion.
    Eigen::VectorXd a(harmonics), phase(harmonics);
    for (int l = 0; l < harmonics; ++l) {
      a[l] = rng.Uniform(0.3, 1.0) / (l + 1);
      phase[l] = rng.Uniform(0, 2 * kPi);
    }
    a *= amplitude[i] / a.sum();
    // A sin(w l t + phi) = (a / (w l)) sin(w l t) - (b / (w l)) cos(w l t) with
    // a = w l A cos(phi), b = -w l A sin(phi).
    for (int l = 0; l < harmonics; ++l) {
      traj.a(i, l) = w * (l + 1) * a[l] * std::cos(phase[l]);
      traj.b(i, l) = -w * (l + 1) * a[l] * std::sin(phase[l]);
    }
    const ArmJoint& joint = model.joints[static_cast<std::size_t>(i)];
    if (center[i] - amplitude[i] < joint.lower + 0.05 || center[i] + amplitude[i] > joint.upper - 0.05) {
      std::ostringstream msg;
      msg << "RandomTrainingTrajectory: joint " << i + 1 << " '" << joint.name << "' would leave its limits ["
          << joint.lower << ", " << joint.upper << "] less 0.05 (centre " << center[i] << ", amplitude "
          << amplitude[i] << ")";
      throw InputError(msg.str());
    }
  }
  traj.model = model.name;
  return traj;
}

ArmReference SampledReference(const FourierTrajectory& trajectory, double sample_time, double seconds) {
  const SampledMotion m = SampleFourier(trajectory, sample_time, seconds);
  ArmReference ref;
  ref.sample_time = sample_time;
  ref.t = Eigen::Map<const Eigen::VectorXd>(m.t.data(), static_cast<long>(m.t.size()));
  ref.q = m.q;
  ref.qd = m.qd;
  ref.qdd = m.qdd;
  return ref;
}

ArmReference RandomStopAndGoReference(const ArmModel& model, const TrainingTrialOptions& options, std::uint64_t seed) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("TrainingTrialOptions: " + why);
  if (!(options.stroke_speed > 0) || !(options.stroke_acceleration > 0))
    throw InputError("TrainingTrialOptions: stroke speed and acceleration must be positive");
  const int n = model.dof();
  const Eigen::VectorXd center = OrDefault(options.center, n, {0.0, 0.35, -1.1}, "center");
  const Eigen::VectorXd amplitude = OrDefault(options.amplitude, n, {0.7, 0.45, 0.6}, "amplitude");
  const double ts = model.sample_time;
  const int samples = static_cast<int>(std::lround(options.seconds / ts));
  Rng rng = Rng::Derived(seed, 0x737467);  // "stg"
  ArmReference ref;
  ref.sample_time = ts;
  ref.t.resize(samples);
  ref.q.resize(samples, n), ref.qd.resize(samples, n), ref.qdd.resize(samples, n);
  Eigen::VectorXd from = center;
  int k = 0;
  while (k < samples) {
    Eigen::VectorXd to(n);
    for (int j = 0; j < n; ++j) to[j] = center[j] + amplitude[j] * rng.Uniform(-1, 1);
    const Eigen::VectorXd delta = to - from;
    const double dist = delta.cwiseAbs().maxCoeff();
    // The path parameter s in [0, dist] on a trapezoid (a triangle for short moves).
    const double v = options.stroke_speed, a = options.stroke_acceleration;
    const double ramp = std::min(v / a, std::sqrt(dist / a));
    const double peak = a * ramp;
    const double cruise = peak > 0 ? (dist - peak * ramp) / peak : 0;
    const double duration = 2 * ramp + cruise;
    const double pause = rng.Uniform(0, 0.2);
    const Eigen::VectorXd dir = dist > 0 ? Eigen::VectorXd(delta / dist) : Eigen::VectorXd::Zero(n);
    const int move_samples = static_cast<int>(std::ceil((duration + pause) / ts));
    for (int i = 0; i < move_samples && k < samples; ++i, ++k) {
      const double t = i * ts;
      double s = dist, sd = 0, sdd = 0;
      if (t < ramp) {
        s = 0.5 * a * t * t, sd = a * t, sdd = a;
      } else if (t < ramp + cruise) {
        s = 0.5 * a * ramp * ramp + peak * (t - ramp), sd = peak;
      } else if (t < duration) {
        const double r = duration - t;
        s = dist - 0.5 * a * r * r, sd = a * r, sdd = -a;
      }
      ref.t[k] = k * ts;
      ref.q.row(k) = (from + s * dir).transpose();
      ref.qd.row(k) = (sd * dir).transpose();
      ref.qdd.row(k) = (sdd * dir).transpose();
    }
    from = to;
  }
  return ref;
}

ArmLog RecordArmTrial(const ArmModel& plant, const ArmModel& hat, const ArmReference& reference,
                      const TrainingTrialOptions& options, std::uint64_t seed, Eigen::MatrixXd* received) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("TrainingTrialOptions: " + why);
  const int n = hat.dof();
  const Eigen::Index samples = reference.t.size();
  if (plant.dof() != n || reference.q.cols() != n || reference.q.rows() != samples || samples < 2)
    throw std::invalid_argument("RecordArmTrial: the plant, model and reference differ in joints or rows");
  if (std::abs(reference.sample_time - plant.sample_time) > 1e-12 * plant.sample_time)
    throw std::invalid_argument("RecordArmTrial: the reference's sample time differs from the plant's");

  ArmSimulation sim(plant, MakeArmBackend(options.backend, plant));
  const TrackingGains gains = ComputedTorqueGains(n, options.bandwidth, 1.0);
  const int preview = plant.delay_samples;
  Eigen::VectorXd limit(n), sigma(n);
  for (int j = 0; j < n; ++j) {
    const double effort = hat.joints[static_cast<std::size_t>(j)].effort_limit;
    limit[j] = effort > 0 ? effort : INFINITY;
    sigma[j] = options.dither * (effort > 0 ? effort : 1.0);
  }
  const Eigen::VectorXd q0 = reference.q.row(0).transpose(), qd0 = reference.qd.row(0).transpose();
  sim.Reset(q0, qd0, InverseDynamics(hat, q0, qd0, reference.qdd.row(0).transpose(), true));

  Rng rng = Rng::Derived(seed, 0x646974);  // "dit"
  Eigen::VectorXd dither = Eigen::VectorXd::Zero(n);
  Eigen::Index k = 0;
  std::vector<Eigen::VectorXd> sent;  // commands before the disturbance
  // A copy per trial: a disturbance with state (a closure) starts every trial afresh.
  const std::function<Eigen::VectorXd(const Eigen::VectorXd&, const Eigen::VectorXd&)> disturbance =
      options.disturbance;
  const ArmController controller = [&](double, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    const Eigen::Index ahead = std::min<Eigen::Index>(k + preview, samples - 1);
    if (k % options.dither_hold == 0)
      for (int j = 0; j < n; ++j) dither[j] = rng.Gaussian(sigma[j]);
    const Eigen::VectorXd qd_a = reference.qd.row(ahead).transpose();
    Eigen::VectorXd tau = ComputedTorque(hat, gains, true, qd_a, reference.q.row(k).transpose(),
                                         reference.qd.row(k).transpose(), reference.qdd.row(ahead).transpose(), q,
                                         qd, nullptr);
    ++k;
    tau += dither;
    tau = tau.cwiseMax(-limit).cwiseMin(limit);
    if (!disturbance) return tau;
    sent.push_back(tau);  // what the log shows
    return Eigen::VectorXd(tau + disturbance(q, qd));
  };
  const ArmTrajectory run = sim.Run(static_cast<int>(samples), controller);

  ArmLog log;
  log.dof = n;
  log.t = run.t;
  log.q = run.q;
  log.qd = run.qd;
  log.tau = run.command;
  if (received) *received = run.command;
  if (options.disturbance) {
    for (Eigen::Index i = 0; i < log.tau.rows() && i < static_cast<Eigen::Index>(sent.size()); ++i) {
      log.tau.row(i) = sent[static_cast<std::size_t>(i)].transpose();
    }
  }
  log.qref = reference.q;
  log.qd_logged = true;
  // Accelerations: the mean over each sample, (qd_{k+1} - qd_k) / Ts, the last repeated.
  log.qdd.resize(samples, n);
  for (Eigen::Index i = 0; i + 1 < samples; ++i)
    log.qdd.row(i) = (run.qd.row(i + 1) - run.qd.row(i)) / plant.sample_time;
  log.qdd.row(samples - 1) = log.qdd.row(samples - 2);
  log.qdd_logged = true;
  log.sample_period = plant.sample_time;
  log.line_of.resize(static_cast<std::size_t>(samples));
  for (Eigen::Index i = 0; i < samples; ++i) log.line_of[static_cast<std::size_t>(i)] = static_cast<int>(i) + 2;
  return log;
}

std::vector<ArmLog> RecordTrainingTrials(const ArmModel& plant, const ArmModel& hat, const TrainingTrialOptions& options,
                                         int count, std::uint64_t first_seed) {
  std::vector<ArmLog> logs;
  for (int i = 0; i < count; ++i) {
    const std::uint64_t seed = first_seed + static_cast<std::uint64_t>(i);
    const int multisine = static_cast<int>(std::lround(count * (1 - options.stop_and_go)));
    const ArmReference ref =
        i < multisine ? SampledReference(RandomTrainingTrajectory(hat, options, seed), plant.sample_time, options.seconds)
                      : RandomStopAndGoReference(hat, options, seed);
    logs.push_back(RecordArmTrial(plant, hat, ref, options, seed));
    logs.back().path = "trial" + std::to_string(seed);
  }
  return logs;
}

}  // namespace twinsim

// Computed-torque and PD + feedforward tracking control and the tracking trial; see
// computed_torque.h.
#include "control/computed_torque.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "core/rng.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_effects.h"
#include "sim/arm_simulation.h"

namespace twinsim {
namespace {

void CheckSize(const char* what, const Eigen::VectorXd& v, int dof) {
  if (v.size() != dof) {
    throw std::invalid_argument(std::string("tracking control: ") + what + " has " + std::to_string(v.size()) +
                                " entries, the model " + std::to_string(dof));
  }
}

void CheckAll(const ArmModel& hat, const TrackingGains& gains, const Eigen::VectorXd& q_r,
              const Eigen::VectorXd& qd_r, const Eigen::VectorXd& qdd_r, const Eigen::VectorXd& q,
              const Eigen::VectorXd& qd) {
  const int n = hat.dof();
  CheckSize("kp", gains.kp, n), CheckSize("kd", gains.kd, n);
  CheckSize("q_r", q_r, n), CheckSize("qd_r", qd_r, n), CheckSize("qdd_r", qdd_r, n);
  CheckSize("q", q, n), CheckSize("qd", qd, n);
}

// rad/s: a joint slower than this at both ends of a sample is taken as stuck.
constexpr double kStuckSpeed = 1e-6;

Eigen::VectorXd Rms(const Eigen::MatrixXd& m) {
  if (m.rows() == 0) return Eigen::VectorXd::Zero(m.cols());
  return (m.array().square().colwise().sum() / static_cast<double>(m.rows())).sqrt().transpose();
}

}  // namespace

std::string TrackingControllerName(TrackingController controller) {
  return controller == TrackingController::kComputedTorque ? "computed_torque" : "pd_feedforward";
}

bool TrackingOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  if (!(std::isfinite(bandwidth) && bandwidth > 0)) return fail("bandwidth must be > 0 (Hz)");
  if (!(std::isfinite(damping) && damping > 0)) return fail("damping must be > 0");
  if (preview < -1) return fail("preview must be >= 0 samples, or -1 for the model's delay");
  if (backend.empty()) return fail("backend is empty");
  if (!(std::isfinite(dither) && dither >= 0)) return fail("dither must be >= 0 (a fraction of the effort limit)");
  if (dither_hold < 1) return fail("dither_hold must be >= 1 sample");
  return true;
}

TrackingGains ComputedTorqueGains(int dof, double bandwidth, double damping) {
  if (!(std::isfinite(bandwidth) && bandwidth > 0) || !(std::isfinite(damping) && damping > 0) || dof < 1) {
    throw std::invalid_argument("ComputedTorqueGains: bandwidth and damping must be > 0 and dof >= 1");
  }
  const double w = 2 * kPi * bandwidth;
  return TrackingGains{Eigen::VectorXd::Constant(dof, w * w), Eigen::VectorXd::Constant(dof, 2 * damping * w)};
}

TrackingGains PdFeedforwardGains(const ArmModel& hat, const Eigen::VectorXd& q0, double bandwidth, double damping) {
  CheckSize("q0", q0, hat.dof());
  TrackingGains g = ComputedTorqueGains(hat.dof(), bandwidth, damping);
  const Eigen::VectorXd m = MassMatrix(hat, q0).diagonal();
  g.kp = g.kp.cwiseProduct(m);
  g.kd = g.kd.cwiseProduct(m);
  return g;
}

Eigen::VectorXd ComputedTorque(const ArmModel& hat, const TrackingGains& gains, bool friction,
                               const Eigen::VectorXd& qd_friction,
                               const Eigen::VectorXd& q_r, const Eigen::VectorXd& qd_r, const Eigen::VectorXd& qdd_r,
                               const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::VectorXd* model_part) {
  CheckAll(hat, gains, q_r, qd_r, qdd_r, q, qd);
  const Eigen::MatrixXd m = MassMatrix(hat, q);
  CheckSize("qd_friction", qd_friction, hat.dof());
  Eigen::VectorXd bias = BiasForces(hat, q, qd);
  if (friction) {
    for (int j = 0; j < hat.dof(); ++j) bias(j) += ArmFrictionTorque(hat, j, q(j), qd_friction(j));
  }
  const Eigen::VectorXd feedback = gains.kd.cwiseProduct(qd_r - qd) + gains.kp.cwiseProduct(q_r - q);
  if (model_part) *model_part = m * qdd_r + bias;
  return m * (qdd_r + feedback) + bias;
}

Eigen::VectorXd PdFeedforwardTorque(const ArmModel& hat, const TrackingGains& gains, bool friction,
                                    const Eigen::VectorXd& q_r, const Eigen::VectorXd& qd_r,
                                    const Eigen::VectorXd& qdd_r, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                    Eigen::VectorXd* model_part) {
  CheckAll(hat, gains, q_r, qd_r, qdd_r, q, qd);
  const Eigen::VectorXd ff = InverseDynamics(hat, q_r, qd_r, qdd_r, friction);
  if (model_part) *model_part = ff;
  return ff + gains.kp.cwiseProduct(q_r - q) + gains.kd.cwiseProduct(qd_r - qd);
}

std::string TrackingTrial::BriefReport() const {
  std::ostringstream out;
  Eigen::Index worst = 0;
  const double e = error_max.size() ? error_max.maxCoeff(&worst) : 0;
  out << controller << " on " << backend << ": max error " << e << " rad (joint " << worst + 1 << "), saturated";
  for (Eigen::Index j = 0; j < saturated_fraction.size(); ++j) {
    out << (j ? " / " : " ") << 100 * saturated_fraction(j) << "%";
  }
  return out.str();
}

std::string TrackingTrial::FullReport() const {
  std::ostringstream out;
  out << BriefReport() << "\n";
  for (Eigen::Index j = 0; j < error_rms.size(); ++j) {
    out << "  joint " << j + 1 << ": error rms " << error_rms(j) << " max " << error_max(j) << " rad; command rms "
        << command_rms(j) << " N·m; model vs command rms " << model_vs_command_rms(j) << " N·m; needed vs applied rms "
        << needed_vs_applied_rms(j) << " N·m; saturated " << 100 * saturated_fraction(j) << "%\n";
  }
  return out.str();
}

TrackingTrial RunTrackingTrial(const ArmModel& plant, const ArmModel& hat, const ArmReference& reference,
                               const TrackingOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("TrackingOptions: " + why);
  return RunTrackingTrial(plant, MakeArmBackend(options.backend, plant, options.backend_options), hat, reference,
                          options);
}

namespace {

// Checks a trial's inputs; throws InputError for invalid options and
// std::invalid_argument for a missing backend or shapes that do not fit.
void CheckTrackingInputs(const ArmModel& plant, const ArmBackend* backend, const ArmModel& hat,
                         const ArmReference& reference, const TrackingOptions& options) {
  if (!backend) throw std::invalid_argument("RunTrackingTrial: no backend");
  std::string why;
  if (!options.IsValid(&why)) throw InputError("TrackingOptions: " + why);
  const int n = hat.dof();
  if (plant.dof() != n) throw std::invalid_argument("RunTrackingTrial: the model and the plant differ in dof");
  const Eigen::Index samples = reference.t.size();
  if (samples < 2 || reference.q.rows() != samples || reference.q.cols() != n || reference.qd.rows() != samples ||
      reference.qd.cols() != n || reference.qdd.rows() != samples || reference.qdd.cols() != n) {
    throw std::invalid_argument("RunTrackingTrial: the reference needs >= 2 rows of q, qd, qdd with one column per joint");
  }
  if (std::abs(reference.sample_time - plant.sample_time) > 1e-12 * plant.sample_time) {
    throw std::invalid_argument("RunTrackingTrial: the reference's sample time differs from the plant's");
  }
  const Eigen::MatrixXd* feedforward = options.feedforward;
  if (feedforward && (feedforward->rows() != samples || feedforward->cols() != n)) {
    throw std::invalid_argument("RunTrackingTrial: the feedforward is " + std::to_string(feedforward->rows()) + " x " +
                                std::to_string(feedforward->cols()) + ", the reference needs " +
                                std::to_string(samples) + " x " + std::to_string(n));
  }
}

// The torque the plant's bodies (`body`: payload lumped) needed for the run's motion,
// per sample (samples x n): rigid bodies plus friction over each interval; a joint that
// does not move over the interval sticks, and then any torque within its Coulomb band
// holds it: the closest to the applied. The last sample repeats the one before.
Eigen::MatrixXd NeededTorque(const ArmModel& body, const ArmTrajectory& run, double sample_time) {
  const Eigen::Index samples = run.q.rows();
  const int n = body.dof();
  Eigen::MatrixXd out(samples, n);
  for (Eigen::Index i = 0; i + 1 < samples; ++i) {
    const Eigen::VectorXd qm = 0.5 * (run.q.row(i) + run.q.row(i + 1)).transpose();
    const Eigen::VectorXd qdm = 0.5 * (run.qd.row(i) + run.qd.row(i + 1)).transpose();
    const Eigen::VectorXd acc = (run.qd.row(i + 1) - run.qd.row(i)).transpose() / sample_time;
    Eigen::VectorXd needed = InverseDynamics(body, qm, qdm, acc, false);
    for (int j = 0; j < n; ++j) {
      const bool stuck = std::abs(run.qd(i, j)) < kStuckSpeed && std::abs(run.qd(i + 1, j)) < kStuckSpeed;
      if (stuck) {
        const double band = std::abs(body.joints[j].coulomb);
        needed(j) += std::clamp(run.applied(i, j) - needed(j), -band, band);
      } else {
        needed(j) += ArmFrictionTorque(body, j, qm(j), qdm(j));
      }
    }
    out.row(i) = needed.transpose();
  }
  out.row(samples - 1) = out.row(samples - 2);
  return out;
}

// The trial's scores: tracking error (RMS and largest per joint), the share of samples
// each joint's demand reached its limit, and the torque mismatches.
void ScoreTrial(const ArmReference& reference, const Eigen::VectorXd& limit, TrackingTrial* trial) {
  const Eigen::MatrixXd error = reference.q - trial->q;
  trial->error_rms = Rms(error);
  trial->error_max = error.cwiseAbs().colwise().maxCoeff().transpose();
  const Eigen::Index samples = trial->demand.rows();
  trial->saturated_fraction.resize(limit.size());
  for (Eigen::Index j = 0; j < limit.size(); ++j) {
    trial->saturated_fraction(j) =
        static_cast<double>((trial->demand.col(j).cwiseAbs().array() >= limit(j)).count()) / static_cast<double>(samples);
  }
  trial->model_vs_command_rms = Rms(trial->command - trial->model_torque);
  trial->needed_vs_applied_rms = Rms(trial->needed - trial->applied);
  trial->command_rms = Rms(trial->command);
}

}  // namespace

TrackingTrial RunTrackingTrial(const ArmModel& plant, std::unique_ptr<ArmBackend> backend, const ArmModel& hat,
                               const ArmReference& reference, const TrackingOptions& options) {
  CheckTrackingInputs(plant, backend.get(), hat, reference, options);
  const int n = hat.dof();
  const Eigen::Index samples = reference.t.size();
  const Eigen::MatrixXd* feedforward = options.feedforward;

  ArmSimulation sim(plant, std::move(backend));
  const ArmModel& body = sim.model();  // the plant with its payload lumped
  const int preview = options.preview >= 0 ? options.preview : plant.delay_samples;
  const Eigen::VectorXd q0 = reference.q.row(0).transpose();
  const TrackingGains gains = options.controller == TrackingController::kComputedTorque
                                  ? ComputedTorqueGains(n, options.bandwidth, options.damping)
                                  : PdFeedforwardGains(hat, q0, options.bandwidth, options.damping);
  Eigen::VectorXd limit(n), dither_sigma(n);
  for (int j = 0; j < n; ++j) {
    const double effort = plant.joints[j].effort_limit;
    limit(j) = effort > 0 ? effort : INFINITY;
    dither_sigma(j) = options.dither * (effort > 0 ? effort : 1.0);
  }
  Rng dither_rng = Rng::Derived(options.dither_seed, 0x646974);  // "dit"
  Eigen::VectorXd dither = Eigen::VectorXd::Zero(n);
  sim.Reset(q0, Eigen::VectorXd::Zero(n), InverseDynamics(hat, q0, Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n), false));

  TrackingTrial trial;
  trial.backend = sim.backend().name();
  trial.controller = TrackingControllerName(options.controller);
  trial.sample_time = plant.sample_time;
  trial.q_ref = reference.q;
  trial.demand.resize(samples, n), trial.model_torque.resize(samples, n);
  Eigen::Index k = 0;
  const ArmController controller = [&](double, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    const Eigen::Index ahead = std::min<Eigen::Index>(k + preview, samples - 1);
    const Eigen::VectorXd q_r = reference.q.row(k).transpose(), qd_r = reference.qd.row(k).transpose();
    // The feedforward acts `preview` samples from now: take the reference then, but
    // keep the feedback on the error measured now.
    const Eigen::VectorXd q_a = reference.q.row(ahead).transpose(), qd_a = reference.qd.row(ahead).transpose();
    Eigen::VectorXd qdd_a = reference.qdd.row(ahead).transpose();
    if (options.interval_acceleration && ahead + 1 < samples) {
      qdd_a = (reference.qd.row(ahead + 1) - reference.qd.row(ahead)).transpose() / reference.sample_time;
    }
    Eigen::VectorXd model_part, tau;
    if (options.controller == TrackingController::kComputedTorque) {
      tau = ComputedTorque(hat, gains, options.friction, options.friction_from_reference ? qd_a : qd, q_r, qd_r,
                           qdd_a, q, qd, &model_part);
    } else {
      tau = PdFeedforwardTorque(hat, gains, options.friction, q_a, qd_a, qdd_a, q, qd, &model_part);
      tau += gains.kp.cwiseProduct(q_r - q_a) + gains.kd.cwiseProduct(qd_r - qd_a);  // feedback on the error now
    }
    if (feedforward) tau += feedforward->row(k).transpose();
    if (options.dither > 0) {
      if (k % options.dither_hold == 0)
        for (int j = 0; j < n; ++j) dither(j) = dither_rng.Gaussian(dither_sigma(j));
      tau += dither;
    }
    trial.demand.row(k) = tau.transpose();
    trial.model_torque.row(k) = model_part.transpose();
    ++k;
    return options.saturate ? Eigen::VectorXd(tau.cwiseMax(-limit).cwiseMin(limit)) : tau;
  };
  const ArmTrajectory run = sim.Run(static_cast<int>(samples), controller);
  trial.t = run.t, trial.q = run.q, trial.qd = run.qd, trial.command = run.command, trial.applied = run.applied;

  trial.needed = NeededTorque(body, run, plant.sample_time);
  ScoreTrial(reference, limit, &trial);
  return trial;
}

}  // namespace twinsim

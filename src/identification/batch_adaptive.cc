#include "identification/batch_adaptive.h"

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/math_constants.h"
#include "core/rng.h"
#include "io/csv_table.h"
#include "io/printf_number.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_integrators.h"

namespace twinsim {
namespace {

// The mean of sign(qd_i) of the reference over [t0, t1]: +-1 unless the velocity
// changes sign inside, then weighted by where (found by bisection).
double MeanSign(const FourierTrajectory& trajectory, int joint, double t0, double t1) {
  auto velocity = [&](double t) { return EvaluateFourier(trajectory, t).qd[joint]; };
  auto sign = [](double v) { return v > 0 ? 1.0 : v < 0 ? -1.0 : 0.0; };
  const double tm = 0.5 * (t0 + t1);
  const double s0 = sign(velocity(t0)), sm = sign(velocity(tm)), s1 = sign(velocity(t1));
  if (s0 == sm && sm == s1) return s0;
  // Each half: the part before the crossing has the start's sign, the rest the end's.
  auto half = [&](double a, double b, double sa, double sb) {
    if (sa == sb) return sa * (b - a);
    double lo = a, hi = b;
    for (int k = 0; k < 50; ++k) {
      const double mid = 0.5 * (lo + hi);
      (sign(velocity(mid)) == sa ? lo : hi) = mid;
    }
    return sa * (lo - a) + sb * (b - lo);
  };
  return (half(t0, tm, s0, sm) + half(tm, t1, sm, s1)) / (t1 - t0);
}

double Quantise(double v, double resolution) { return resolution > 0 ? resolution * std::round(v / resolution) : v; }

}  // namespace

bool ArmTrialOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& what) {
    if (why) *why = what;
    return false;
  };
  if (!(encoder_resolution >= 0)) return fail("encoder resolution must not be negative");
  if (torque_noise.size() > 0 && !(torque_noise.array() >= 0).all())
    return fail("torque noise must not be negative");
  if (substeps < 1) return fail("substeps must be at least 1");
  return true;
}

ArmTrial RunTrial(const ArmModel& plant, const ArmTrialInput& input, const ArmTrialOptions& options, int trial) {
  std::string invalid;
  if (!options.IsValid(&invalid)) throw InputError("trial options: " + invalid);
  const int n = plant.dof();
  const Eigen::Index samples = input.q_ref.rows();
  if (input.q_ref.cols() != n || input.qd_ref.cols() != n || input.feedforward.cols() != n ||
      input.qd_ref.rows() != samples || input.feedforward.rows() != samples || input.hold_command.size() != n ||
      input.kp.size() != n || input.kd.size() != n || samples < 1)
    throw std::invalid_argument("trial input: shapes do not match the plant's " + std::to_string(n) + " joints");
  if (options.torque_noise.size() != 0 && options.torque_noise.size() != n)
    throw InputError("trial options: torque noise needs " + std::to_string(n) + " values");
  if (!(input.sample_time > 0)) throw InputError("trial input: sample time must be positive");

  Rng rng = Rng::Derived(options.seed, static_cast<std::uint64_t>(trial));
  const bool noisy = options.torque_noise.size() == n && (options.torque_noise.array() > 0).any();
  ArmTrial out;
  out.q_measured.resize(samples, n);
  out.feedback.resize(samples, n);
  out.command.resize(samples, n);
  // Commands in flight: what the joints receive over the next delay_samples samples.
  std::deque<Eigen::VectorXd> in_flight(static_cast<std::size_t>(plant.delay_samples), input.hold_command);
  Eigen::VectorXd q = input.q_ref.row(0).transpose(), qd = input.qd_ref.row(0).transpose();
  Eigen::VectorXd previous_error;
  const double h = input.sample_time / options.substeps;
  ArmStepWorkspace work;
  for (Eigen::Index k = 0; k < samples; ++k) {
    Eigen::VectorXd measured(n);
    for (int i = 0; i < n; ++i) measured[i] = Quantise(q[i], options.encoder_resolution);
    const Eigen::VectorXd error = input.q_ref.row(k).transpose() - measured;
    const Eigen::VectorXd error_rate =
        previous_error.size() ? Eigen::VectorXd((error - previous_error) / input.sample_time) : Eigen::VectorXd::Zero(n);
    previous_error = error;
    const Eigen::VectorXd u_fb = input.kp.cwiseProduct(error) + input.kd.cwiseProduct(error_rate);
    const Eigen::VectorXd u = input.feedforward.row(k).transpose() + u_fb;
    out.q_measured.row(k) = measured.transpose();
    out.feedback.row(k) = u_fb.transpose();
    out.command.row(k) = u.transpose();
    in_flight.push_back(u);
    Eigen::VectorXd tau = in_flight.front();
    in_flight.pop_front();
    if (noisy)
      for (int i = 0; i < n; ++i) tau[i] += rng.Gaussian(options.torque_noise[i]);
    for (int s = 0; s < options.substeps; ++s) Rk4Step(plant, tau, h, /*friction=*/true, &work, &q, &qd);
    if (!q.allFinite() || !qd.allFinite() || qd.cwiseAbs().maxCoeff() > 1e4)
      throw CheckFailed("trial " + std::to_string(trial) + " diverged at t = " +
                        PrintfNumber("%.4f", static_cast<double>(k + 1) * input.sample_time) + " s");
  }
  return out;
}

ArmTrialRunner SimulatedTrials(const ArmModel& plant, const ArmTrialOptions& options) {
  return [plant, options](const ArmTrialInput& input, int trial) { return RunTrial(plant, input, options, trial); };
}

bool BatchAdaptiveOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& what) {
    if (why) *why = what;
    return false;
  };
  if (max_trials < 1) return fail("max_trials must be at least 1");
  if (!(tolerance > 0)) return fail("tolerance must be positive");
  if (!(learning_gain > 0 && learning_gain < 2)) return fail("learning gain must be in (0, 2)");
  if (periods < 1) return fail("periods must be at least 1");
  if (!(feedback_bandwidth > 0)) return fail("feedback bandwidth must be positive");
  if (!(feedback_damping > 0)) return fail("feedback damping must be positive");
  if (kp.size() != kd.size()) return fail("kp and kd must both be given or both be empty");
  if (kp.size() && (!(kp.array() > 0).all() || !(kd.array() >= 0).all()))
    return fail("kp must be positive and kd not negative");
  if (joint_weights.size() && !(joint_weights.array() > 0).all()) return fail("joint weights must be positive");
  if (!(velocity_threshold >= 0)) return fail("velocity threshold must not be negative");
  return true;
}

namespace {

// Row block j: the mean of Y_b along the reference over [t_j, t_j+1], which is what a
// torque held over that interval must equal (Simpson's rule; the Coulomb columns' mean
// sign exactly, since sign(qd) jumps inside an interval). (intervals * n) x r.
Eigen::MatrixXd HeldIntervalRegressor(const ArmModel& model, const FourierTrajectory& trajectory,
                                      const BaseParameters& base, int intervals) {
  const int n = model.dof(), r = base.rank();
  const double ts = model.sample_time;
  std::vector<std::pair<int, int>> coulomb;  // (joint, base column)
  for (int c = 0; c < r; ++c) {
    const int k = base.independent[static_cast<std::size_t>(c)] - kParametersPerLink * n;
    if (k >= 0 && k % kFrictionPerJoint == 1) coulomb.emplace_back(k / kFrictionPerJoint, c);
  }
  auto regressor_at = [&](double t) {
    const JointMotion m = EvaluateFourier(trajectory, t);
    return Eigen::MatrixXd(base.Reduce(Regressor(model, m.q, m.qd, m.qdd)));
  };
  Eigen::MatrixXd phi(intervals * n, r);
  Eigen::MatrixXd y_start = regressor_at(0);
  for (int j = 0; j < intervals; ++j) {
    const Eigen::MatrixXd y_end = regressor_at((j + 1) * ts);
    Eigen::MatrixXd y = (y_start + 4 * regressor_at((j + 0.5) * ts) + y_end) / 6;
    for (const auto& [joint, column] : coulomb) y(joint, column) = MeanSign(trajectory, joint, j * ts, (j + 1) * ts);
    phi.middleRows(j * n, n) = y;
    y_start = y_end;
  }
  return phi;
}

// The update's row weights over the intervals whose command was issued in the trial
// (interval d + j for j = 0 .. samples - d - 1), per joint: 0 where the joint is slower
// than the threshold at either end (counted in *left_out).
Eigen::VectorXd UpdateRowWeights(const FourierTrajectory& trajectory, const BatchAdaptiveOptions& options, int n,
                                 int samples, int d, double ts, int* left_out) {
  Eigen::VectorXd row_weight((samples - d) * n);
  *left_out = 0;
  for (int j = 0; j < samples - d; ++j) {
    const JointMotion a = EvaluateFourier(trajectory, (d + j) * ts), b = EvaluateFourier(trajectory, (d + j + 1) * ts);
    for (int i = 0; i < n; ++i) {
      const bool slow = std::min(std::abs(a.qd[i]), std::abs(b.qd[i])) < options.velocity_threshold;
      row_weight[j * n + i] = slow ? 0.0 : options.joint_weights.size() ? std::sqrt(options.joint_weights[i]) : 1.0;
      *left_out += slow;
    }
  }
  return row_weight;
}

// PD gains: the options' where given, else J w^2 and 2 zeta J w, J the nominal inertia
// each joint sees on average over a period.
void FeedbackGains(const ArmModel& model, const FourierTrajectory& trajectory, const BatchAdaptiveOptions& options,
                   BatchAdaptiveResult* result) {
  if (options.kp.size()) {
    result->kp = options.kp;
    result->kd = options.kd;
    return;
  }
  Eigen::VectorXd inertia = Eigen::VectorXd::Zero(model.dof());
  constexpr int kInertiaSamples = 50;
  for (int s = 0; s < kInertiaSamples; ++s)
    inertia += MassMatrix(model, EvaluateFourier(trajectory, s * trajectory.period() / kInertiaSamples).q).diagonal();
  inertia /= kInertiaSamples;
  const double w = 2 * kPi * options.feedback_bandwidth;
  result->kp = inertia * w * w;
  result->kd = inertia * 2 * options.feedback_damping * w;
}

// Throws InputError where the options do not fit the model or are invalid, or the
// trajectory does not fit the model.
void CheckBatchAdaptiveInputs(const ArmModel& model, const FourierTrajectory& trajectory,
                              const BatchAdaptiveOptions& options) {
  std::string invalid;
  if (!options.IsValid(&invalid)) throw InputError("batch-adaptive options: " + invalid);
  CheckTrajectoryFitsModel(trajectory, model, "batch-adaptive");
  const int n = model.dof();
  if (options.kp.size() && options.kp.size() != n)
    throw InputError("batch-adaptive options: kp and kd need " + std::to_string(n) + " values");
  if (options.joint_weights.size() && options.joint_weights.size() != n)
    throw InputError("batch-adaptive options: joint weights need " + std::to_string(n) + " values");
}

// Trial k's record before its update: the estimate it ran with, its tracking error
// against `q_ref` (samples x n) and its feedback's RMS. Throws std::invalid_argument
// for a trial record of another shape than the reference.
BatchAdaptiveTrial TrialRecord(int k, const Eigen::VectorXd& beta, const Eigen::MatrixXd& q_ref, const ArmTrial& trial) {
  const auto samples = q_ref.rows();
  if (trial.feedback.rows() != samples || trial.feedback.cols() != q_ref.cols() ||
      trial.q_measured.rows() != samples || trial.q_measured.cols() != q_ref.cols())
    throw std::invalid_argument("batch-adaptive: trial " + std::to_string(k) + " returned a record of the wrong shape");
  BatchAdaptiveTrial record;
  record.trial = k;
  record.beta_used = beta;
  const Eigen::MatrixXd error = q_ref - trial.q_measured;
  record.error_rms = (error.colwise().squaredNorm() / static_cast<double>(samples)).cwiseSqrt().transpose();
  record.error_max = error.cwiseAbs().colwise().maxCoeff().transpose();
  record.feedback_rms = (trial.feedback.colwise().squaredNorm() / static_cast<double>(samples)).cwiseSqrt().transpose();
  return record;
}

}  // namespace

BatchAdaptiveResult RunBatchAdaptive(const ArmModel& model, const FourierTrajectory& trajectory,
                                     const BatchAdaptiveOptions& options, const ArmTrialRunner& run_trial,
                                     const BatchAdaptiveProgress& progress) {
  const auto started = std::chrono::steady_clock::now();
  CheckBatchAdaptiveInputs(model, trajectory, options);
  const int n = model.dof();

  BatchAdaptiveResult result;
  result.model = model.name;
  result.base = FindBaseParameters(model);
  const BaseParameters& base = result.base;
  const int r = base.rank();
  const std::vector<std::string> standard_names = StandardParameterNames(model);
  for (int c : base.independent) result.short_names.push_back(standard_names[static_cast<std::size_t>(c)]);
  result.initial = options.initial.size() ? options.initial : Eigen::VectorXd(base.from_standard * StandardParameters(model));
  if (result.initial.size() != r)
    throw InputError("batch-adaptive options: the initial estimate needs " + std::to_string(r) + " values");

  // The reference at the sample instants (for the feedback) and the regressor rows at
  // the middle of each hold interval (for the feedforward and the update).
  const double ts = model.sample_time;
  const int d = model.delay_samples;
  const SampledMotion ref = SampleFourier(trajectory, ts, options.periods * trajectory.period());
  const int samples = static_cast<int>(ref.t.size());
  if (samples <= d + 1) throw InputError("batch-adaptive: the trial is shorter than the command delay");
  result.samples_per_trial = samples;
  const Eigen::MatrixXd phi = HeldIntervalRegressor(model, trajectory, base, samples + d);
  // The update's least squares, weighted per joint, solved by QR with scaled columns.
  const int rows = (samples - d) * n;
  const Eigen::VectorXd row_weight = UpdateRowWeights(trajectory, options, n, samples, d, ts, &result.rows_left_out);
  const Eigen::MatrixXd fit_rows = phi.middleRows(d * n, rows);
  result.scales = (fit_rows.colwise().squaredNorm() / rows).cwiseSqrt().transpose();
  for (int c = 0; c < r; ++c)
    if (!(result.scales[c] > 0)) result.scales[c] = 1;
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(row_weight.asDiagonal() * fit_rows *
                                                       result.scales.cwiseInverse().asDiagonal());
  if (qr.rank() < r)
    throw InputError("batch-adaptive: the trajectory does not excite all " + std::to_string(r) +
                     " base parameters (regressor rank " + std::to_string(qr.rank()) + ")");
  FeedbackGains(model, trajectory, options, &result);

  ArmTrialInput input;
  input.sample_time = ts;
  input.q_ref = ref.q;
  input.qd_ref = ref.qd;
  input.kp = result.kp;
  input.kd = result.kd;
  const JointMotion start = EvaluateFourier(trajectory, 0);
  const Eigen::MatrixXd hold_regressor =
      base.Reduce(Regressor(model, start.q, Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n)));

  Eigen::VectorXd beta = result.initial;
  for (int k = 1; k <= options.max_trials; ++k) {
    // The command issued at t_k acts over interval k + d.
    input.feedforward.resize(samples, n);
    for (int j = 0; j < samples; ++j) input.feedforward.row(j) = (phi.middleRows((j + d) * n, n) * beta).transpose();
    input.hold_command = hold_regressor * beta;
    const ArmTrial trial = run_trial(input, k);
    BatchAdaptiveTrial record = TrialRecord(k, beta, ref.q, trial);
    // U_fb: the feedback issued at t_{j-d}, which acted over interval j.
    Eigen::VectorXd u_fb(rows);
    for (int j = 0; j < samples - d; ++j) u_fb.segment(j * n, n) = trial.feedback.row(j).transpose();
    const Eigen::VectorXd step =
        result.scales.cwiseInverse().cwiseProduct(qr.solve(Eigen::VectorXd(row_weight.cwiseProduct(u_fb))));
    const Eigen::VectorXd next = beta + options.learning_gain * step;
    record.beta_next = next;
    record.relative_change =
        (result.scales.cwiseProduct(next - beta)).norm() / std::max((result.scales.cwiseProduct(next)).norm(), 1e-300);
    result.trials.push_back(record);
    beta = next;
    if (progress) progress(k, options.max_trials, record.relative_change);
    if (record.relative_change < options.tolerance) {
      result.converged = true;
      break;
    }
  }
  result.beta = beta;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return result;
}

std::string BatchAdaptiveResult::BriefReport() const {
  if (trials.empty()) return "no trials";
  const BatchAdaptiveTrial& first = trials.front();
  const BatchAdaptiveTrial& last = trials.back();
  Eigen::Index worst = 0;
  first.error_rms.maxCoeff(&worst);
  std::ostringstream s;
  s << (converged ? "converged after " : "not converged after ") << trials.size() << " trial(s): parameter change "
    << PrintfNumber("%.2e", last.relative_change) << ", tracking error RMS " << PrintfNumber("%.4g", first.error_rms[worst] * 1e3)
    << " -> " << PrintfNumber("%.4g", last.error_rms[worst] * 1e3) << " mrad (joint " << worst + 1 << ")";
  return s.str();
}

std::string BatchAdaptiveResult::FullReport() const {
  std::ostringstream s;
  const int n = static_cast<int>(kp.size());
  s << "Batch-adaptive estimation for " << model << ": " << base.rank() << " base parameters, " << samples_per_trial
    << " samples per trial\n";
  s << "PD gains: kp";
  for (int i = 0; i < n; ++i) s << " " << PrintfNumber("%.4g", kp[i]);
  s << ", kd";
  for (int i = 0; i < n; ++i) s << " " << PrintfNumber("%.4g", kd[i]);
  s << "\n  trial     change";
  for (int i = 1; i <= n; ++i) s << "   rms" << i << " [mrad]";
  for (int i = 1; i <= n; ++i) s << "   fb" << i << " [N m]";
  s << "\n";
  for (const BatchAdaptiveTrial& t : trials) {
    s << PrintfNumber("  %5.0f", t.trial) << PrintfNumber("   %.2e", t.relative_change);
    for (int i = 0; i < n; ++i) s << PrintfNumber("   %11.4g", t.error_rms[i] * 1e3);
    for (int i = 0; i < n; ++i) s << PrintfNumber("   %9.4g", t.feedback_rms[i]);
    s << "\n";
  }
  s << "estimates (initial -> final):\n";
  for (int c = 0; c < base.rank(); ++c) {
    char line[256];
    std::snprintf(line, sizeof line, "  %-8s %12.6g -> %12.6g   %s\n", short_names[static_cast<std::size_t>(c)].c_str(),
                  initial[c], beta[c], base.names[static_cast<std::size_t>(c)].c_str());
    s << line;
  }
  s << BriefReport() << "\n";
  return s.str();
}

std::string FormatBatchAdaptiveCsv(const BatchAdaptiveResult& result) {
  const int n = static_cast<int>(result.kp.size());
  std::string out = "trial";
  for (const std::string& name : result.short_names) {
    out += ',';
    out += name;
  }
  for (const char* prefix : {"rms", "max", "fb_rms"})
    for (int i = 1; i <= n; ++i) {
      out += ',';
      out += prefix;
      out += std::to_string(i);
    }
  out += ",change\n";
  for (const BatchAdaptiveTrial& t : result.trials) {
    out += std::to_string(t.trial);
    for (const Eigen::VectorXd* v : {&t.beta_next, &t.error_rms, &t.error_max, &t.feedback_rms})
      for (Eigen::Index i = 0; i < v->size(); ++i) {
        out += ',';
        out += FormatCsvNumber((*v)[i]);
      }
    out += ',';
    // The change is often far below FormatCsvNumber's 1e-9 resolution.
    out += PrintfNumber("%.6e", t.relative_change);
    out += '\n';
  }
  return out;
}

}  // namespace twinsim

#include "analysis/arm_output_error.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>
#include <vector>

#include "analysis/arm_fit_coordinates.h"
#include "analysis/arm_replay.h"
#include "analysis/arm_shooting.h"
#include "analysis/arm_simulation_score.h"
#include "analysis/fit_covariance.h"
#include "analysis/fixed_step_cost.h"
#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "io/csv_table.h"
#include "identification/wls_identification.h"
#include "sim/arm_simulation.h"

namespace twinsim {

bool ArmOutputErrorOptions::IsValid(std::string* why) const {
  if (presliding != ArmPresliding::kNone && !stribeck) {
    *why = "pre-sliding fits the Stribeck curve's bristles: it needs the Stribeck fit too";
    return false;
  }
  if (!whole_run && (!std::isfinite(horizon) || horizon <= 0)) {
    *why = "the output-error horizon must be a positive number of seconds";
    return false;
  }
  for (double h : also_horizons) {
    if (whole_run || !std::isfinite(h) || h <= 0) {
      *why = whole_run ? "whole runs take no window lengths beside them"
                       : "the output-error horizon must be a positive number of seconds";
      return false;
    }
  }
  if (whole_run && (!std::isfinite(segment) || segment <= 0)) {
    *why = "the shooting segments must be a positive number of seconds";
    return false;
  }

  if (max_iterations < 1) {
    *why = "the output-error fit needs at least one iteration";
    return false;
  }
  if (!std::isfinite(torque_weight) || torque_weight < 0) {
    *why = "the torque rows' weight must be 0 or more";
    return false;
  }
  if (threads < 0) {
    *why = "threads must be 0 (one per core) or more";
    return false;
  }
  if (!(rest_share >= 0 && rest_share < 1)) {
    *why = "the rest share must lie in [0, 1)";
    return false;
  }
  return true;
}

namespace {

// The coordinates' step for the central differences: 0.1 % of a scale or a friction,
// a hundredth of a percent of a joint's torque RMS for an offset.
constexpr double kStep = 1e-3;

// The share of the held-out windows' cost (their squared errors over the baseline's)
// the low-speed friction must remove to be kept: 2n parameters more must earn their
// place (measured on a plant without it: 3 % from fitting the engines' differences).
constexpr double kLowSpeedGain = 0.1;

// One window length's windows over the logs: per log the fit and held-out windows' first
// rows and their length, the simulated fit rows, the constant-velocity baseline's RMSE on
// them per joint and each joint's residual weight.
struct WindowSet {
  std::vector<std::vector<int>> fit, check;
  std::vector<int> lengths;
  int fit_windows = 0, check_windows = 0;
  std::size_t rows = 0;
  Eigen::VectorXd constant_velocity, weight;
};

// Where a window from row s simulating `length` rows lies against the held-out
// `stretches` (first row, rows simulated after it): wholly inside one (held out with it),
// apart from all (fitted), or across an edge (neither: its rows on one side are held out,
// on the other fitted by the longer windows). Sharing only a first row (one window's
// logged start the other's last row) is not meeting: a start is no score.
enum class Against { kApart, kInside, kAcross };
Against Place(int s, int length, const std::vector<std::pair<int, int>>& stretches) {
  for (const auto& [first, rows] : stretches) {
    if (!(s < first + rows && first < s + length)) continue;
    return first <= s && s + length <= first + rows ? Against::kInside : Against::kAcross;
  }
  return Against::kApart;
}

// The fit's data; its coordinates are ArmFitCoordinates'.
class OutputErrorProblem {
 public:
  OutputErrorProblem(const ArmModel& start, const std::vector<ArmLog>& logs, const ArmOutputErrorOptions& options)
      : start_(start),
        logs_(logs),
        options_(options),
        n_(start.dof()),
        coordinates_(start, logs, options.offsets, options.stribeck, options.presliding) {
    std::vector<double> horizons{options_.horizon};
    horizons.insert(horizons.end(), options_.also_horizons.begin(), options_.also_horizons.end());
    longest_ = static_cast<std::size_t>(std::max_element(horizons.begin(), horizons.end()) - horizons.begin());
    sets_.resize(horizons.size());
    // The longest set first: its every fourth window (counted over the logs) is held out,
    // the other sets' windows wholly inside those with them, and those across their edges
    // neither fitted nor held out (Place).
    std::vector<std::vector<std::pair<int, int>>> held(logs_.size());
    std::vector<std::size_t> order{longest_};
    for (std::size_t k = 0; k < sets_.size(); ++k)
      if (k != longest_) order.push_back(k);
    int window = 0;
    for (std::size_t k : order) {
      WindowSet& set = sets_[k];
      Eigen::ArrayXd velocity2 = Eigen::ArrayXd::Zero(n_);
      for (std::size_t l = 0; l < logs_.size(); ++l) {
        const ArmLog& log = logs_[l];
        if (k == longest_) CheckArmLogMatchesModel(log, start_);
        int length = 0;
        const std::vector<int> starts =
            ArmSimulationWindows(ArmModelAtLogPeriod(start_, log.sample_period), log, horizons[k], &length);
        set.fit.emplace_back();
        set.check.emplace_back();
        set.lengths.push_back(length);
        for (int s : starts) {
          const Against place = k == longest_ ? Against::kApart : Place(s, length, held[l]);
          if (place == Against::kAcross) continue;
          const bool check = k == longest_ ? window++ % 4 == 3 : place == Against::kInside;
          if (check) {
            if (k == longest_) held[l].emplace_back(s, length);
            set.check.back().push_back(s);
            ++set.check_windows;
            continue;
          }
          set.fit.back().push_back(s);
          ++set.fit_windows;
          for (int r = 0; r < length; ++r)
            velocity2 += (ConstantVelocityQ(log, s, r + 1) - log.q.row(s + 1 + r)).array().square().transpose();
          set.rows += static_cast<std::size_t>(length);
        }
      }
      if ((k == longest_ && window < 4) || set.rows == 0) {
        const std::string seconds = OutputErrorWindowLengths(horizons[k], {});
        throw InputError(SourceLocation{logs_.empty() ? std::string("(no log)") : logs_.front().path, 1},
                         k == longest_ ? "the logs are too short for the output-error fit: it needs at least 4 windows "
                                         "of the horizon (one held out), they hold " + std::to_string(window) +
                                             (sets_.size() > 1 ? " of " + seconds + " s" : "")
                                       : std::string("the logs hold no window of ") + seconds +
                                             " s outside the held-out longer ones to fit");
      }
      const double rows = static_cast<double>(set.rows);
      set.constant_velocity = (velocity2 / rows).sqrt().matrix();
      // Each block's residuals scaled so that its squares start near 1 per joint: the
      // simulation's by the constant-velocity baseline, the torques' by the start's error.
      set.weight = (set.constant_velocity.array().max(1e-12) * std::sqrt(rows)).inverse().matrix();
    }
    Eigen::ArrayXd torque_error2 = Eigen::ArrayXd::Zero(n_);
    for (const ArmLog& log : logs_) torque_rows_ += static_cast<std::size_t>(log.rows() - 2 * log.edge_samples);
    const Eigen::VectorXd rest_speed = ArmRestSpeeds(logs_, options_.rest_share);
    for (const ArmLog& log : logs_) rest_.push_back(ArmRestRows(log, rest_speed));
    for (std::size_t k = 0; k < logs_.size(); ++k)
      TorqueErrors(start_, k, [&](int j, double e) { torque_error2[j] += e * e; });
    const double torque_rows = static_cast<double>(std::max<std::size_t>(torque_rows_, 1));
    const Eigen::ArrayXd torque_rmse = (torque_error2 / torque_rows).sqrt().max(1e-12);
    torque_weight_ = (std::sqrt(options_.torque_weight) / (torque_rmse * std::sqrt(torque_rows))).matrix();
  }

  const ArmFitCoordinates& coordinates() const { return coordinates_; }
  int parameters() const { return coordinates_.parameters(); }
  // The fit's residuals: the simulated rows' position errors, then the torque rows'.
  std::size_t residuals() const {
    std::size_t rows = torque_rows_;
    for (const WindowSet& set : sets_) rows += set.rows;
    return rows * static_cast<std::size_t>(n_);
  }
  // `horizon`'s windows (the first set): what the summary reports.
  int fit_windows() const { return sets_.front().fit_windows; }
  int check_windows() const { return sets_.front().check_windows; }
  const Eigen::VectorXd& constant_velocity() const { return sets_.front().constant_velocity; }
  // Per joint, the position RMSE of `horizon`'s fit windows (`check` false) or held-out ones.
  Eigen::VectorXd FirstSimulationRmse(const ArmModel& model, bool check) const {
    return SimulationRmse(sets_.front(), model, check);
  }

  // The model for coordinates x (0: the start, frictions raised to their floors).
  ArmModel Apply(const double* x) const { return coordinates_.Apply(x); }

  // The fit's weighted residuals: the position errors of every fit window of every set
  // and log, row by row, joint by joint; then the torque errors of every log's rows.
  void Residual(const ArmModel& model, double* out) const {
    std::size_t i = 0;
    for (const WindowSet& set : sets_) {
      SimulateWindows(set, model, false, [&](const ArmLog& log, int s, const Eigen::MatrixXd& q) {
        for (Eigen::Index r = 0; r < q.rows(); ++r)
          for (int j = 0; j < n_; ++j) out[i++] = (q(r, j) - log.q(s + 1 + r, j)) * set.weight[j];
      });
    }
    for (std::size_t k = 0; k < logs_.size(); ++k)
      TorqueErrors(model, k, [&](int j, double e) { out[i++] = e * torque_weight_[j]; });
  }

  // The torque rows' errors of `model` on log k, row by row, joint by joint, as
  // identification fits them: 0 where the joint is at rest or near it (its friction
  // anywhere in its band; ArmRestRows).
  template <typename Visit>
  void TorqueErrors(const ArmModel& model, std::size_t k, const Visit& visit) const {
    const ArmLog& log = logs_[k];
    const Eigen::MatrixXd tau = PredictArmCommands(model, log);
    for (int r = log.edge_samples; r < log.rows() - log.edge_samples; ++r)
      for (int j = 0; j < n_; ++j) visit(j, rest_[k](r, j) ? 0.0 : tau(r, j) - log.tau(r, j));
  }

  // Each residual's cluster for the standard errors: a stretch of its log as long as the
  // longest set's window (numbered from 0 over the logs), holding the simulated rows of
  // the fit windows that start in it and the torque rows in it. In Residual's order.
  std::vector<int> Clusters() const {
    std::vector<int> out, first;
    out.reserve(residuals());
    const std::vector<int>& stretch = sets_[longest_].lengths;
    int stretches = 0;
    for (std::size_t l = 0; l < logs_.size(); ++l) {
      first.push_back(stretches);
      stretches += logs_[l].rows() / stretch[l] + 1;
    }
    for (const WindowSet& set : sets_)
      for (std::size_t l = 0; l < logs_.size(); ++l)
        for (int s : set.fit[l])
          out.insert(out.end(), static_cast<std::size_t>(set.lengths[l] * n_), first[l] + s / stretch[l]);
    for (std::size_t l = 0; l < logs_.size(); ++l)
      for (int r = logs_[l].edge_samples; r < logs_[l].rows() - logs_[l].edge_samples; ++r)
        out.insert(out.end(), static_cast<std::size_t>(n_), first[l] + r / stretch[l]);
    return out;
  }

  // Per length (`horizon`'s first) and joint, the position RMSE of the fit windows
  // (`check` false) or the held-out ones.
  std::vector<Eigen::VectorXd> SimulationRmse(const ArmModel& model, bool check) const {
    std::vector<Eigen::VectorXd> out;
    for (const WindowSet& set : sets_) out.push_back(SimulationRmse(set, model, check));
    return out;
  }

  // The cost the decisions compare: over every length, each joint's RMSE (SimulationRmse)
  // against the constant-velocity baseline, squared.
  double Cost(const std::vector<Eigen::VectorXd>& rmse) const {
    double cost = 0;
    for (std::size_t k = 0; k < sets_.size(); ++k)
      cost += (rmse[k].array() / sets_[k].constant_velocity.array().max(1e-12)).square().sum();
    return cost;
  }

 private:
  Eigen::VectorXd SimulationRmse(const WindowSet& set, const ArmModel& model, bool check) const {
    Eigen::ArrayXd squares = Eigen::ArrayXd::Zero(n_);
    double rows = 0;
    SimulateWindows(set, model, check, [&](const ArmLog& log, int s, const Eigen::MatrixXd& q) {
      squares += (q - log.q.middleRows(s + 1, q.rows())).array().square().colwise().sum().transpose();
      rows += static_cast<double>(q.rows());
    });
    return (squares / std::max(1.0, rows)).sqrt().matrix();
  }

  // Simulates `model` over the set's fit windows (or, with `check`, the held-out ones) of
  // every log, calling each(log, first row, the simulated q of the rows after it).
  template <typename Each>
  void SimulateWindows(const WindowSet& set, const ArmModel& model, bool check, const Each& each) const {
    Eigen::MatrixXd q;
    for (std::size_t l = 0; l < logs_.size(); ++l) {
      const ArmLog& log = logs_[l];
      const ArmModel at = ArmModelAtLogPeriod(model, log.sample_period);
      ArmSimulation sim(at, MakeArmBackend(options_.backend, at));
      for (int s : (check ? set.check : set.fit)[l]) {
        SimulateArmFromLog(&sim, log, s, set.lengths[l], &q, true);
        each(log, s, q);
      }
    }
  }

  const ArmModel& start_;
  const std::vector<ArmLog>& logs_;
  ArmOutputErrorOptions options_;
  int n_;
  std::vector<WindowSet> sets_;  // `horizon`'s first, then also_horizons'
  std::size_t longest_ = 0;      // the set whose windows decide what is held out
  std::size_t torque_rows_ = 0;
  ArmFitCoordinates coordinates_;
  Eigen::VectorXd torque_weight_;
  std::vector<Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic>> rest_;  // per log: rows at rest, not scored
};

// Levenberg-Marquardt from `x` within the problem's bounds; the coordinates found into
// *x, the iterations taken returned, those that ended at a bound into *at_bound, their
// standard errors into *se (one Jacobian more).
int Solve(const OutputErrorProblem& problem, const ArmOutputErrorOptions& options, std::vector<double>* x,
          std::vector<int>* at_bound, std::vector<double>* se) {
  const int p = problem.parameters();
  ceres::Problem ceres_problem;
  // Central differences at kStep in every coordinate, the columns simulated on
  // options.threads threads.
  auto* cost = new FixedStepCost(problem.residuals(), std::vector<double>(x->size(), kStep),
                                 [&problem](const double* at, double* out) {
                                   problem.Residual(problem.Apply(at), out);
                                   return true;
                                 },
                                 options.threads);
  const ceres::ResidualBlockId block = ceres_problem.AddResidualBlock(cost, nullptr, x->data());
  std::vector<double> lower(static_cast<std::size_t>(p)), upper(static_cast<std::size_t>(p));
  for (int k = 0; k < p; ++k) problem.coordinates().Bounds(k, &lower[k], &upper[k]);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = 1e-9;
  solver.parameter_tolerance = 1e-8;
  solver.num_threads = 1;  // the cost simulates its columns in parallel itself
  solver.logging_type = ceres::SILENT;
  const int iterations = SolveWithinBounds(&ceres_problem, x, lower, upper, solver, at_bound);
  *se = ClusteredStandardErrors(&ceres_problem, {x->data()}, {block}, p, *at_bound, problem.Clusters());
  return iterations;
}

// The summary's fits, parameters and bounds: `plain` the plain refinement's problem,
// `used` the one whose coordinates x are (plain, or the low-speed one), `floor` the start
// with its frictions raised to their floors, `with` the low-speed fit (read only when
// `stribeck_tried`). The check windows, iterations and decisions are the caller's.
ArmOutputErrorSummary Summarise(const OutputErrorProblem& plain, const OutputErrorProblem& used, const ArmModel& start,
                                const ArmModel& floor, const ArmModel& fitted, const std::vector<double>& x,
                                const std::vector<int>& at_bound, const std::vector<double>& se,
                                const ArmOutputErrorOptions& options) {
  ArmOutputErrorSummary s;
  s.horizon = options.horizon;
  s.also_horizons = options.also_horizons;
  s.fit_windows = plain.fit_windows();
  s.check_windows = plain.check_windows();
  s.rmse_before = plain.FirstSimulationRmse(floor, false);
  s.rmse_after = plain.FirstSimulationRmse(fitted, false);
  s.constant_velocity = plain.constant_velocity();
  SummariseArmFit(used.coordinates(), start, fitted, x, at_bound, se, &s);
  return s;
}

}  // namespace

void SummariseArmFit(const ArmFitCoordinates& coordinates, const ArmModel& start, const ArmModel& fitted,
                     const std::vector<double>& x, const std::vector<int>& at_bound, const std::vector<double>& se,
                     ArmOutputErrorSummary* s) {
  const int n = start.dof();
  s->scale.resize(n);
  s->viscous_before.resize(n), s->viscous_after.resize(n), s->coulomb_before.resize(n), s->coulomb_after.resize(n);
  s->offset_before.resize(n), s->offset_after.resize(n);
  for (int j = 0; j < n; ++j) {
    s->scale[j] = std::exp(x[static_cast<std::size_t>(j)]);
    s->viscous_before[j] = start.joints[j].viscous;
    s->coulomb_before[j] = start.joints[j].coulomb;
    s->viscous_after[j] = fitted.joints[j].viscous;
    s->coulomb_after[j] = fitted.joints[j].coulomb;
    s->offset_before[j] = start.effects.joint(j).torque_offset;
    s->offset_after[j] = fitted.effects.joint(j).torque_offset;
  }
  s->at_bound = coordinates.Names(at_bound);
  const int blocks = coordinates.parameters() / n;
  s->standard_error.resize(se.empty() ? 0 : n, se.empty() ? 0 : blocks);
  s->standard_error_kinds.clear();
  for (int b = 0; b < blocks && !se.empty(); ++b) {
    s->standard_error_kinds.push_back(coordinates.KindOf(b * n));
    for (int j = 0; j < n; ++j) {
      const int k = b * n + j;
      s->standard_error(j, b) = coordinates.ValueError(k, se[static_cast<std::size_t>(k)]);
    }
  }
}

void SummariseLowSpeedFriction(const ArmModel& with, bool tried, bool kept, const Eigen::VectorXd& check_plain,
                               ArmOutputErrorSummary* s) {
  s->stribeck_tried = tried;
  s->stribeck_kept = kept;
  s->check_plain = tried ? check_plain : Eigen::VectorXd();
  if (!tried) return;
  const int n = with.dof();
  s->breakaway.resize(n);
  s->stribeck_velocity.resize(n);
  s->bristle_stiffness.resize(with.effects.joint(0).presliding() ? n : 0);
  for (int j = 0; j < n; ++j) {
    const JointEffects& e = with.effects.joint(j);
    s->breakaway[j] = e.stribeck_static - e.stribeck_coulomb;
    s->stribeck_velocity[j] = e.stribeck_velocity;
    if (s->bristle_stiffness.size() > 0) s->bristle_stiffness[j] = e.bristle_stiffness;
  }
}

double ArmOutputErrorStartCost(const ArmModel& model, const std::vector<ArmLog>& logs,
                               const ArmOutputErrorOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  if (logs.empty()) throw InputError("output error: no log to fit");
  if (options.whole_run) return ArmShootingStartCost(model, logs, options);
  ArmOutputErrorOptions windows = options;
  windows.stribeck = false;
  windows.presliding = ArmPresliding::kNone;
  const OutputErrorProblem problem(model, logs, windows);
  const std::vector<double> x(static_cast<std::size_t>(problem.parameters()), 0.0);
  return problem.Cost(problem.SimulationRmse(problem.Apply(x.data()), false));
}

ArmModel RefineArmByOutputError(const ArmModel& start, const std::vector<ArmLog>& logs,
                                const ArmOutputErrorOptions& options, ArmOutputErrorSummary* summary) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  if (logs.empty()) throw InputError("output error: no log to fit");
  if (options.whole_run) return RefineArmByShooting(start, logs, options, summary);
  ArmOutputErrorOptions plain_options = options;
  plain_options.stribeck = false;
  plain_options.presliding = ArmPresliding::kNone;
  const OutputErrorProblem plain(start, logs, plain_options);
  std::vector<double> x(static_cast<std::size_t>(plain.parameters()), 0.0);
  const ArmModel floor = plain.Apply(x.data());
  std::vector<int> at_bound;
  std::vector<double> se;
  int iterations = Solve(plain, plain_options, &x, &at_bound, &se);
  ArmModel fitted = plain.Apply(x.data());
  // Kept only where the held-out windows get better.
  const std::vector<Eigen::VectorXd> check_before = plain.SimulationRmse(floor, true);
  std::vector<Eigen::VectorXd> check_after = plain.SimulationRmse(fitted, true);
  const bool kept = plain.Cost(check_after) < plain.Cost(check_before);
  const OutputErrorProblem* final_problem = &plain;

  // Friction that holds at low speed: fitted from where a kept plain refinement ended (a
  // refinement not kept returns the start, so a fit on top of it could not be used), and
  // kept where it simulates the held-out windows better still.
  std::unique_ptr<OutputErrorProblem> low_speed;
  const std::vector<Eigen::VectorXd> check_plain = check_after;
  const bool stribeck_tried = options.stribeck && kept;
  bool stribeck_kept = false;
  ArmModel with;  // the low-speed fit, kept or not
  std::vector<std::string> low_speed_at_bound;
  if (stribeck_tried) {
    low_speed = std::make_unique<OutputErrorProblem>(start, logs, options);
    std::vector<double> y = x;
    y.resize(static_cast<std::size_t>(low_speed->parameters()), 0.0);
    std::vector<int> y_bound;
    std::vector<double> y_se;
    const int y_iterations = Solve(*low_speed, options, &y, &y_bound, &y_se);
    with = low_speed->Apply(y.data());
    const std::vector<Eigen::VectorXd> check_with = low_speed->SimulationRmse(with, true);
    stribeck_kept = low_speed->Cost(check_with) < (1 - kLowSpeedGain) * plain.Cost(check_plain);
    low_speed_at_bound = low_speed->coordinates().Names(y_bound);
    if (stribeck_kept) {
      x = std::move(y);
      at_bound = std::move(y_bound);
      se = std::move(y_se);
      iterations += y_iterations;
      fitted = with;
      check_after = check_with;
      final_problem = low_speed.get();
    }
  }

  if (summary) {
    *summary = Summarise(plain, *final_problem, start, floor, fitted, x, at_bound, se, options);
    summary->iterations = iterations;
    summary->kept = kept;
    SummariseLowSpeedFriction(with, stribeck_tried, stribeck_kept, check_plain.front(), summary);
    summary->low_speed_at_bound = std::move(low_speed_at_bound);
    summary->check_before = check_before.front();
    summary->check_after = check_after.front();
  }
  if (!kept) return start;
  return fitted;
}

namespace {

// The summary's standard errors: a row per joint, a column per coordinate block.
std::string StandardErrorTable(const ArmOutputErrorSummary& s) {
  std::string text = s.whole_run ? "standard errors (each shooting segment an independent cluster; % of the value, "
                                   "offsets in N·m or N):\n"
                                 : "standard errors (each window-long stretch of the logs an independent cluster; % "
                                   "of the value, offsets in N·m or N):\n";
  char cell[64];
  std::snprintf(cell, sizeof cell, "%-6s", "joint");
  text += cell;
  for (ArmFitCoordinates::Kind kind : s.standard_error_kinds) {
    std::snprintf(cell, sizeof cell, " %13s", ArmFitCoordinates::Heading(kind).c_str());
    text += cell;
  }
  text += "\n";
  for (Eigen::Index j = 0; j < s.standard_error.rows(); ++j) {
    std::snprintf(cell, sizeof cell, "%-6d", static_cast<int>(j + 1));
    text += cell;
    for (Eigen::Index b = 0; b < s.standard_error.cols(); ++b) {
      const double e = s.standard_error(j, b);
      const bool relative = ArmFitCoordinates::Relative(s.standard_error_kinds[static_cast<std::size_t>(b)]);
      if (std::isnan(e)) {
        std::snprintf(cell, sizeof cell, " %13s", "at bound");
      } else if (std::isinf(e)) {
        std::snprintf(cell, sizeof cell, " %13s", "undetermined");
      } else if (!relative) {
        std::snprintf(cell, sizeof cell, " %13.3g", e);
      } else if (e > 10) {  // ten times the value: the delta method says no more than that
        std::snprintf(cell, sizeof cell, " %13s", "> 1000 %");
      } else {
        std::snprintf(cell, sizeof cell, " %11.3g %%", 100 * e);
      }
      text += cell;
    }
    text += "\n";
  }
  return text;
}

// With whole_run: the fit's first line and its per-joint table of free runs and values.
std::string WholeRunTable(const ArmOutputErrorSummary& s) {
  std::string text;
  char line[320];
  const int n = static_cast<int>(s.scale.size());
  std::snprintf(line, sizeof line,
                "output error over whole runs: each log's first three quarters fitted by multiple shooting (%d "
                "segments of %g s; largest defect left %.3g of the spread of q), its last quarter held out and "
                "simulated free; %d iterations\n",
                s.segments, s.segment, s.largest_defect, s.iterations);
  text += line;
  std::snprintf(line, sizeof line, "%-6s %35s %35s %8s %23s %23s %23s\n", "joint", "fitted part's free run (fit %)",
                "held-out quarter's free run (fit %)", "scale k", "viscous", "Coulomb", "offset tau0");
  text += line;
  const auto fit = [](double rmse, double spread) { return spread > 0 ? 100 * (1 - rmse / spread) : 0.0; };
  for (int j = 0; j < n; ++j) {
    std::snprintf(line, sizeof line,
                  "%-6d %9.4g (%5.1f) -> %9.4g (%5.1f)  %9.4g (%5.1f) -> %9.4g (%5.1f) %8.4g %10.4g -> %10.4g "
                  "%10.4g -> %10.4g %10.4g -> %10.4g\n",
                  j + 1, s.rmse_before[j], fit(s.rmse_before[j], s.spread_fit[j]), s.rmse_after[j],
                  fit(s.rmse_after[j], s.spread_fit[j]), s.check_before[j], fit(s.check_before[j], s.spread_check[j]),
                  s.check_after[j], fit(s.check_after[j], s.spread_check[j]), s.scale[j], s.viscous_before[j],
                  s.viscous_after[j], s.coulomb_before[j], s.coulomb_after[j], s.offset_before[j], s.offset_after[j]);
    text += line;
  }
  return text;
}

}  // namespace

std::string OutputErrorWindowLengths(double horizon, const std::vector<double>& also) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", horizon);
  std::string out = text;
  for (std::size_t k = 0; k < also.size(); ++k) {
    std::snprintf(text, sizeof text, "%s%g", k + 1 == also.size() ? " and " : ", ", also[k]);
    out += text;
  }
  return out;
}

std::string FormatArmOutputErrorCsv(const std::vector<ArmOutputErrorSummary>& stages) {
  using Kind = ArmFitCoordinates::Kind;
  std::string csv = "stage,joint,coordinate,value,standard_error\n";
  for (std::size_t k = 0; k < stages.size(); ++k) {
    const ArmOutputErrorSummary& s = stages[k];
    for (Eigen::Index j = 0; j < s.standard_error.rows(); ++j) {
      for (std::size_t b = 0; b < s.standard_error_kinds.size(); ++b) {
        const Kind kind = s.standard_error_kinds[b];
        const double value = kind == Kind::kScale              ? s.scale[j]
                             : kind == Kind::kViscous          ? s.viscous_after[j]
                             : kind == Kind::kCoulomb          ? s.coulomb_after[j]
                             : kind == Kind::kOffset           ? s.offset_after[j]
                             : kind == Kind::kBreakaway        ? s.breakaway[j]
                             : kind == Kind::kStribeckVelocity ? s.stribeck_velocity[j]
                                                               : s.bristle_stiffness[j];
        const double e = s.standard_error(j, static_cast<Eigen::Index>(b));
        const double error = ArmFitCoordinates::Relative(kind) ? e * std::abs(value) : e;
        csv += std::to_string(k + 1) + "," + std::to_string(j + 1) + "," + ArmFitCoordinates::Key(kind) + "," +
               FormatCsvNumber(value) + "," +
               (std::isnan(error) ? std::string() : std::isinf(error) ? std::string("inf") : FormatCsvNumber(error)) +
               "\n";
      }
    }
  }
  return csv;
}

std::string ArmOutputErrorSummary::FullReport() const {
  std::string text;
  char line[320];
  const int n = static_cast<int>(scale.size());
  if (whole_run) {
    text += WholeRunTable(*this);
  } else {
    std::snprintf(line, sizeof line,
                  "output error: windows of %g s simulated from the logged torques, %d fitted and %d held out; %d "
                  "iterations\n",
                  horizon, fit_windows, check_windows, iterations);
    text += line;
    if (!also_horizons.empty())
      text += "  windows of " + OutputErrorWindowLengths(horizon, also_horizons) +
              " s fitted at once (each length's squared errors over its constant-velocity baseline's, summed in "
              "the fit and in the decisions to keep; held out by the longest windows' every fourth; the RMSE below "
              "is the first length's)\n";
    std::snprintf(line, sizeof line, "%-6s %27s %27s %11s %8s %23s %23s %23s\n", "joint", "fit windows' RMSE",
                  "held-out windows' RMSE", "const. vel.", "scale k", "viscous", "Coulomb", "offset tau0");
    text += line;
    for (int j = 0; j < n; ++j) {
      std::snprintf(line, sizeof line,
                    "%-6d %11.4g -> %11.4g  %11.4g -> %11.4g  %11.4g %8.4g %10.4g -> %10.4g %10.4g -> %10.4g %10.4g "
                    "-> %10.4g\n",
                    j + 1, rmse_before[j], rmse_after[j], check_before[j], check_after[j], constant_velocity[j],
                    scale[j], viscous_before[j], viscous_after[j], coulomb_before[j], coulomb_after[j],
                    offset_before[j], offset_after[j]);
      text += line;
    }
  }
  if (standard_error.size() > 0) text += StandardErrorTable(*this);
  // The held-out part the decisions are made on: windows, or with whole_run each log's last quarter.
  const std::string held_out = whole_run ? "held-out quarters" : "held-out windows";
  if (stribeck_tried) {
    const bool bristles = bristle_stiffness.size() == n;
    text += bristles ? "low-speed friction (stribeck_friction's break-away s - c, speed vs and bristle stiffness "
                       "sigma0), fitted after the plain refinement:\n"
                  : "low-speed friction (stribeck_friction: break-away s - c, speed vs), fitted after the plain "
                    "refinement:\n";
    for (int j = 0; j < n; ++j) {
      std::snprintf(line, sizeof line, "  joint %d: s - c %.4g, vs %.4g", j + 1, breakaway[j], stribeck_velocity[j]);
      text += line;
      if (bristles) {
        std::snprintf(line, sizeof line, ", sigma0 %.4g", bristle_stiffness[j]);
        text += line;
      }
      std::snprintf(line, sizeof line, "; %s' RMSE %.4g without it\n", held_out.c_str(), check_plain[j]);
      text += line;
    }
    if (!stribeck_kept && !low_speed_at_bound.empty()) {
      text += "  at the edge of its range:";
      for (std::size_t k = 0; k < low_speed_at_bound.size(); ++k) text += (k ? ", " : " ") + low_speed_at_bound[k];
      text += "\n";
    }
    text += stribeck_kept ? "  kept: the " + held_out + " are simulated better with it\n"
                          : "  not kept: it removes under 10 % of the " + held_out + "' cost the plain refinement leaves\n";
  }
  if (!at_bound.empty()) {
    text += "at the edge of its range (not determined by the simulation):";
    for (std::size_t k = 0; k < at_bound.size(); ++k) text += (k ? ", " : " ") + at_bound[k];
    text += "\n";
  }
  text += (kept ? "kept: the " : "not kept: the ") + held_out +
          (kept ? " are simulated better\n" : " are simulated no better; the model it started from is written as it was\n");
  return text;
}

}  // namespace twinsim

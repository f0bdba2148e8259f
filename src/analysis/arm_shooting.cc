#include "analysis/arm_shooting.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "analysis/arm_fit_coordinates.h"
#include "analysis/arm_simulation_score.h"
#include "analysis/fit_covariance.h"
#include "analysis/fixed_step_cost.h"
#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "core/samples.h"
#include "sim/arm_simulation.h"

namespace twinsim {
namespace {

// The coordinates' step for the central differences (ArmFitCoordinates' units, and a
// segment state's: a thousandth of a joint's spread of q, a hundredth of its RMS speed).
constexpr double kShootingStep = 1e-3;

// A continuity defect between two segments weighs as much as kContinuity^2 times the
// segment's rows all off by it: at the optimum the defects are a small part of the
// simulation error, so the fitted parameters are those of one continuous run.
constexpr double kContinuity = 10;

// The share of the held-out quarters' cost (their squared free-run errors over the
// spread) that the low-speed friction must remove to be kept, as on windows
// (arm_output_error.cc): 2n parameters more must earn their place.
constexpr double kRunLowSpeedGain = 0.1;

// The share of each log's usable rows fitted; the rest is the held-out check.
constexpr double kFitShare = 0.75;

// Rows start + 1 .. start + length of log `log` simulated from a state of the segment's
// own; `linked`: its end is tied to the next segment's start (row start + length).
struct Segment {
  std::size_t log = 0;
  int start = 0, length = 0;
  bool linked = false;
};

// Rows first .. cut of a log are fitted, cut .. last held out.
struct LogSplit {
  int first = 0, cut = 0, last = 0;
};

class ShootingProblem {
 public:
  ShootingProblem(const ArmModel& start, const std::vector<ArmLog>& logs, const ArmOutputErrorOptions& options)
      : logs_(logs),
        options_(options),
        n_(start.dof()),
        coordinates_(start, logs, options.offsets, options.stribeck, options.presliding) {
    for (const ArmLog& log : logs_) {
      CheckArmLogMatchesModel(log, start);
      LogSplit split;
      split.first = std::max(log.edge_samples, ArmModelAtLogPeriod(start, log.sample_period).delay_samples);
      split.last = log.rows() - 1 - log.edge_samples;
      split.cut = split.first + static_cast<int>(kFitShare * (split.last - split.first));
      const int length = std::max(1, SamplesIn(options.segment, log.sample_period));
      if (split.cut - split.first < 2 * length || split.last - split.cut < 2) {
        char what[160];
        std::snprintf(what, sizeof what,
                      "too short for the whole-run output-error fit: its first three quarters must hold two segments "
                      "of %g s",
                      options.segment);
        throw InputError(SourceLocation{log.path, 1}, what);
      }
      splits_.push_back(split);
      const int count = (split.cut - split.first) / length;
      for (int i = 0; i < count; ++i) {
        Segment s;
        s.log = splits_.size() - 1;
        s.start = split.first + i * length;
        s.length = i + 1 < count ? length : split.cut - s.start;  // the last takes the rest
        s.linked = i + 1 < count;
        segments_.push_back(s);
      }
    }
    spread_fit_ = Spread(false);
    spread_check_ = Spread(true);
    Eigen::ArrayXd qd2 = Eigen::ArrayXd::Zero(n_);
    double rows = 0;
    for (const LogSplit& split : splits_) rows += split.cut - split.first;
    for (const ArmLog& log : logs_) qd2 += log.qd.array().square().colwise().sum().transpose() / log.rows();
    weight_ = (spread_fit_.array().max(1e-12) * std::sqrt(rows)).inverse().matrix();
    q_unit_ = 1e-3 * spread_fit_.array().max(1e-9).matrix();
    qd_unit_ = 1e-2 * (qd2 / static_cast<double>(logs_.size())).sqrt().max(1e-9).matrix();
  }

  const ArmFitCoordinates& coordinates() const { return coordinates_; }
  const std::vector<Segment>& segments() const { return segments_; }
  int state_size() const { return 2 * n_; }
  // A segment's residuals: its rows' position errors, then with a link the defects.
  int rows(const Segment& s) const { return s.length * n_ + (s.linked ? 2 * n_ : 0); }
  const Eigen::VectorXd& spread(bool check) const { return check ? spread_check_ : spread_fit_; }

  // The weights of a linked segment's defect rows, q then qd (kContinuity over the rows').
  double LinkWeight(const Segment& s, int k) const {
    const double q = weight_[k % n_] * kContinuity * std::sqrt(static_cast<double>(s.length));
    return k < n_ ? q : q * s.length * logs_[s.log].sample_period;
  }
  // How the defect row k moves with the next segment's state coordinate k.
  double LinkSlope(const Segment& s, int k) const {
    return -LinkWeight(s, k) * (k < n_ ? q_unit_[k] : qd_unit_[k - n_]);
  }

  // Segment s simulated by the model at coordinates x from its state coordinates y: its
  // weighted position errors, and with a link its end state's weighted distance from the
  // next segment's logged start (LinkSlope times the next state's coordinates completes it).
  bool Residual(const double* x, const double* y, const Segment& s, double* out) const {
    const ArmLog& log = logs_[s.log];
    const ArmModel at = ArmModelAtLogPeriod(coordinates_.Apply(x), log.sample_period);
    ArmSimulation sim(at, MakeArmBackend(options_.backend, at));
    Eigen::MatrixXd q;
    const bool finished = SimulateArmFromState(&sim, log, s.start, s.length, StartQ(log, s.start, y),
                                               StartQd(log, s.start, y), &q, true);
    int i = 0;
    for (int r = 0; r < s.length; ++r)
      for (int j = 0; j < n_; ++j) out[i++] = (q(r, j) - log.q(s.start + 1 + r, j)) * weight_[j];
    if (!s.linked) return true;
    // A segment that ran away ends where it was held, at rest: its defects stay numbers.
    const int next = s.start + s.length;
    for (int j = 0; j < n_; ++j) out[i++] = (q(s.length - 1, j) - log.q(next, j)) * LinkWeight(s, j);
    for (int j = 0; j < n_; ++j)
      out[i++] = ((finished ? sim.backend().qd()[j] : 0.0) - log.qd(next, j)) * LinkWeight(s, n_ + j);
    return true;
  }

  // Per joint, the RMSE of each log's fitted part (`check` false) or held-out part simulated
  // free from its first logged state by the model.
  Eigen::VectorXd FreeRunRmse(const ArmModel& model, bool check) const {
    Eigen::ArrayXd squares = Eigen::ArrayXd::Zero(n_);
    double rows = 0;
    Eigen::MatrixXd q;
    for (std::size_t l = 0; l < logs_.size(); ++l) {
      const ArmLog& log = logs_[l];
      const ArmModel at = ArmModelAtLogPeriod(model, log.sample_period);
      ArmSimulation sim(at, MakeArmBackend(options_.backend, at));
      const int from = check ? splits_[l].cut : splits_[l].first, to = check ? splits_[l].last : splits_[l].cut;
      SimulateArmFromLog(&sim, log, from, to - from, &q, true);
      squares += (q - log.q.middleRows(from + 1, to - from)).array().square().colwise().sum().transpose();
      rows += to - from;
    }
    return (squares / std::max(1.0, rows)).sqrt().matrix();
  }

  // The held-out runs' error against the joints' spread, summed over the joints.
  double CheckCost(const Eigen::VectorXd& rmse) const {
    return (rmse.array() / spread_check_.array().max(1e-12)).square().sum();
  }

  // The fit's position rows at its start (the model at coordinates 0, every segment from
  // its logged state), each joint's over its spread, squared and summed: the cost without
  // the defects.
  double StartCost() const {
    const std::vector<double> x(static_cast<std::size_t>(coordinates_.parameters()), 0.0);
    const std::vector<double> y(static_cast<std::size_t>(state_size()), 0.0);
    double cost = 0;
    std::vector<double> out;
    for (const Segment& s : segments_) {
      out.resize(static_cast<std::size_t>(rows(s)));
      Residual(x.data(), y.data(), s, out.data());
      for (int r = 0; r < s.length * n_; ++r) cost += out[static_cast<std::size_t>(r)] * out[static_cast<std::size_t>(r)];
    }
    return cost;
  }

  // The largest defect between segments' q, over the joint's spread of q.
  double LargestDefect(const double* x, const std::vector<std::vector<double>>& states) const {
    double largest = 0;
    std::vector<double> out;
    for (std::size_t i = 0; i < segments_.size(); ++i) {
      const Segment& s = segments_[i];
      if (!s.linked) continue;
      out.resize(static_cast<std::size_t>(rows(s)));
      Residual(x, states[i].data(), s, out.data());
      for (int j = 0; j < n_; ++j) {
        const double defect = out[static_cast<std::size_t>(s.length * n_ + j)] + LinkSlope(s, j) * states[i + 1][j];
        largest = std::max(largest, std::abs(defect / LinkWeight(s, j)) / std::max(spread_fit_[j], 1e-12));
      }
    }
    return largest;
  }

 private:
  Eigen::VectorXd StartQ(const ArmLog& log, int row, const double* y) const {
    return log.q.row(row).transpose() + q_unit_.cwiseProduct(Eigen::Map<const Eigen::VectorXd>(y, n_));
  }
  Eigen::VectorXd StartQd(const ArmLog& log, int row, const double* y) const {
    return log.qd.row(row).transpose() + qd_unit_.cwiseProduct(Eigen::Map<const Eigen::VectorXd>(y + n_, n_));
  }
  // Per joint, the RMS of q about its mean over the fitted (or held-out) rows of every log.
  Eigen::VectorXd Spread(bool check) const {
    Eigen::ArrayXd sum = Eigen::ArrayXd::Zero(n_), squares = sum;
    double rows = 0;
    for (std::size_t l = 0; l < logs_.size(); ++l) {
      const int from = check ? splits_[l].cut : splits_[l].first, to = check ? splits_[l].last : splits_[l].cut;
      const Eigen::MatrixXd q = logs_[l].q.middleRows(from + 1, to - from);
      sum += q.colwise().sum().transpose().array();
      squares += q.array().square().colwise().sum().transpose();
      rows += to - from;
    }
    return (squares / rows - (sum / rows).square()).max(0).sqrt().matrix();
  }

  const std::vector<ArmLog>& logs_;
  ArmOutputErrorOptions options_;
  int n_;
  ArmFitCoordinates coordinates_;
  std::vector<LogSplit> splits_;
  std::vector<Segment> segments_;
  Eigen::VectorXd spread_fit_, spread_check_, weight_, q_unit_, qd_unit_;
};

// One segment's residual block: the model's coordinates, the segment's state and, linked,
// the next segment's state. The first two by central differences at kShootingStep, their
// columns simulated on `threads` threads (each on its own: the same numbers for any
// count); the next state enters the defect rows linearly.
class SegmentCost : public ceres::CostFunction {
 public:
  SegmentCost(const ShootingProblem& problem, const Segment& segment, int threads)
      : problem_(problem), segment_(segment), threads_(threads) {
    mutable_parameter_block_sizes()->push_back(problem.coordinates().parameters());
    mutable_parameter_block_sizes()->push_back(problem.state_size());
    if (segment.linked) mutable_parameter_block_sizes()->push_back(problem.state_size());
    set_num_residuals(problem.rows(segment));
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const int p = problem_.coordinates().parameters(), m = problem_.state_size(), rows = problem_.rows(segment_);
    std::vector<double> z(parameters[0], parameters[0] + p);
    z.insert(z.end(), parameters[1], parameters[1] + m);
    const FitResidualFunction f = [this, p](const double* at, double* out) {
      return problem_.Residual(at, at + p, segment_, out);
    };
    if (!f(z.data(), residuals)) return false;
    const int body = rows - (segment_.linked ? m : 0);
    if (segment_.linked)
      for (int k = 0; k < m; ++k) residuals[body + k] += problem_.LinkSlope(segment_, k) * parameters[2][k];
    if (!jacobians) return true;
    if (jacobians[0] || jacobians[1]) {
      const std::size_t columns = z.size();
      std::vector<double> jacobian(static_cast<std::size_t>(rows) * columns);
      if (!CentralDifferences(f, z.data(), std::vector<double>(columns, kShootingStep), static_cast<std::size_t>(rows),
                              jacobian.data(), threads_))
        return false;
      for (int r = 0; r < rows; ++r) {
        const double* row = jacobian.data() + static_cast<std::size_t>(r) * columns;
        if (jacobians[0]) std::copy(row, row + p, jacobians[0] + static_cast<std::size_t>(r) * p);
        if (jacobians[1]) std::copy(row + p, row + p + m, jacobians[1] + static_cast<std::size_t>(r) * m);
      }
    }
    if (segment_.linked && jacobians[2]) {
      std::fill(jacobians[2], jacobians[2] + static_cast<std::size_t>(rows) * m, 0.0);
      for (int k = 0; k < m; ++k) jacobians[2][static_cast<std::size_t>(body + k) * m + k] = problem_.LinkSlope(segment_, k);
    }
    return true;
  }

 private:
  const ShootingProblem& problem_;
  Segment segment_;
  int threads_;
};

// Levenberg-Marquardt over the model's coordinates *x and the segments' states *states
// (both from 0: the start and the logged states); the iterations returned, the model
// coordinates that ended at a bound into *at_bound, their standard errors into *se (each
// segment, its defect rows with it, an independent cluster; the states' uncertainty
// carried into them).
int SolveShooting(const ShootingProblem& problem, const ArmOutputErrorOptions& options, std::vector<double>* x,
                  std::vector<std::vector<double>>* states, std::vector<int>* at_bound, std::vector<double>* se) {
  const std::vector<Segment>& segments = problem.segments();
  ceres::Problem ceres_problem;
  std::vector<ceres::ResidualBlockId> ids;
  std::vector<int> clusters;
  std::vector<double*> parameters = {x->data()};
  for (std::size_t i = 0; i < segments.size(); ++i) {
    std::vector<double*> blocks = {x->data(), (*states)[i].data()};
    if (segments[i].linked) blocks.push_back((*states)[i + 1].data());
    ids.push_back(ceres_problem.AddResidualBlock(new SegmentCost(problem, segments[i], options.threads), nullptr, blocks));
    clusters.insert(clusters.end(), static_cast<std::size_t>(problem.rows(segments[i])), static_cast<int>(i));
    parameters.push_back((*states)[i].data());
  }
  const int p = problem.coordinates().parameters();
  std::vector<double> lower(static_cast<std::size_t>(p)), upper(static_cast<std::size_t>(p));
  for (int k = 0; k < p; ++k) problem.coordinates().Bounds(k, &lower[k], &upper[k]);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = 1e-6;
  solver.parameter_tolerance = 1e-8;
  // One thread for Ceres: its threads would sum the blocks' costs and gradients in the
  // order they finish. The segments' columns are simulated in parallel instead.
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  const int iterations = SolveWithinBounds(&ceres_problem, x, lower, upper, solver, at_bound);
  *se = ClusteredStandardErrors(&ceres_problem, parameters, ids, p, *at_bound, clusters);
  return iterations;
}

// The model coordinates fitted from x0 by multiple shooting.
//
// Not followed by a single-shooting fit of the free run itself: a free run's few stops
// decide its error, and there the frictions bent to place them and the held-out quarter
// got worse on the real EMPS, where the segments' own states keep the fit from chasing
// them (docs/identification.md, "Output error over whole runs").
struct RunFit {
  std::vector<double> x;
  std::vector<int> at_bound;
  std::vector<double> se;  // ClusteredStandardErrors of x
  int iterations = 0, segments = 0;
  double largest_defect = 0;
};

RunFit FitRuns(const ShootingProblem& problem, const ArmOutputErrorOptions& options, std::vector<double> x0) {
  RunFit fit;
  fit.x = std::move(x0);
  fit.x.resize(static_cast<std::size_t>(problem.coordinates().parameters()), 0.0);
  std::vector<std::vector<double>> states(problem.segments().size(),
                                          std::vector<double>(static_cast<std::size_t>(problem.state_size()), 0.0));
  fit.iterations = SolveShooting(problem, options, &fit.x, &states, &fit.at_bound, &fit.se);
  fit.segments = static_cast<int>(problem.segments().size());
  fit.largest_defect = problem.LargestDefect(fit.x.data(), states);
  return fit;
}

}  // namespace

double ArmShootingStartCost(const ArmModel& model, const std::vector<ArmLog>& logs,
                            const ArmOutputErrorOptions& options) {
  ArmOutputErrorOptions plain = options;
  plain.stribeck = false;
  plain.presliding = ArmPresliding::kNone;
  return ShootingProblem(model, logs, plain).StartCost();
}

ArmModel RefineArmByShooting(const ArmModel& start, const std::vector<ArmLog>& logs,
                             const ArmOutputErrorOptions& options, ArmOutputErrorSummary* summary) {
  ArmOutputErrorOptions plain_options = options;
  plain_options.stribeck = false;
  plain_options.presliding = ArmPresliding::kNone;
  const ShootingProblem plain(start, logs, plain_options);
  RunFit fit = FitRuns(plain, plain_options, {});
  ArmModel fitted = plain.coordinates().Apply(fit.x.data());
  const Eigen::VectorXd check_before = plain.FreeRunRmse(start, true);
  Eigen::VectorXd check_after = plain.FreeRunRmse(fitted, true);
  const bool kept = plain.CheckCost(check_after) < plain.CheckCost(check_before);
  // Friction that holds at low speed, from where a kept plain fit ended, kept where it
  // simulates the held-out quarters better still (by kRunLowSpeedGain of their cost).
  const Eigen::VectorXd check_plain = check_after;
  const bool stribeck_tried = options.stribeck && kept;
  bool stribeck_kept = false;
  ArmModel with;
  std::optional<ShootingProblem> low_speed;
  std::vector<std::string> low_speed_at_bound;
  if (stribeck_tried) {
    low_speed.emplace(start, logs, options);
    RunFit y = FitRuns(*low_speed, options, fit.x);
    with = low_speed->coordinates().Apply(y.x.data());
    const Eigen::VectorXd check_with = low_speed->FreeRunRmse(with, true);
    stribeck_kept = low_speed->CheckCost(check_with) < (1 - kRunLowSpeedGain) * plain.CheckCost(check_plain);
    low_speed_at_bound = low_speed->coordinates().Names(y.at_bound);
    if (stribeck_kept) {
      y.iterations += fit.iterations;
      fit = std::move(y);
      fitted = with;
      check_after = check_with;
    }
  }
  if (summary) {
    *summary = ArmOutputErrorSummary();
    SummariseArmFit((stribeck_kept ? *low_speed : plain).coordinates(), start, fitted, fit.x, fit.at_bound, fit.se,
                    summary);
    SummariseLowSpeedFriction(with, stribeck_tried, stribeck_kept, check_plain, summary);
    summary->low_speed_at_bound = std::move(low_speed_at_bound);
    summary->whole_run = true;
    summary->segment = options.segment;
    summary->segments = fit.segments;
    summary->fit_windows = summary->check_windows = static_cast<int>(logs.size());
    summary->iterations = fit.iterations;
    summary->kept = kept;
    summary->rmse_before = plain.FreeRunRmse(start, false);
    summary->rmse_after = plain.FreeRunRmse(fitted, false);
    summary->check_before = check_before;
    summary->check_after = check_after;
    summary->spread_fit = plain.spread(false);
    summary->spread_check = plain.spread(true);
    summary->largest_defect = fit.largest_defect;
  }
  return kept ? fitted : start;
}

}  // namespace twinsim

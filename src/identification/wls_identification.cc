#include "identification/wls_identification.h"

#include "robots/arm/arm_effects.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "core/error.h"
#include "identification/physical_consistency.h"
#include "identification/wls_extra_columns.h"

namespace twinsim {
namespace {

// Folds rows into an upper-triangular factor R with R^T R = A^T A for all rows A added
// (QR of [R; new rows] block by block), so that a tall system is never stored.
class TriangularAccumulator {
 public:
  TriangularAccumulator(int cols, int block)
      : cols_(cols), block_(block), r_(Eigen::MatrixXd::Zero(cols, cols)), buffer_(cols + block, cols) {}

  // The next row to fill (a row of the buffer); call Commit() after filling it.
  Eigen::MatrixXd::RowXpr Next() { return buffer_.row(cols_ + fill_); }
  void Commit() {
    if (++fill_ == block_) Flush();
  }
  void Flush() {
    if (fill_ == 0) return;
    const int rows = cols_ + fill_;
    buffer_.topRows(cols_) = r_;
    Eigen::Ref<Eigen::MatrixXd> stacked(buffer_.topRows(rows));
    Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(stacked);  // in place
    const int keep = std::min(rows, cols_);
    r_.setZero();
    r_.topRows(keep) = qr.matrixQR().topRows(keep).triangularView<Eigen::Upper>();
    fill_ = 0;
  }
  const Eigen::MatrixXd& r() const { return r_; }

 private:
  int cols_;
  int block_;
  int fill_ = 0;
  Eigen::MatrixXd r_;       // cols x cols
  Eigen::MatrixXd buffer_;  // (cols + block) x cols: R on top, new rows below
};

// The log paths for messages: "a.csv" or "a.csv, b.csv".
// Each path once (a log may come in several stretches, as diagnose's fit blocks do).
std::string LogPaths(const std::vector<ArmLog>& logs) {
  std::string s;
  std::vector<std::string> seen;
  for (const auto& l : logs) {
    if (std::find(seen.begin(), seen.end(), l.path) != seen.end()) continue;
    seen.push_back(l.path);
    s += (s.empty() ? "" : ", ") + l.path;
  }
  return s;
}

std::string Format(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

bool WlsIdentificationOptions::IsValid(std::string* why) const {
  std::ostringstream s;
  if (decimate < 1) {
    s << "decimate must be at least 1, got " << decimate;
  } else if (!(still_range >= 0) || !std::isfinite(still_range)) {
    s << "still_range must not be negative, got " << still_range;
  } else if (!(rest_share >= 0 && rest_share < 1)) {
    s << "rest_share must lie in [0, 1), got " << rest_share;
  } else if (!(max_condition_number > 1)) {
    s << "max_condition_number must be above 1, got " << max_condition_number;
  } else if (base_samples < 10) {
    s << "base_samples must be at least 10, got " << base_samples;
  } else if (position_friction_knots != 0 &&
             !(position_friction_knots >= 2 && position_friction_knots <= kMaxProfileKnots)) {
    s << "position friction needs 2 to " << kMaxProfileKnots << " knots (or 0: none), got " << position_friction_knots;
  } else if (position_torque_knots != 0 &&
             !(position_torque_knots >= 2 && position_torque_knots <= kMaxProfileKnots)) {
    s << "a position torque needs 2 to " << kMaxProfileKnots << " knots (or 0: none), got " << position_torque_knots;
  }
  if (why) *why = s.str();
  return s.str().empty();
}

Eigen::VectorXd ArmRestSpeeds(const std::vector<ArmLog>& logs, double share, int decimate, bool skip_edges) {
  const int n = logs.empty() ? 0 : logs.front().dof;
  Eigen::VectorXd square = Eigen::VectorXd::Zero(n);
  int rows = 0;
  for (const ArmLog& log : logs) {
    const int edge = skip_edges ? log.edge_samples : 0;
    for (int row = edge; row < log.rows() - edge; row += decimate, ++rows) square += log.qd.row(row).transpose().cwiseAbs2();
  }
  return share * (square / std::max(rows, 1)).cwiseSqrt();
}

Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> ArmRestRows(const ArmLog& log, const Eigen::VectorXd& rest_speed) {
  const int rows = log.rows(), n = log.dof;
  Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> rest(rows, n);
  const int reach = log.qd_logged || !(log.derive_cutoff_hz > 0)
                        ? 0
                        : static_cast<int>(std::ceil(1 / (log.derive_cutoff_hz * log.sample_period)));
  for (int j = 0; j < n; ++j) {
    int last_rest = -1 - reach;  // the latest row at rest so far
    for (int r = 0; r < rows; ++r) {
      if (std::abs(log.qd(r, j)) < rest_speed[j]) last_rest = r;
      rest(r, j) = r - last_rest <= reach;
    }
    int next_rest = rows + reach;  // the next row at rest, from the end
    for (int r = rows - 1; r >= 0; --r) {
      if (std::abs(log.qd(r, j)) < rest_speed[j]) next_rest = r;
      rest(r, j) = rest(r, j) || next_rest - r <= reach;
    }
  }
  return rest;
}

BaseParameters IdentificationBase(const ArmModel& model, const WlsIdentificationOptions& options) {
  return FindBaseParameters(model, options.base_samples, options.base_seed);
}

std::string DescribeBaseParameter(const ArmModel& model, const BaseParameters& base, int k) {
  const int n = model.dof();
  const int s = base.independent[static_cast<std::size_t>(k)];
  std::string text;
  if (s >= kParametersPerLink * n) {
    const int f = s - kParametersPerLink * n;
    text = std::string(f % 2 == 0 ? "viscous" : "Coulomb") + " friction of joint " + std::to_string(f / 2 + 1);
  } else {
    static const char* kWhat[] = {"mass",        "first moment m cx", "first moment m cy", "first moment m cz",
                                  "inertia Ixx", "inertia Ixy",       "inertia Ixz",       "inertia Iyy",
                                  "inertia Iyz", "inertia Izz"};
    const int p = s % kParametersPerLink;
    text = std::string(kWhat[p]) + " of link " + std::to_string(s / kParametersPerLink + 1) +
           (p >= 4 ? " about its frame's origin" : "");
  }
  int others = 0;
  for (Eigen::Index c = 0; c < base.from_standard.cols(); ++c)
    if (c != s && base.from_standard(k, c) != 0) ++others;
  if (others > 0) text += ", regrouped with " + std::to_string(others) + (others == 1 ? " other" : " others");
  return text;
}

namespace {

// How far each joint moves over all logs, and which never do.
struct JointSpans {
  std::vector<double> lo, hi;  // rad or m, min and max of q per joint
  std::vector<double> span;    // hi - lo
  std::vector<bool> still;     // span below the options' still_range
};

// Names the unknowns in *summary (the r base parameters, then the extra columns) with
// the a-priori model's values.
void DescribeUnknowns(const ArmModel& a_priori, const BaseParameters& base, const ExtraColumns& extras,
                      WlsIdentificationSummary* summary) {
  const int r = base.rank();
  summary->base_parameters = r;
  summary->names = base.names;
  for (int k = 0; k < r; ++k) summary->descriptions.push_back(DescribeBaseParameter(a_priori, base, k));
  for (int c = 0; c < extras.size(); ++c) {
    const int j = extras.joint[static_cast<std::size_t>(c)], k = extras.knot[static_cast<std::size_t>(c)];
    const std::string joint = std::to_string(j + 1);
    const auto kind = extras.kind[static_cast<std::size_t>(c)];
    if (kind == ExtraColumns::Kind::kOffset) {
      summary->names.push_back("offset" + joint);
      summary->descriptions.push_back("torque offset of joint " + joint);
      continue;
    }
    const bool friction = kind == ExtraColumns::Kind::kFriction;
    const int knots = friction ? extras.knots : extras.torque_knots;
    const std::string at = " at knot " + std::to_string(k + 1) + " of " + std::to_string(knots) + " (q = " +
                           Format(extras.from[j] + (extras.to[j] - extras.from[j]) * k / (knots - 1)) + ")";
    summary->names.push_back((friction ? "dfc" : "tq") + joint + "_" + std::to_string(k + 1));
    summary->descriptions.push_back(friction ? "Coulomb friction of joint " + joint + at + " over its level at knot 1"
                                             : "torque along the travel of joint " + joint + at +
                                                   " (measured - model, as an offset)");
  }
  summary->a_priori = Eigen::VectorXd::Zero(r + extras.size());
  summary->a_priori.head(r) = base.from_standard * StandardParameters(a_priori);
}

// Finds the joints that never move (listed 1-based in summary->still_joints): their
// velocity and acceleration are then taken as exactly zero, so that the parameters only
// their motion reveals show up as unexcited instead of as noise.
JointSpans FindStillJoints(const std::vector<ArmLog>& logs, int n, double still_range,
                           WlsIdentificationSummary* summary) {
  JointSpans s;
  s.span.assign(static_cast<std::size_t>(n), 0.0);
  s.still.assign(static_cast<std::size_t>(n), false);
  s.lo.assign(static_cast<std::size_t>(n), 0.0);
  s.hi.assign(static_cast<std::size_t>(n), 0.0);
  for (int j = 0; j < n; ++j) {
    double lo = 1e300, hi = -1e300;
    for (const ArmLog& log : logs) {
      lo = std::min(lo, log.q.col(j).minCoeff());
      hi = std::max(hi, log.q.col(j).maxCoeff());
    }
    s.lo[static_cast<std::size_t>(j)] = lo;
    s.hi[static_cast<std::size_t>(j)] = hi;
    s.span[static_cast<std::size_t>(j)] = hi - lo;
    if (hi - lo < still_range) {
      s.still[static_cast<std::size_t>(j)] = true;
      summary->still_joints.push_back(j + 1);
    }
  }
  return s;
}

// The stacked system W beta = tau, reduced joint by joint to R_j (m_j x cols, scattered
// to all unknowns' columns), z_j and the part of tau_j no column can reach (rho_j^2):
// ||W_j beta - tau_j||^2 = rho_j^2 + ||z_j - R_j beta||^2.
struct JointSystems {
  std::vector<Eigen::MatrixXd> r_of;
  std::vector<Eigen::VectorXd> z_of;
  Eigen::VectorXd rho2;
  int rows = 0;             // sum of m_j
  Eigen::VectorXi samples;  // per joint: the rows in its equations

  int dof() const { return static_cast<int>(r_of.size()); }
  // Joint j's rows weighted by weight[j], stacked: *a (rows x cols) and *b (rows).
  void Stack(const Eigen::VectorXd& weight, Eigen::MatrixXd* a, Eigen::VectorXd* b) const {
    a->resize(rows, r_of.front().cols());
    b->resize(rows);
    int at = 0;
    for (int j = 0; j < dof(); ++j) {
      const int m = static_cast<int>(r_of[static_cast<std::size_t>(j)].rows());
      a->middleRows(at, m) = weight[j] * r_of[static_cast<std::size_t>(j)];
      b->segment(at, m) = weight[j] * z_of[static_cast<std::size_t>(j)];
      at += m;
    }
  }
  // Residual sum of squares of joint j for the unknowns x.
  double Rss(int j, const Eigen::VectorXd& x) const {
    return rho2[j] + (z_of[static_cast<std::size_t>(j)] - r_of[static_cast<std::size_t>(j)] * x).squaredNorm();
  }
  // Torque error RMS per joint (N·m or N) for the unknowns x.
  Eigen::VectorXd ErrorRms(const Eigen::VectorXd& x) const {
    Eigen::VectorXd e(dof());
    for (int j = 0; j < dof(); ++j) e[j] = std::sqrt(std::max(0.0, Rss(j, x)) / samples[j]);
    return e;
  }
};

// Each moving joint's speed below which a row is at rest (summary->rest_speed); a joint
// that never moves keeps every row (its q̇ is taken as 0).
Eigen::VectorXd RestSpeeds(const std::vector<ArmLog>& logs, int n, const WlsIdentificationOptions& options,
                           const JointSpans& spans) {
  Eigen::VectorXd speed = ArmRestSpeeds(logs, options.rest_share, options.decimate, options.skip_filter_edges);
  for (int j = 0; j < n; ++j)
    if (spans.still[static_cast<std::size_t>(j)]) speed[j] = 0;
  return speed;
}

// Throws InputError unless every joint has rows left beside its rows at rest
// (`joint_samples`, per joint) and all joints together at least twice `columns`.
void CheckEnoughRows(const Eigen::VectorXi& joint_samples, int columns, double rest_share, const std::string& where,
                     const WlsIdentificationSummary& summary) {
  const int samples = summary.samples, n = static_cast<int>(joint_samples.size());
  for (int j = 0; j < n && samples > 0; ++j) {
    if (joint_samples[j] > 0) continue;
    char msg[240];
    std::snprintf(msg, sizeof msg,
                  "joint %d is at rest or near it on every one of the %d samples (|qd| under %.3g, %g %% of its RMS "
                  "speed, or within one cut-off period of such a row): nothing to identify its parameters from",
                  j + 1, samples, summary.rest_speed[j], 100 * rest_share);
    throw InputError(SourceLocation{where}, msg);
  }
  if (joint_samples.sum() < 2 * columns) {
    throw InputError(SourceLocation{where}, "too few samples to identify " + std::to_string(columns) +
                                                " parameters: " + std::to_string(samples) + " samples of " +
                                                std::to_string(n) + " joints");
  }
}

// Accumulates the regressor rows of every log sample, joint by joint, into JointSystems
// (a joint's rows at rest, below summary->rest_speed or near it, left out of its own
// equations) and sets summary->samples, rest_rows and torque_rms; throws InputError for
// too few samples.
JointSystems AccumulateRows(const ArmModel& a_priori, const BaseParameters& base, const ExtraColumns& extras,
                            const std::vector<ArmLog>& logs, const WlsIdentificationOptions& options,
                            const JointSpans& spans, const std::string& where, WlsIdentificationSummary* summary) {
  const int n = a_priori.dof();
  const int r = base.rank();
  const int cols_total = r + extras.size();
  // Joint j's torque depends only on links j..n and its own friction: its rows are folded
  // into a factor over those base columns alone.
  std::vector<std::vector<int>> columns(static_cast<std::size_t>(n));
  for (int k = 0; k < r; ++k) {
    const int s = base.independent[static_cast<std::size_t>(k)];
    for (int j = 0; j < n; ++j) {
      const bool link = s < kParametersPerLink * n && s / kParametersPerLink >= j;
      const bool friction = s >= kParametersPerLink * n && (s - kParametersPerLink * n) / kFrictionPerJoint == j;
      if (link || friction) columns[static_cast<std::size_t>(j)].push_back(k);
    }
  }
  for (int c = 0; c < extras.size(); ++c)
    columns[static_cast<std::size_t>(extras.joint[static_cast<std::size_t>(c)])].push_back(r + c);
  std::vector<TriangularAccumulator> factors;
  for (int j = 0; j < n; ++j) factors.emplace_back(static_cast<int>(columns[static_cast<std::size_t>(j)].size()) + 1, 1024);

  Eigen::VectorXd torque_square = Eigen::VectorXd::Zero(n);
  int samples = 0;
  Eigen::VectorXi joint_samples = Eigen::VectorXi::Zero(n);
  Eigen::VectorXd q(n), qd(n), qdd(n);
  for (const ArmLog& log : logs) {
    const int edge = options.skip_filter_edges ? log.edge_samples : 0;
    const Eigen::Matrix<bool, Eigen::Dynamic, Eigen::Dynamic> rest = ArmRestRows(log, summary->rest_speed);
    for (int row = edge; row < log.rows() - edge; row += options.decimate) {
      q = log.q.row(row).transpose();
      qd = log.qd.row(row).transpose();
      qdd = log.qdd.row(row).transpose();
      for (int j = 0; j < n; ++j) {
        if (spans.still[static_cast<std::size_t>(j)]) qd[j] = qdd[j] = 0;
      }
      const Eigen::MatrixXd y = Regressor(a_priori, q, qd, qdd);
      for (int j = 0; j < n; ++j) {
        if (rest(row, j)) continue;
        ++joint_samples[j];
        const auto& cols = columns[static_cast<std::size_t>(j)];
        auto next = factors[static_cast<std::size_t>(j)].Next();
        for (std::size_t c = 0; c < cols.size(); ++c) {
          const int k = cols[c];
          next[static_cast<Eigen::Index>(c)] =
              k < r ? y(j, base.independent[static_cast<std::size_t>(k)]) : extras.Value(k - r, q[j], qd[j]);
        }
        next[static_cast<Eigen::Index>(cols.size())] = log.tau(row, j);
        factors[static_cast<std::size_t>(j)].Commit();
        torque_square[j] += log.tau(row, j) * log.tau(row, j);
      }
      ++samples;
    }
  }
  summary->samples = samples;
  summary->rest_rows = Eigen::VectorXi::Constant(n, samples) - joint_samples;
  CheckEnoughRows(joint_samples, cols_total, options.rest_share, where, *summary);
  summary->torque_rms = torque_square.cwiseQuotient(joint_samples.cast<double>()).cwiseSqrt();

  JointSystems systems;
  systems.r_of.resize(static_cast<std::size_t>(n));
  systems.z_of.resize(static_cast<std::size_t>(n));
  systems.rho2.resize(n);
  systems.samples = joint_samples;
  for (int j = 0; j < n; ++j) {
    auto& f = factors[static_cast<std::size_t>(j)];
    f.Flush();
    const auto& cols = columns[static_cast<std::size_t>(j)];
    const int m = static_cast<int>(cols.size());
    Eigen::MatrixXd rj = Eigen::MatrixXd::Zero(m, cols_total);
    for (int c = 0; c < m; ++c) rj.col(cols[static_cast<std::size_t>(c)]) = f.r().col(c).head(m);
    systems.r_of[static_cast<std::size_t>(j)] = rj;
    systems.z_of[static_cast<std::size_t>(j)] = f.r().col(m).head(m);
    systems.rho2[j] = f.r()(m, m) * f.r()(m, m);
    systems.rows += m;
  }
  return systems;
}

// Refuses data that leaves some direction of the column-scaled regressor `a` without
// weight, with an InputError naming the unknowns involved and the joints that never move.
void CheckExcitation(const Eigen::MatrixXd& a, const BaseParameters& base, const JointSpans& spans,
                     const WlsIdentificationOptions& options, const std::string& where,
                     const WlsIdentificationSummary& summary) {
  const int n = summary.dof;
  const int r = base.rank();
  const int cols_total = static_cast<int>(a.cols());
  Eigen::VectorXd norms = a.colwise().norm().transpose();
  const double largest = norms.maxCoeff();
  for (int k = 0; k < cols_total; ++k)
    if (!(norms[k] > 1e-14 * largest)) norms[k] = 0;
  const Eigen::MatrixXd scaled = a * norms.unaryExpr([](double v) { return v > 0 ? 1 / v : 0.0; }).asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  const double limit = s[0] / options.max_condition_number;
  std::vector<int> weak;
  for (int k = 0; k < cols_total; ++k)
    if (!(s[k] > limit)) weak.push_back(k);
  if (weak.empty()) return;
  Eigen::VectorXd share = Eigen::VectorXd::Zero(cols_total);
  for (int w : weak) share += svd.matrixV().col(w).cwiseAbs2();
  share = share.cwiseSqrt();
  std::vector<int> named;
  for (int k = 0; k < cols_total; ++k)
    if (share[k] > 0.3) named.push_back(k);
  std::stable_sort(named.begin(), named.end(), [&](int x, int y) { return share[x] > share[y]; });
  if (named.empty()) named.push_back(static_cast<int>(std::max_element(share.data(), share.data() + cols_total) - share.data()));
  std::string still_list;
  for (int j : summary.still_joints) still_list += (still_list.empty() ? "" : ", ") + std::to_string(j);
  std::ostringstream msg;
  // One line per parameter: a log where nothing moves names dozens of them.
  msg << "the data does not excite base parameter" << (named.size() > 1 ? "s:" : ":");
  for (const int k : named) {
    const int sidx = k < r ? base.independent[static_cast<std::size_t>(k)] : -1;
    msg << "\n  " << summary.names[static_cast<std::size_t>(k)] << " (" << summary.descriptions[static_cast<std::size_t>(k)];
    if (sidx >= kParametersPerLink * n) {
      const int joint = (sidx - kParametersPerLink * n) / kFrictionPerJoint;
      if (spans.still[static_cast<std::size_t>(joint)]) msg << ": it never moves";
    }
    msg << ")";
  }
  if (weak.size() < named.size() && weak.size() > 0)
    msg << "\ntogether they leave " << weak.size() << " combination" << (weak.size() > 1 ? "s" : "")
        << " undetermined";
  if (!still_list.empty()) {
    msg << "\njoint" << (summary.still_joints.size() > 1 ? "s " : " ") << still_list << " never move"
        << (summary.still_joints.size() > 1 ? "" : "s") << ":";
    for (int j : summary.still_joints) {
      msg << " q" << j << " spans only " << Format(spans.span[static_cast<std::size_t>(j - 1)]) << " (below "
          << Format(options.still_range) << ");";
    }
  }
  msg << "\nMove every joint in both directions with varied speeds and accelerations (the condition number is "
      << (s[cols_total - 1] > 0 ? Format(s[0] / s[cols_total - 1]) : std::string("infinite")) << ", the limit "
      << Format(options.max_condition_number) << ")";
  throw InputError(SourceLocation{where}, msg.str());
}

// The weighted system and what the consistency projection needs of its solution.
struct WeightedSolution {
  Eigen::MatrixXd aw;       // rows x cols, the stacked rows weighted by joint
  Eigen::MatrixXd rw;       // cols x cols, upper triangular: R of aw's QR
  Eigen::VectorXd std_dev;  // cols, the standard deviation of each estimate
};

// Solves by ordinary least squares (a, b: the unweighted stacked system), then again
// with each joint weighted by its residual's standard deviation; fills the summary's
// estimates, sigmas, condition number and relative standard deviations.
WeightedSolution Solve(const JointSystems& systems, const Eigen::MatrixXd& a, const Eigen::VectorXd& b,
                       const WlsIdentificationOptions& options, WlsIdentificationSummary* summary) {
  const int n = systems.dof();
  const int samples = systems.samples.sum();
  const int cols_total = static_cast<int>(a.cols());
  summary->ordinary = a.householderQr().solve(b);
  summary->joint_sigma.resize(n);
  for (int j = 0; j < n; ++j) {
    const double dof_of_joint = std::max(1.0, systems.samples[j] - static_cast<double>(cols_total) / n);
    const double floor = 1e-12 * std::max(summary->torque_rms[j], 1e-12);
    summary->joint_sigma[j] =
        std::max(floor, std::sqrt(std::max(0.0, systems.Rss(j, summary->ordinary)) / dof_of_joint));
  }
  const Eigen::VectorXd weights =
      options.weighted ? Eigen::VectorXd(summary->joint_sigma.cwiseInverse()) : Eigen::VectorXd::Ones(n);
  WeightedSolution solution;
  Eigen::VectorXd bw;
  systems.Stack(weights, &solution.aw, &bw);
  const Eigen::MatrixXd& aw = solution.aw;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(aw);
  summary->identified = qr.solve(bw);
  solution.rw = qr.matrixQR().topRows(cols_total).triangularView<Eigen::Upper>();
  {
    Eigen::VectorXd norms = aw.colwise().norm().transpose();
    const Eigen::VectorXd sv = (aw * norms.cwiseInverse().asDiagonal()).jacobiSvd().singularValues();
    summary->condition_number = sv[0] / sv[cols_total - 1];
  }
  double weighted_rss = 0;
  for (int j = 0; j < n; ++j) weighted_rss += weights[j] * weights[j] * systems.Rss(j, summary->identified);
  const double variance = weighted_rss / std::max(1, samples - cols_total);
  const Eigen::MatrixXd rinv =
      solution.rw.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(cols_total, cols_total));
  solution.std_dev = (variance * rinv.rowwise().squaredNorm()).cwiseSqrt();
  summary->relative_std.resize(cols_total);
  for (int k = 0; k < cols_total; ++k) {
    const double v = std::abs(summary->identified[k]);
    summary->relative_std[k] = v > 0 ? 100 * solution.std_dev[k] / v : std::numeric_limits<double>::infinity();
  }
  return solution;
}

// Returns the a-priori model with standard parameters that give the identified base
// parameters (the least change, K having full row rank) or, if that is no real arm, the
// physically consistent ones that fit the torques best, and fills summary->consistent,
// offsets and the consistency fields; throws InputError when even those are no valid arm.
// The `extras` unknowns after the base parameters (offsets, position friction) are free.
ArmModel ProjectConsistent(const ArmModel& a_priori, const Eigen::MatrixXd& k_matrix, const ExtraColumns& extra_columns,
                           const WeightedSolution& solution, const std::string& where,
                           WlsIdentificationSummary* summary) {
  const int r = static_cast<int>(k_matrix.rows());
  const int extras = extra_columns.size();
  const int cols_total = r + extras;
  const Eigen::MatrixXd& aw = solution.aw;
  // The extra unknowns (offsets, position friction) are free: with them first in a QR of
  // the weighted system, R = [[R_oo, R_ob], [0, R_bb]] and R_bb is the weighted metric of
  // beta with them refitted.
  const Eigen::VectorXd beta = summary->identified.head(r);
  Eigen::MatrixXd r_beta = solution.rw.topLeftCorner(r, r), r_oo, r_ob;
  if (extras > 0) {
    Eigen::MatrixXd permuted(aw.rows(), cols_total);
    permuted << aw.rightCols(extras), aw.leftCols(r);
    const Eigen::MatrixXd rp = permuted.householderQr().matrixQR().topRows(cols_total).triangularView<Eigen::Upper>();
    r_oo = rp.topLeftCorner(extras, extras);
    r_ob = rp.topRightCorner(extras, r);
    r_beta = rp.bottomRightCorner(r, r);
  }
  const Eigen::VectorXd pi_mn = NearestStandardParameters(a_priori, k_matrix, beta);
  ArmModel result;
  bool consistent = false;
  try {
    result = WithStandardParameters(a_priori, pi_mn);
    const std::string problems = result.Validate();
    consistent = problems.empty();
    std::istringstream lines(problems);
    std::string line;
    while (std::getline(lines, line)) summary->consistency_notes.push_back(line);
  } catch (const InputError& e) {
    summary->consistency_notes.push_back(e.what());
  }
  Eigen::VectorXd pi_final = pi_mn;
  if (!consistent) {
    summary->consistency_fixed = true;
    const ConsistentFit fit = FitConsistentParameters(a_priori, k_matrix, r_beta, beta);
    summary->consistency_iterations = fit.iterations;
    pi_final = fit.pi;
    result = WithStandardParameters(a_priori, pi_final);
    const std::string problems = result.Validate();
    if (!problems.empty()) {
      std::string list;
      std::istringstream lines(problems);
      for (std::string line; std::getline(lines, line);) list += (list.empty() ? "" : "; ") + line;
      throw InputError(SourceLocation{where},
                       "the data does not determine a real arm: even the physically consistent fit of the identified "
                       "parameters fails validation (" + list + "). Check the torques' units, and move every joint "
                       "in both directions with varied speeds and accelerations");
    }
  }
  summary->consistent = summary->identified;
  summary->consistent.head(r) = k_matrix * pi_final;
  if (extras > 0) {
    // The extra unknowns that go best with the consistent base parameters.
    summary->consistent.tail(extras) -=
        r_oo.triangularView<Eigen::Upper>().solve(r_ob * (summary->consistent.head(r) - beta));
  }
  summary->offsets = summary->consistent.segment(r, extra_columns.offsets);
  summary->consistency_shift_max_std = 0;
  for (int k = 0; k < cols_total; ++k) {
    if (solution.std_dev[k] > 0)
      summary->consistency_shift_max_std =
          std::max(summary->consistency_shift_max_std,
                   std::abs(summary->consistent[k] - summary->identified[k]) / solution.std_dev[k]);
  }
  return result;
}

// The identified model's effects: the a-priori ones the fit cannot estimate, and the
// estimated offsets as torque_offset effects.
ArmEffects IdentifiedEffects(const ArmModel& a_priori, const Eigen::VectorXd& offsets) {
  const int n = a_priori.dof();
  // Dropped: those whose torques the identified parameters now hold (the friction
  // effects and the payload, absorbed into the joints' viscous and Coulomb friction and
  // the last link; an old torque_offset, which the fit did not see). Kept: what the fit
  // cannot estimate (time_delay, torque_saturation, joint_flexibility).
  ArmEffects effects;
  for (const ArmEffect& e : ListArmEffects(a_priori.effects)) {
    if (e.name == "time_delay" || e.name == "torque_saturation" || e.name == "joint_flexibility")
      AddArmEffect(e, n, &effects);
  }
  // tau0 = -offset: the joint receives the command plus tau0, so the log's torque is the
  // model's minus tau0.
  for (int j = 0; j < offsets.size(); ++j) {
    if (offsets[j] != 0) AddArmEffect({"torque_offset", j, {{"tau0", -offsets[j]}}}, n, &effects);
  }
  return effects;
}

}  // namespace

Eigen::MatrixXd ExtraTorques(const WlsIdentificationSummary& summary, const Eigen::VectorXd& x, const ArmLog& log) {
  const int n = log.dof, r = summary.base_parameters;
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(n);
  const bool profiles = !summary.position_joints.empty();
  const ExtraColumns extras(n, summary.offsets.size() > 0, summary.position_knots, summary.torque_knots,
                            summary.position_joints, profiles ? summary.position_from : none,
                            profiles ? summary.position_to : none);
  Eigen::MatrixXd tau = Eigen::MatrixXd::Zero(log.rows(), n);
  for (int c = 0; c < extras.size(); ++c) {
    const int j = extras.joint[static_cast<std::size_t>(c)];
    for (int row = 0; row < log.rows(); ++row) tau(row, j) += x[r + c] * extras.Value(c, log.q(row, j), log.qd(row, j));
  }
  return tau;
}

ArmModel IdentifyArmByLeastSquares(const ArmModel& a_priori, const std::vector<ArmLog>& logs,
                     const WlsIdentificationOptions& options, WlsIdentificationSummary* summary_out) {
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw InputError("identification options: " + why);
  if (logs.empty()) throw InputError("identification needs at least one log");
  for (const ArmLog& log : logs) CheckArmLogMatchesModel(log, a_priori);
  const std::string where = LogPaths(logs);

  WlsIdentificationSummary summary;
  const int n = a_priori.dof();
  summary.dof = n;
  summary.logs = static_cast<int>(logs.size());
  const BaseParameters base = IdentificationBase(a_priori, options);
  const JointSpans spans = FindStillJoints(logs, n, options.still_range, &summary);
  // Estimated: the r base parameters, then (optionally) one torque offset per joint and
  // the position friction's knots.
  summary.position_joints =
      PositionJoints(options.position_friction_knots > 0 || options.position_torque_knots > 0, spans.still);
  const ExtraColumns extras(n, options.torque_offsets, options.position_friction_knots, options.position_torque_knots,
                            summary.position_joints, Eigen::Map<const Eigen::VectorXd>(spans.lo.data(), n),
                            Eigen::Map<const Eigen::VectorXd>(spans.hi.data(), n));
  if (!summary.position_joints.empty()) {
    summary.position_from = extras.from;
    summary.position_to = extras.to;
  }
  DescribeUnknowns(a_priori, base, extras, &summary);
  summary.rest_speed = RestSpeeds(logs, n, options, spans);
  const JointSystems systems = AccumulateRows(a_priori, base, extras, logs, options, spans, where, &summary);
  Eigen::MatrixXd a;
  Eigen::VectorXd b;
  systems.Stack(Eigen::VectorXd::Ones(n), &a, &b);
  CheckExcitation(a, base, spans, options, where, summary);
  const WeightedSolution solution = Solve(systems, a, b, options, &summary);
  ArmModel result = ProjectConsistent(a_priori, base.from_standard, extras, solution, where, &summary);
  summary.error_rms_a_priori = systems.ErrorRms(summary.a_priori);
  summary.error_rms_identified = systems.ErrorRms(summary.identified);
  summary.error_rms_model = systems.ErrorRms(summary.consistent);
  result.effects = IdentifiedEffects(a_priori, summary.offsets);
  SetPositionFriction(extras, &result, &summary);
  SetPositionTorque(extras, &result, &summary);
  result.source_path.clear();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (summary_out) *summary_out = summary;
  return result;
}

std::string WlsIdentificationSummary::BriefReport() const {
  std::ostringstream s;
  const double before = error_rms_a_priori.size() ? (error_rms_a_priori.cwiseQuotient(torque_rms)).mean() : 0;
  const double after = error_rms_model.size() ? (error_rms_model.cwiseQuotient(torque_rms)).mean() : 0;
  std::vector<std::string> parts;
  if (offsets.size() > 0) parts.push_back("torque offsets");
  if (position_knots > 0) parts.push_back("position friction");
  if (torque_knots > 0) parts.push_back("position torque");
  std::string extras;
  for (const std::string& part : parts) extras += " and " + part;
  s << base_parameters << " base parameters" << extras << " from " << samples << " samples of " << logs << " log" << (logs == 1 ? "" : "s")
    << ", condition number " << Format(condition_number) << ", torque error " << Format(100 * before) << " % -> "
    << Format(100 * after) << " % of the torque RMS (mean over joints)"
    << (consistency_fixed ? ", made physically consistent" : "");
  return s.str();
}

std::string WlsIdentificationSummary::FullReport() const {
  std::ostringstream s;
  char line[512];
  s << BriefReport() << " (" << Format(seconds) << " s)\n\n";
  std::size_t width = 9;
  for (const auto& name : names) width = std::max(width, std::min<std::size_t>(name.size(), 60));
  std::snprintf(line, sizeof line, "%-*s %13s %13s %9s %13s\n", static_cast<int>(width), "parameter", "a priori",
                "identified", "rel. std", "model");
  s << line;
  for (std::size_t k = 0; k < names.size(); ++k) {
    std::string name = names[k];
    if (name.size() > width) name = name.substr(0, width - 3) + "...";
    char rel[32];
    if (std::isfinite(relative_std[static_cast<Eigen::Index>(k)]) && relative_std[static_cast<Eigen::Index>(k)] < 1e4)
      std::snprintf(rel, sizeof rel, "%8.2f%%", relative_std[static_cast<Eigen::Index>(k)]);
    else
      std::snprintf(rel, sizeof rel, "%9s", "-");
    const auto i = static_cast<Eigen::Index>(k);
    std::snprintf(line, sizeof line, "%-*s %13.6g %13.6g %s %13.6g\n", static_cast<int>(width), name.c_str(),
                  a_priori[i], identified[i], rel, consistent[i]);
    s << line;
  }
  s << "\n";
  std::snprintf(line, sizeof line, "%-6s %12s %12s %12s %12s %12s\n", "joint", "torque RMS", "sigma", "a priori",
                "identified", "model");
  s << line;
  for (int j = 0; j < dof; ++j) {
    std::snprintf(line, sizeof line, "%-6d %12.5g %12.5g %12.5g %12.5g %12.5g\n", j + 1, torque_rms[j], joint_sigma[j],
                  error_rms_a_priori[j], error_rms_identified[j], error_rms_model[j]);
    s << line;
  }
  s << "(torque RMS error per joint in N·m or N over the samples used; sigma: the weight's standard deviation)\n";
  if (rest_rows.size() && rest_rows.sum() > 0) {
    s << "rows at rest left out of a joint's equations (it holds anywhere within its friction band there):";
    for (int j = 0; j < dof; ++j) {
      std::snprintf(line, sizeof line, " joint %d %d (%.1f %%, |qd| < %.3g)", j + 1, rest_rows[j],
                    100.0 * rest_rows[j] / std::max(samples, 1), rest_speed[j]);
      s << line << (j + 1 < dof ? ";" : "\n");
    }
  }
  // A profile's levels at its knots, one line per knotted joint.
  const auto knot_levels = [&](const char* title, int knots, const Eigen::MatrixXd& levels) {
    s << title << ":\n";
    for (const int j : position_joints) {
      std::snprintf(line, sizeof line, "  joint %d, %d knots from %.6g to %.6g:", j + 1, knots, position_from[j],
                    position_to[j]);
      s << line;
      for (int k = 0; k < knots; ++k) s << " " << Format(levels(j, k));
      s << "\n";
    }
  };
  if (position_knots > 0) {
    knot_levels("Coulomb friction along each joint's travel (the model's level at each knot, N·m or N)", position_knots,
                position_levels);
    for (const auto& note : position_notes) s << "  " << note << "\n";
  }
  if (torque_knots > 0) {
    knot_levels("Torque along each joint's travel (position_torque: what the joint receives beside the command at "
                "each knot, N·m or N)",
                torque_knots, torque_levels);
  }
  if (consistency_fixed) {
    s << "\nThe minimum-norm standard parameters were not physical:\n";
    for (const auto& note : consistency_notes) s << "  " << note << "\n";
    s << "made consistent (log-det barrier, " << consistency_iterations
      << " Newton steps), moving the base parameters by at most "
      << Format(consistency_shift_max_std) << " standard deviations\n";
  }
  return s.str();
}

}  // namespace twinsim

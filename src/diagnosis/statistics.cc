#include "diagnosis/statistics.h"

#include <Eigen/Dense>
#include <unsupported/Eigen/SpecialFunctions>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "diagnosis/diagnosis.h"

namespace twinsim {
namespace {

double MeanOf(const std::vector<double>& x) {
  return x.empty() ? 0.0 : std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(x.size());
}

// Autocorrelations of x at lags 1..max_lag (0 where x is constant).
std::vector<double> Autocorrelation(const std::vector<double>& x, int max_lag) {
  const double m = MeanOf(x);
  double c0 = 0;
  for (double v : x) c0 += (v - m) * (v - m);
  std::vector<double> r(static_cast<std::size_t>(std::max(max_lag, 0)), 0.0);
  if (c0 <= 0) return r;
  for (int k = 1; k <= max_lag && static_cast<std::size_t>(k) < x.size(); ++k) {
    double c = 0;
    for (std::size_t i = static_cast<std::size_t>(k); i < x.size(); ++i) c += (x[i] - m) * (x[i - static_cast<std::size_t>(k)] - m);
    r[static_cast<std::size_t>(k - 1)] = c / c0;
  }
  return r;
}

std::vector<double> EveryStep(const std::vector<double>& x, int step) {
  std::vector<double> out;
  for (std::size_t i = 0; i < x.size(); i += static_cast<std::size_t>(std::max(step, 1))) out.push_back(x[i]);
  return out;
}

}  // namespace

double TwoSidedNormalQuantile(double p) {
  if (!(p > 0 && p < 1)) return std::numeric_limits<double>::quiet_NaN();
  return -Eigen::numext::ndtri(0.5 * p);  // P(|Z| > z) = p
}

double WorstChannelP(double t, double df, int channels) {
  return std::min(1.0, std::max(1, channels) * StudentTUpperTail(-t, df));
}

double StudentTUpperTail(double t, double df) {
  if (std::isnan(t) || !(df > 0)) return std::numeric_limits<double>::quiet_NaN();
  if (std::isinf(t)) return t > 0 ? 0.0 : 1.0;
  const double tail = 0.5 * Eigen::numext::betainc(df / 2, 0.5, df / (df + t * t));  // P(T >= |t|)
  return t >= 0 ? tail : 1 - tail;
}

double ChiSquareUpperTail(double x, double k) {
  if (std::isnan(x) || !(k > 0)) return std::numeric_limits<double>::quiet_NaN();
  if (x <= 0) return 1;
  return std::clamp(Eigen::numext::igammac(k / 2, x / 2), 0.0, 1.0);
}

LongRunTest LongRunMeanTest(const std::vector<double>& x, int min_bandwidth) {
  LongRunTest out;
  const std::size_t n = x.size();
  if (n < 4) return out;
  out.mean = MeanOf(x);
  const int longest = std::max(1, static_cast<int>(n / 3));
  out.bandwidth = std::clamp(std::max(min_bandwidth, 6 * CorrelationLength(x, longest)), 1, longest);
  std::vector<double> d(n);
  for (std::size_t i = 0; i < n; ++i) d[i] = x[i] - out.mean;
  auto autocovariance = [&](int lag) {
    double s = 0;
    for (std::size_t i = static_cast<std::size_t>(lag); i < n; ++i) s += d[i] * d[i - static_cast<std::size_t>(lag)];
    return s / static_cast<double>(n);
  };
  const double gamma0 = autocovariance(0);
  double long_run = gamma0;
  for (int lag = 1; lag <= out.bandwidth; ++lag) {
    long_run += 2 * (1 - lag / (out.bandwidth + 1.0)) * autocovariance(lag);
  }
  long_run = std::max(long_run, gamma0 / static_cast<double>(n));  // Bartlett keeps it positive; rounding may not
  out.standard_error = std::sqrt(long_run / static_cast<double>(n));
  out.df = std::max(1.0, static_cast<double>(n) / out.bandwidth - 1);
  out.effective_rows = gamma0 > 0 ? std::min(static_cast<double>(n), static_cast<double>(n) * gamma0 / long_run)
                                  : static_cast<double>(n);
  if (out.standard_error > 0) {
    out.t = out.mean / out.standard_error;
    out.p = StudentTUpperTail(out.t, out.df);
  } else {
    out.t = out.mean > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    out.p = out.mean > 0 ? 0.0 : 1.0;
  }
  return out;
}

void AccountForBlocks(const std::vector<double>& x, const std::vector<int>& block, LongRunTest* test) {
  if (x.size() != block.size() || x.empty()) return;
  const double mean = MeanOf(x);
  std::vector<double> sums;  // per block, of the deviations from the mean
  for (std::size_t i = 0; i < x.size(); ++i) {
    if (i == 0 || block[i] != block[i - 1]) sums.push_back(0);
    sums.back() += x[i] - mean;
  }
  const double b = static_cast<double>(sums.size());
  if (b < 2) return;
  double ss = 0;
  for (double s : sums) ss += s * s;
  const double cluster = std::sqrt(b / (b - 1) * ss) / static_cast<double>(x.size());
  test->standard_error = std::max(test->standard_error, cluster);
  test->df = std::min(test->df, b - 1);
  if (test->standard_error > 0) {
    test->t = test->mean / test->standard_error;
    test->p = StudentTUpperTail(test->t, test->df);
  }
}

BlockCoefficientTest TestBlockCoefficient(const std::vector<std::vector<double>>& x, const std::vector<double>& y,
                                          const std::vector<int>& block, int column) {
  BlockCoefficientTest out;
  if (x.empty() || x.size() != y.size() || x.size() != block.size()) return out;
  const long k = static_cast<long>(x.front().size());
  if (column < 0 || column >= k) return out;
  for (const std::vector<double>& row : x) {
    if (static_cast<long>(row.size()) != k) return out;
  }
  // The normal equations per block: each block's coefficients are the whole's minus its own.
  std::map<int, std::pair<Eigen::MatrixXd, Eigen::VectorXd>> parts;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(k);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Eigen::Map<const Eigen::VectorXd> row(x[i].data(), k);
    auto [it, fresh] = parts.try_emplace(block[i], Eigen::MatrixXd::Zero(k, k), Eigen::VectorXd::Zero(k));
    it->second.first.selfadjointView<Eigen::Lower>().rankUpdate(row);
    it->second.second += y[i] * row;
  }
  for (const auto& [id, part] : parts) {
    a += part.first;
    b += part.second;
  }
  const double nb = static_cast<double>(parts.size());
  if (parts.size() < 3) return out;
  // Columns that are zero on every row of a fit (a log never commanded to turn, or a
  // block left out that held all of a column's rows) carry nothing there: left out, so
  // that they do not make the rest look singular.
  auto solve = [&](const Eigen::MatrixXd& full, const Eigen::VectorXd& full_v, double* c) {
    std::vector<long> kept;
    long at = -1;
    for (long j = 0; j < k; ++j) {
      if (full(j, j) <= 1e-12 * a(j, j) && j != column) continue;  // zero there, or rounding's rest of it
      if (j == column) at = static_cast<long>(kept.size());
      kept.push_back(j);
    }
    const long n = static_cast<long>(kept.size());
    Eigen::MatrixXd m(n, n);
    Eigen::VectorXd v(n);
    for (long r = 0; r < n; ++r) {
      v(r) = full_v(kept[static_cast<std::size_t>(r)]);
      for (long q = 0; q <= r; ++q) m(r, q) = full(kept[static_cast<std::size_t>(r)], kept[static_cast<std::size_t>(q)]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(m);  // reads the lower triangle, the one filled
    if (ldlt.info() != Eigen::Success || ldlt.rcond() < 1e-12) return false;
    *c = ldlt.solve(v)(at);
    return std::isfinite(*c);
  };
  if (!solve(a, b, &out.value)) return out;
  std::vector<double> left_out;
  for (const auto& [id, part] : parts) {
    double c = 0;
    if (!solve(a - part.first, b - part.second, &c)) return out;
    left_out.push_back(c);
  }
  const double mean = MeanOf(left_out);
  double ss = 0;
  for (double c : left_out) ss += (c - mean) * (c - mean);
  out.standard_error = std::sqrt((nb - 1) / nb * ss);
  if (!(out.standard_error > 0)) return out;
  out.blocks = static_cast<int>(parts.size());
  out.t = out.value / out.standard_error;
  out.p = std::min(1.0, 2 * StudentTUpperTail(std::abs(out.t), nb - 1));
  return out;
}

std::vector<bool> HolmReject(const std::vector<double>& p, double alpha) {
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (!std::isnan(p[k])) order.push_back(k);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return p[a] < p[b]; });
  std::vector<bool> reject(p.size(), false);
  const std::size_t m = order.size();
  for (std::size_t i = 0; i < m; ++i) {
    if (p[order[i]] > alpha / static_cast<double>(m - i)) break;
    reject[order[i]] = true;
  }
  return reject;
}

Whiteness LjungBox(const std::vector<double>& x, int max_lag, int step) {
  Whiteness w;
  w.step = std::max(step, 1);
  const std::vector<double> y = EveryStep(x, w.step);
  w.rows = static_cast<int>(y.size());
  const int lags = std::min(max_lag, w.rows / 4);
  if (lags < 1) return w;
  w.autocorrelation = Autocorrelation(y, lags);
  const double n = static_cast<double>(y.size());
  for (int k = 1; k <= lags; ++k) {
    const double r = w.autocorrelation[static_cast<std::size_t>(k - 1)];
    w.q += r * r / (n - k);
  }
  w.q *= n * (n + 2);
  w.bound = 1.96 / std::sqrt(n);
  w.p = ChiSquareUpperTail(w.q, lags);
  return w;
}

CrossCorrelation PeakCrossCorrelation(const std::vector<double>& residual, const std::vector<double>& input, int max_lag,
                                      int step, const std::string& name, int family) {
  CrossCorrelation out;
  out.input = name;
  const std::vector<double> r = EveryStep(residual, step), u = EveryStep(input, step);
  const std::size_t n = std::min(r.size(), u.size());
  if (n < 8) return out;
  const int reach = std::min<int>(max_lag, static_cast<int>(n / 4));
  // r[i] against u[i - lag], the lags in increasing order: shifts of u from +reach down.
  const Alignment peak = BestAlignment(std::vector<double>(r.begin(), r.begin() + static_cast<long>(n)),
                                       std::vector<double>(u.begin(), u.begin() + static_cast<long>(n)), reach, -reach,
                                       true);
  out.peak = peak.correlation;
  out.lag = -peak.shift * std::max(step, 1);
  // Two autocorrelated series correlate by chance more than white ones: Bartlett's
  // variance of a cross-correlation, n_eff = n / (1 + 2 sum r_res(k) r_in(k)).
  const int lags = std::min<int>(50, static_cast<int>(n / 4));
  const std::vector<double> ar = Autocorrelation(r, lags), au = Autocorrelation(u, lags);
  double inflation = 1;
  for (int k = 0; k < lags; ++k) inflation += 2 * ar[static_cast<std::size_t>(k)] * au[static_cast<std::size_t>(k)];
  const double effective = static_cast<double>(n) / std::max(inflation, 1.0);
  // The band for the largest of `tests` correlations, each within it with 1 - alpha_1:
  // (1 - alpha_1)^tests = 0.95.
  const double tests = static_cast<double>(2 * reach + 1) * std::max(1, family);
  out.bound = TwoSidedNormalQuantile(1 - std::pow(0.95, 1 / tests)) / std::sqrt(effective);
  return out;
}

}  // namespace twinsim

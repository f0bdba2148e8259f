#include "diagnosis/response_changes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "analysis/omni_replay.h"
#include "core/error.h"
#include "diagnosis/statistics.h"

namespace twinsim {
namespace {

// Sums of one stretch's rows for the least-squares scale sum(xy) / sum(xx).
struct Sums {
  double xx = 0, xy = 0, yy = 0;
  double Scale() const { return xx > 0 ? xy / xx : 0; }
  double SquaredError() const { return xx > 0 ? yy - xy * xy / xx : yy; }
};

struct Split {
  std::size_t row = 0;
  Sums left, right;
  bool found = false;
};

// Prefix sums of x^2, xy and y^2, for any stretch's sums in constant time.
class PrefixSums {
 public:
  PrefixSums(const std::vector<double>& x, const std::vector<double>& y) : c_(x.size() + 1) {
    for (std::size_t i = 0; i < x.size(); ++i) {
      c_[i + 1] = {c_[i].xx + x[i] * x[i], c_[i].xy + x[i] * y[i], c_[i].yy + y[i] * y[i]};
    }
  }
  // Rows [first, last).
  Sums Of(std::size_t first, std::size_t last) const {
    return {c_[last].xx - c_[first].xx, c_[last].xy - c_[first].xy, c_[last].yy - c_[first].yy};
  }

 private:
  std::vector<Sums> c_;
};

// The split of rows [first, last) that leaves the least squared error, each side at
// least `min_seconds` long.
Split BestSplit(const std::vector<double>& t, const PrefixSums& sums, std::size_t first, std::size_t last,
                double min_seconds) {
  Split best;
  double best_error = 0;
  for (std::size_t s = first + 1; s < last; ++s) {
    if (t[s] - t[first] < min_seconds || t[last - 1] - t[s] < min_seconds) continue;
    const Sums left = sums.Of(first, s), right = sums.Of(s, last);
    if (left.xx <= 0 || right.xx <= 0) continue;
    const double error = left.SquaredError() + right.SquaredError();
    if (!best.found || error < best_error) {
      best = {s, left, right, true};
      best_error = error;
    }
  }
  return best;
}

// The two splits a < b of rows [first, last) that leave the least squared error with
// three scales: a stretch in the middle that differs from both ends (a floor crossed
// and left), which no single split fits. Each piece at least `min_seconds` long.
bool BestPair(const std::vector<double>& t, const PrefixSums& sums, std::size_t first, std::size_t last,
              double min_seconds, std::size_t* a_out, std::size_t* b_out) {
  bool found = false;
  double best_error = 0;
  for (std::size_t a = first + 1; a < last; ++a) {
    if (t[a] - t[first] < min_seconds) continue;
    const Sums left = sums.Of(first, a);
    if (left.xx <= 0) continue;
    for (std::size_t b = a + 1; b < last; ++b) {
      if (t[b] - t[a] < min_seconds) continue;
      if (t[last - 1] - t[b] < min_seconds) break;
      const Sums middle = sums.Of(a, b), right = sums.Of(b, last);
      if (middle.xx <= 0 || right.xx <= 0) continue;
      const double error = left.SquaredError() + middle.SquaredError() + right.SquaredError();
      if (!found || error < best_error) {
        *a_out = a;
        *b_out = b;
        best_error = error;
        found = true;
      }
    }
  }
  return found;
}

// The residual's long-run variance (the variance of its mean times its length) by
// Newey-West (Bartlett kernel, statistics.h), which a slowly decaying correlation biases
// low (to 84 % for an AR(1) with phi = 0.9 at 54 lags);
double BartlettLongRunVariance(const std::vector<double>& e, int bandwidth_rows) {
  const LongRunTest lr = LongRunMeanTest(e, bandwidth_rows);
  return lr.standard_error * lr.standard_error * static_cast<double>(e.size());
}

// ... and prewhitened by an AR(1) fit (Andrews and Monahan, 1992): sigma_u^2 / (1 - phi)^2,
// unbiased where the correlation is that of an AR(1), as a velocity differenced from
// camera poses nearly is. The change's standard error takes the larger of the two.
double Ar1LongRunVariance(const std::vector<double>& e) {
  const std::size_t n = e.size();
  if (n < 3) return 0;
  double mean = 0;
  for (double v : e) mean += v;
  mean /= static_cast<double>(n);
  double c0 = 0, c1 = 0;
  for (std::size_t i = 0; i < n; ++i) c0 += (e[i] - mean) * (e[i] - mean);
  for (std::size_t i = 1; i < n; ++i) c1 += (e[i] - mean) * (e[i - 1] - mean);
  if (!(c0 > 0)) return 0;
  const double phi = std::clamp(c1 / c0, -0.97, 0.97);  // bounded: a unit root has no long-run variance
  const double innovation = c0 / static_cast<double>(n) * (1 - phi * phi);
  return innovation / ((1 - phi) * (1 - phi));
}

// |s_a - s_b| over its standard error, sigma_lr^2 (1 / sum_a x^2 + 1 / sum_b x^2), with
// sigma_lr^2 the long-run variance of the residual the fitted scales leave.
double DifferenceT(const std::vector<double>& residual, const Sums& a, const Sums& b, int bandwidth_rows) {
  const double long_run_variance = std::max(BartlettLongRunVariance(residual, bandwidth_rows),
                                            Ar1LongRunVariance(residual));
  const double se = std::sqrt(long_run_variance * (1 / a.xx + 1 / b.xx));
  return se > 0 ? std::abs(a.Scale() - b.Scale()) / se : 0;
}

// The t statistic of the split's change in scale over the stretch [first, last).
double ChangeT(const std::vector<double>& x, const std::vector<double>& y, std::size_t first, std::size_t last,
               const Split& split, int bandwidth_rows) {
  std::vector<double> residual;
  residual.reserve(last - first);
  const double before = split.left.Scale(), after = split.right.Scale();
  for (std::size_t i = first; i < last; ++i) residual.push_back(y[i] - (i < split.row ? before : after) * x[i]);
  return DifferenceT(residual, split.left, split.right, bandwidth_rows);
}

// The same for a middle stretch [a, b) of [first, last) against both ends pooled: the
// residual that of three scales (ends, middle, ends each their own).
double MiddleT(const std::vector<double>& x, const std::vector<double>& y, const PrefixSums& sums, std::size_t first,
               std::size_t a, std::size_t b, std::size_t last, int bandwidth_rows) {
  const Sums left = sums.Of(first, a), middle = sums.Of(a, b), right = sums.Of(b, last);
  const Sums ends{left.xx + right.xx, left.xy + right.xy, left.yy + right.yy};
  std::vector<double> residual;
  residual.reserve(last - first);
  for (std::size_t i = first; i < last; ++i) {
    const double scale = i < a ? left.Scale() : (i < b ? middle.Scale() : right.Scale());
    residual.push_back(y[i] - scale * x[i]);
  }
  return DifferenceT(residual, middle, ends, bandwidth_rows);
}

double MedianStep(const std::vector<double>& t) {
  std::vector<double> d;
  for (std::size_t i = 1; i < t.size(); ++i) d.push_back(t[i] - t[i - 1]);
  if (d.empty()) return 0;
  std::nth_element(d.begin(), d.begin() + static_cast<long>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

// Body velocities of a pose series differenced between rows `lo` and `hi`, expressed in
// the robot frame at heading `theta`.
Twist2 BodyVelocity(const Pose2& a, double ta, const Pose2& b, double tb, double theta) {
  const double h = tb - ta;
  return FieldToBody(Twist2{(b.x - a.x) / h, (b.y - a.y) / h, (b.theta - a.theta) / h}, theta);
}

// Per row of `log`: the measured and the model's body velocity, each differenced between
// the same two measured rows about `half` frames either side; `valid` false where no
// such rows lie within twice that.
struct VelocityPairs {
  std::vector<Twist2> measured, modelled;
  std::vector<char> valid;
};

VelocityPairs PairVelocities(const OmniLog& log, const OmniReplayResult& run, int half) {
  const std::size_t n = log.rows.size();
  VelocityPairs out;
  out.measured.resize(n);
  out.modelled.resize(n);
  out.valid.assign(n, 0);
  std::vector<int> frame(n);
  std::vector<std::size_t> measured;
  for (std::size_t i = 0; i < n; ++i) {
    frame[i] = log.FrameIndex(i);
    if (log.rows[i].measured && run.predicted[i]) measured.push_back(i);
  }
  for (std::size_t i = 0; i < n; ++i) {
    // The last measured row at least `half` frames before i and the first at least `half` after.
    auto after = std::lower_bound(measured.begin(), measured.end(), i, [&](std::size_t r, std::size_t row) {
      return frame[r] < frame[row] + half;
    });
    auto before = std::upper_bound(measured.begin(), measured.end(), i, [&](std::size_t row, std::size_t r) {
      return frame[row] - half < frame[r];
    });
    if (after == measured.end() || before == measured.begin()) continue;
    const std::size_t lo = *(before - 1), hi = *after;
    if (frame[hi] - frame[lo] > 4 * half) continue;
    const OmniLogRow &a = log.rows[lo], &b = log.rows[hi];
    out.measured[i] = BodyVelocity(a.pose, a.t, b.pose, b.t, log.rows[i].pose.theta);
    out.modelled[i] = BodyVelocity(run.pose[lo], a.t, run.pose[hi], b.t, run.pose[i].theta);
    out.valid[i] = 1;
  }
  return out;
}

std::string Describe(const std::string& quantity, const ScaleChange& c) {
  char text[200];
  std::snprintf(text, sizeof text, "the %s %s from %.2f to %.2f at t = %.1f s", quantity.c_str(),
                c.after < c.before ? "fell" : "rose", c.before, c.after, c.t);
  return text;
}

// Smallest largest-speed (m/s) and turn rate (rad/s) of the model worth a scale: below,
// the model says the robot stands and the camera's noise is all there is.
constexpr double kMinSpeed = 0.02;
constexpr double kMinTurnRate = 0.1;
// Rows where the model moves at this share of its largest speed or more carry a scale.
constexpr double kMovingShare = 0.5;
// The differencing window's half width (s): the Robotino's camera quantises poses to
// 1.8 mm, 6 % of a frame's travel at 0.1 m/s.
constexpr double kHalfWindowSeconds = 0.15;

}  // namespace

std::vector<ScaleChange> FindScaleChanges(const std::vector<double>& t, const std::vector<double>& x,
                                          const std::vector<double>& y, const ScaleChangeOptions& options) {
  std::vector<ScaleChange> out;
  if (t.size() < 8 || x.size() != t.size() || y.size() != t.size()) return out;
  const double step = MedianStep(t);
  if (!(step > 0)) return out;
  const int bandwidth = std::max(1, static_cast<int>(std::lround(options.bandwidth_seconds / step)));
  const PrefixSums sums(x, y);
  // The change at split.row between rows [first, last), or none: large enough and sure enough.
  auto test = [&](std::size_t first, std::size_t last, const Split& split, ScaleChange* change) {
    const double before = split.left.Scale(), after = split.right.Scale();
    const double larger = std::max(std::abs(before), std::abs(after));
    if (!(larger > 0) || std::abs(after - before) < options.min_relative * larger) return false;
    const double t_stat = ChangeT(x, y, first, last, split, bandwidth);
    if (t_stat < options.min_t) return false;
    *change = {split.row, t[split.row], before, after, t_stat};
    return true;
  };
  std::vector<std::pair<std::size_t, std::size_t>> stretches = {{0, t.size()}};
  while (!stretches.empty()) {
    const auto [first, last] = stretches.back();
    stretches.pop_back();
    const Split split = BestSplit(t, sums, first, last, options.min_segment_seconds);
    ScaleChange change;
    if (split.found && test(first, last, split, &change)) {
      out.push_back(change);
      stretches.push_back({first, split.row});
      stretches.push_back({split.row, last});
      continue;
    }
    // No single change: a middle stretch unlike both ends (whose other edge pollutes a
    // single split's residual), tested against both ends together; then each edge is a
    // change where the scales either side of it differ by the size rule.
    std::size_t a = 0, b = 0;
    if (!BestPair(t, sums, first, last, options.min_segment_seconds, &a, &b)) continue;
    const Sums left = sums.Of(first, a), middle = sums.Of(a, b), right = sums.Of(b, last);
    const double t_stat = MiddleT(x, y, sums, first, a, b, last, bandwidth);
    if (t_stat < options.min_t) continue;
    auto large = [&](double p, double q) {
      const double larger = std::max(std::abs(p), std::abs(q));
      return larger > 0 && std::abs(q - p) >= options.min_relative * larger;
    };
    if (!large(left.Scale(), middle.Scale()) || !large(middle.Scale(), right.Scale())) continue;
    out.push_back({a, t[a], left.Scale(), middle.Scale(), t_stat});
    out.push_back({b, t[b], middle.Scale(), right.Scale(), t_stat});
    stretches.push_back({first, a});
    stretches.push_back({a, b});
    stretches.push_back({b, last});
  }
  std::sort(out.begin(), out.end(), [](const ScaleChange& p, const ScaleChange& q) { return p.row < q.row; });
  // Each change said between the scales of the final pieces either side of it: a piece
  // split again after its change was found no longer has the scale it was found with.
  for (std::size_t k = 0; k < out.size(); ++k) {
    const std::size_t from = k == 0 ? 0 : out[k - 1].row;
    const std::size_t to = k + 1 < out.size() ? out[k + 1].row : t.size();
    out[k].before = sums.Of(from, out[k].row).Scale();
    out[k].after = sums.Of(out[k].row, to).Scale();
  }
  return out;
}

std::vector<ResponseChange> FindOmniResponseChanges(const OmniModel& model, const std::vector<OmniLog>& logs,
                                                    const std::string& backend, const ScaleChangeOptions& options,
                                                    std::vector<std::string>* notes) {
  std::vector<ResponseChange> out;
  for (const OmniLog& log : logs) {
    OmniReplayOptions free_run;
    free_run.backend = backend;
    free_run.horizon = 0;
    OmniReplayResult run;
    try {
      run = ReplayOmniLog(model, log, free_run);
    } catch (const CheckFailed& e) {
      if (notes) notes->push_back(log.path + ": changes part way not searched: the model's free run diverged: " + e.what());
      continue;
    }
    const int half = std::max(1, static_cast<int>(std::lround(kHalfWindowSeconds / log.frame_period)));
    const VelocityPairs v = PairVelocities(log, run, half);
    double top_speed = 0, top_turn = 0;
    for (std::size_t i = 0; i < v.valid.size(); ++i) {
      if (!v.valid[i]) continue;
      top_speed = std::max(top_speed, std::hypot(v.modelled[i].vx, v.modelled[i].vy));
      top_turn = std::max(top_turn, std::abs(v.modelled[i].omega));
    }
    for (const bool turn : {false, true}) {
      if (turn ? top_turn < kMinTurnRate : top_speed < kMinSpeed) continue;
      std::vector<double> t, x, y;
      for (std::size_t i = 0; i < v.valid.size(); ++i) {
        if (!v.valid[i]) continue;
        const Twist2 &m = v.modelled[i], &r = v.measured[i];
        const double size = turn ? std::abs(m.omega) : std::hypot(m.vx, m.vy);
        if (size < kMovingShare * (turn ? top_turn : top_speed)) continue;
        t.push_back(log.rows[i].t);
        // Along the model's own direction: its speed, and the measured velocity's share of it.
        x.push_back(turn ? m.omega : size);
        y.push_back(turn ? r.omega : (r.vx * m.vx + r.vy * m.vy) / size);
      }
      const std::string quantity = turn ? "turn-rate scale" : "velocity scale";
      for (const ScaleChange& c : FindScaleChanges(t, x, y, options)) {
        out.push_back({log.path, c.t, quantity, c.before, c.after, c.t_stat, Describe(quantity, c)});
      }
    }
  }
  return out;
}

}  // namespace twinsim

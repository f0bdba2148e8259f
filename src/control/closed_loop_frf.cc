// Closed-loop process sensitivity by multisine excitation; see closed_loop_frf.h.
#include "control/closed_loop_frf.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/error.h"
#include "core/math_constants.h"
#include "signal/multisine.h"

namespace twinsim {

bool FrfOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  if (!(std::isfinite(period) && period > 0)) return fail("period must be > 0 s");
  if (periods < 1) return fail("periods must be >= 1");
  if (!(std::isfinite(f_min) && f_min > 0)) return fail("the band's lower end must be > 0 Hz");
  if (!(std::isfinite(f_max) && f_max > f_min)) return fail("the band's upper end must be above its lower end");
  if (!(std::isfinite(amplitude) && amplitude > 0)) return fail("amplitude must be > 0 (a fraction of the effort limit)");
  return true;
}

Eigen::VectorXcd ClosedLoopFrf::Nominal(int joint) const {
  if (joint < 0 || joint >= static_cast<int>(response.size())) throw std::invalid_argument("ClosedLoopFrf: no such joint");
  const auto& r = response[static_cast<std::size_t>(joint)];
  Eigen::VectorXcd mean = Eigen::VectorXcd::Zero(frequency.size());
  for (const Eigen::VectorXcd& ps : r) mean += ps;
  return r.empty() ? mean : Eigen::VectorXcd(mean / static_cast<double>(r.size()));
}

Eigen::VectorXd ClosedLoopFrf::WorstCoherence(int joint) const {
  if (joint < 0 || joint >= static_cast<int>(response.size())) throw std::invalid_argument("ClosedLoopFrf: no such joint");
  Eigen::VectorXd worst = Eigen::VectorXd::Ones(frequency.size());
  if (static_cast<std::size_t>(joint) < coherence.size()) {
    for (const Eigen::VectorXd& c : coherence[static_cast<std::size_t>(joint)]) worst = worst.cwiseMin(c);
  }
  return worst;
}

std::vector<Eigen::VectorXd> GridPostures(const ArmModel& arm, const Eigen::VectorXd& base, int a, int b, int count,
                                          const Eigen::VectorXd& low, const Eigen::VectorXd& high) {
  const int n = arm.dof();
  if (a < 0 || a >= n || b < 0 || b >= n || a == b) throw std::invalid_argument("GridPostures: bad joints");
  if (count < 1) throw std::invalid_argument("GridPostures: count must be >= 1");
  if (base.size() != n || low.size() != n || high.size() != n) throw std::invalid_argument("GridPostures: bad sizes");
  if (!(low.array() <= high.array()).all()) throw std::invalid_argument("GridPostures: low > high");
  auto values = [&](int joint) {
    const ArmJoint& j = arm.joints[static_cast<std::size_t>(joint)];
    std::vector<double> v;
    for (int k = 0; k < count; ++k) {
      const double u = count == 1 ? 0.5 : static_cast<double>(k) / (count - 1);
      v.push_back(std::clamp(low[joint] + (high[joint] - low[joint]) * u, j.lower, j.upper));
    }
    return v;
  };
  std::vector<Eigen::VectorXd> postures;
  for (double qa : values(a)) {
    for (double qb : values(b)) {
      Eigen::VectorXd q = base;
      q[a] = qa, q[b] = qb;
      postures.push_back(q);
    }
  }
  return postures;
}

ClosedLoopFrf MeasureProcessSensitivity(const ArmModel& plant, const ArmModel& hat,
                                        const std::vector<Eigen::VectorXd>& postures, const TrackingOptions& tracking,
                                        const FrfOptions& options, const std::function<void(int, int)>& progress) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("FrfOptions: " + why);
  if (postures.empty()) throw std::invalid_argument("MeasureProcessSensitivity: no postures");
  const int n = plant.dof();
  const double ts = plant.sample_time;
  const int period = static_cast<int>(std::lround(options.period / ts));
  if (period < 4) throw InputError("MeasureProcessSensitivity: the period is shorter than 4 samples");
  const int runs = options.periods + 1;
  const Eigen::Index samples = static_cast<Eigen::Index>(runs) * period;

  ClosedLoopFrf frf;
  frf.sample_time = ts;
  frf.postures = postures;
  frf.response.assign(static_cast<std::size_t>(n), {});
  frf.coherence.assign(static_cast<std::size_t>(n), {});
  int done = 0;
  const int total = n * static_cast<int>(postures.size());
  for (int j = 0; j < n; ++j) {
    double effort = plant.joints[static_cast<std::size_t>(j)].effort_limit;
    if (!(effort > 0)) effort = 1;
    // One multisine per joint (seed and joint), the same at every posture.
    const Multisine sine = RandomPhaseMultisine(period, ts, options.f_min, options.f_max, options.amplitude * effort,
                                                options.seed * 131 + static_cast<std::uint64_t>(j));
    if (frf.frequency.size() == 0) {
      frf.frequency.resize(static_cast<Eigen::Index>(sine.lines.size()));
      for (std::size_t i = 0; i < sine.lines.size(); ++i) frf.frequency[static_cast<Eigen::Index>(i)] = sine.Frequency(sine.lines[i]);
    }
    const Eigen::VectorXcd input = DftAtLines(sine.one_period, sine.lines);
    for (const Eigen::VectorXd& posture : postures) {
      if (posture.size() != n) {
        throw std::invalid_argument("MeasureProcessSensitivity: a posture has " + std::to_string(posture.size()) +
                                    " entries, the arm " + std::to_string(n) + " joints");
      }
      ArmReference hold;
      hold.sample_time = ts;
      hold.t = Eigen::VectorXd::LinSpaced(samples, 0, ts * static_cast<double>(samples - 1));
      hold.q = posture.transpose().replicate(samples, 1);
      hold.qd.setZero(samples, n), hold.qdd.setZero(samples, n);
      Eigen::MatrixXd excitation = Eigen::MatrixXd::Zero(samples, n);
      excitation.col(j) = sine.Repeat(runs);
      TrackingOptions o = tracking;
      o.feedforward = &excitation;
      o.dither = 0;
      const TrackingTrial trial = RunTrackingTrial(plant, hat, hold, o);
      Eigen::VectorXcd output = Eigen::VectorXcd::Zero(input.size());
      Eigen::VectorXd power = Eigen::VectorXd::Zero(input.size());
      for (int p = 1; p < runs; ++p) {
        const Eigen::VectorXcd y =
            DftAtLines(trial.q.col(j).segment(static_cast<Eigen::Index>(p) * period, period), sine.lines);
        output += y;
        power += y.cwiseAbs2();
      }
      Eigen::VectorXd coherence(input.size());
      for (Eigen::Index i = 0; i < input.size(); ++i) {
        coherence[i] = power[i] > 0 ? std::min(1.0, std::norm(output[i]) / (options.periods * power[i])) : 0.0;
      }
      output /= static_cast<double>(options.periods);
      frf.response[static_cast<std::size_t>(j)].push_back(output.cwiseQuotient(input));
      frf.coherence[static_cast<std::size_t>(j)].push_back(coherence);
      if (progress) progress(++done, total);
    }
  }
  return frf;
}

}  // namespace twinsim

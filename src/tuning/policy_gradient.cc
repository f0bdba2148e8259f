#include "tuning/policy_gradient.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/rng.h"

namespace twinsim {

bool PolicyGradientOptions::IsValid(int n, std::string* why) const {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (sets_per_iteration < 2) return fail("sets_per_iteration must be at least 2");
  if (max_iterations < 1) return fail("max_iterations must be at least 1");
  if (epsilon.size() != n) return fail("epsilon needs one value per parameter (" + std::to_string(n) + ")");
  if (eta.size() != n) return fail("eta needs one value per parameter (" + std::to_string(n) + ")");
  if ((lower.size() != 0 && lower.size() != n) || (upper.size() != 0 && upper.size() != n))
    return fail("lower and upper bounds need one value per parameter, or none");
  for (int i = 0; i < n; ++i) {
    if (!(epsilon[i] >= 0) || !std::isfinite(epsilon[i])) return fail("epsilon must be finite and >= 0");
    if (!(eta[i] >= 0) || !std::isfinite(eta[i])) return fail("eta must be finite and >= 0");
    if (lower.size() && upper.size() && !(lower[i] <= upper[i])) return fail("lower bound above upper bound");
  }
  if (!(exponent >= 1) || !std::isfinite(exponent)) return fail("exponent must be finite and >= 1");
  if (patience < 0) return fail("patience must be >= 0");
  return true;
}

double PowerMeanQuality(const std::vector<double>& values, const std::vector<double>& all, double exponent) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto [lo, hi] = std::minmax_element(all.begin(), all.end());
  const double margin = 1e-9 * std::max(1.0, *hi - *lo);
  double sum = 0;
  for (double v : values) sum += std::pow(v - *lo + margin, exponent);
  return std::pow(sum / static_cast<double>(values.size()), 1 / exponent) + *lo - margin;
}

int PolicyGradientStep(double a_plus, double a_zero, double a_minus) {
  const bool has_plus = !std::isnan(a_plus), has_minus = !std::isnan(a_minus), has_zero = !std::isnan(a_zero);
  if (has_zero && (!has_plus || a_zero > a_plus) && (!has_minus || a_zero > a_minus)) return 0;
  if (has_plus && has_minus) return a_plus > a_minus ? 1 : a_plus < a_minus ? -1 : 0;
  // One-sided evidence: step towards the side that beat the unperturbed group.
  if (has_plus && has_zero) return a_plus > a_zero ? 1 : 0;
  if (has_minus && has_zero) return a_minus > a_zero ? -1 : 0;
  return 0;
}

namespace {

Eigen::VectorXd Clamp(Eigen::VectorXd p, const PolicyGradientOptions& o) {
  if (o.lower.size()) p = p.cwiseMax(o.lower);
  if (o.upper.size()) p = p.cwiseMin(o.upper);
  return p;
}

}  // namespace

PolicyGradientSummary PolicyGradientSearch(const Eigen::VectorXd& initial, const PolicyGradientOptions& options,
                                           const BatchEvaluator& evaluate, const IterationCallback& on_iteration) {
  const int n = static_cast<int>(initial.size());
  std::string why;
  if (!options.IsValid(n, &why)) throw InputError("policy gradient options: " + why);

  PolicyGradientSummary summary;
  Rng rng(options.seed);
  Eigen::VectorXd p = Clamp(initial, options);
  int since_best = 0;
  summary.termination = "reached max_iterations (" + std::to_string(options.max_iterations) + ")";
  for (int it = 0; it < options.max_iterations; ++it) {
    PolicyGradientIteration record;
    record.iteration = it;
    record.parameters = p;

    // Eq. 3: every parameter of every set moves by -eps, 0 or +eps with equal chance.
    const int sets = options.sets_per_iteration;
    Eigen::MatrixXi sign(sets, n);
    std::vector<Eigen::VectorXd> batch;
    batch.reserve(sets + 1);
    batch.push_back(p);  // the current set is scored with the others
    for (int s = 0; s < sets; ++s) {
      Eigen::VectorXd q = p;
      for (int i = 0; i < n; ++i) {
        sign(s, i) = static_cast<int>(rng.Index(3)) - 1;
        q[i] += sign(s, i) * options.epsilon[i];
      }
      batch.push_back(Clamp(q, options));
    }
    const std::vector<double> scores = evaluate(batch);
    if (static_cast<int>(scores.size()) != sets + 1)
      throw std::logic_error("policy gradient: the evaluator returned the wrong number of qualities");
    summary.evaluations += sets + 1;
    record.quality = scores[0];
    record.sets.assign(batch.begin() + 1, batch.end());
    record.qualities.assign(scores.begin() + 1, scores.end());

    if (it == 0 || record.quality > summary.best_quality) {
      summary.best_quality = record.quality;
      summary.best_parameters = p;
      summary.best_iteration = it;
      since_best = 0;
    } else {
      ++since_best;
    }

    // Eqs. 5 and 6, parameter by parameter.
    record.step = Eigen::VectorXi::Zero(n);
    for (int i = 0; i < n; ++i) {
      std::vector<double> group[3];  // -, 0, +
      for (int s = 0; s < sets; ++s) group[sign(s, i) + 1].push_back(record.qualities[s]);
      const double a_minus = PowerMeanQuality(group[0], record.qualities, options.exponent);
      const double a_zero = PowerMeanQuality(group[1], record.qualities, options.exponent);
      const double a_plus = PowerMeanQuality(group[2], record.qualities, options.exponent);
      record.step[i] = options.eta[i] > 0 ? PolicyGradientStep(a_plus, a_zero, a_minus) : 0;
    }
    p = Clamp(p + (record.step.cast<double>().array() * options.eta.array()).matrix(), options);
    summary.iterations.push_back(record);
    if (on_iteration) on_iteration(summary.iterations.back());
    if (options.patience > 0 && since_best >= options.patience) {
      summary.termination = "no better current set for " + std::to_string(options.patience) + " iterations";
      break;
    }
  }
  summary.final_parameters = p;
  return summary;
}

std::string PolicyGradientSummary::BriefReport() const {
  std::ostringstream out;
  out << "policy gradient: " << iterations.size() << " iterations, " << evaluations << " test runs, best quality "
      << best_quality << " at iteration " << best_iteration << " (" << termination << ")";
  return out.str();
}

std::string PolicyGradientSummary::FullReport() const {
  std::ostringstream out;
  out << BriefReport() << "\n";
  for (const auto& it : iterations) {
    const auto [lo, hi] = std::minmax_element(it.qualities.begin(), it.qualities.end());
    out << "  iteration " << it.iteration << ": current " << it.quality << ", tested " << *lo << " .. " << *hi
        << ", steps +" << (it.step.array() > 0).count() << " -" << (it.step.array() < 0).count() << "\n";
  }
  return out.str();
}

}  // namespace twinsim

// Iterative learning control: learning filters, the update and the trials; see
// iterative_learning.h.
#include "control/iterative_learning.h"

#include <Eigen/QR>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/error.h"
#include "core/math_constants.h"
#include "robots/arm/arm_dynamics.h"
#include "signal/butterworth.h"

namespace twinsim {
namespace {

// The basis responses of L at z = e^{j w Ts}: the inertia at z^shift and at
// z^(shift+1), the damping (the stiffness's is 1) and, if asked, the snap split evenly
// over z^shift and z^(shift+1) (centred half a sample early, as the inertia's pair).
void Basis(double frequency_hz, double ts, int shift, std::complex<double>* b2, std::complex<double>* b2_early,
           std::complex<double>* b1, std::complex<double>* b4 = nullptr) {
  const std::complex<double> z = std::polar(1.0, 2 * kPi * frequency_hz * ts);
  const std::complex<double> second = (z - 2.0 + 1.0 / z) / (ts * ts);
  *b2 = std::pow(z, shift) * second;
  *b2_early = z * *b2;
  *b1 = (z - 1.0 / z) / (2 * ts);
  if (b4) *b4 = 0.5 * (*b2 + *b2_early) * second;
}

// min |a x - b| subject to x >= 0, for the few columns of a learning filter's fit: every
// subset of columns is solved unconstrained and the best one with no negative entry
// kept (at most 2^3 small solves; the empty set, x = 0, is always feasible).
Eigen::VectorXd NonNegativeLeastSquares(const Eigen::MatrixXd& a, const Eigen::VectorXd& b) {
  const auto n = static_cast<int>(a.cols());
  Eigen::VectorXd best = Eigen::VectorXd::Zero(n);
  double best_cost = b.squaredNorm();
  for (int set = 1; set < (1 << n); ++set) {
    std::vector<Eigen::Index> cols;
    for (int k = 0; k < n; ++k) {
      if (set & (1 << k)) cols.push_back(k);
    }
    const Eigen::MatrixXd sub = a(Eigen::all, cols);
    const Eigen::VectorXd scale = sub.colwise().norm().transpose().cwiseMax(1e-300);
    const Eigen::VectorXd y =
        (sub * scale.cwiseInverse().asDiagonal()).colPivHouseholderQr().solve(b).cwiseQuotient(scale);
    if ((y.array() < 0).any()) continue;
    Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
    x(cols) = y;
    const double cost = (a * x - b).squaredNorm();
    if (cost < best_cost) best_cost = cost, best = x;
  }
  return best;
}

void CheckJoint(const ClosedLoopFrf& frf, int joint) {
  if (joint < 0 || joint >= static_cast<int>(frf.response.size())) {
    throw std::invalid_argument("ILC: joint " + std::to_string(joint + 1) + " is not in the frequency response");
  }
}

// The measured lines in [f_min, f_max] (Hz) whose coherence is at least min_coherence.
std::vector<Eigen::Index> LinesInBand(const ClosedLoopFrf& frf, double f_min, double f_max,
                                     const Eigen::VectorXd& coherence, double min_coherence) {
  std::vector<Eigen::Index> lines;
  for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
    if (frf.frequency[i] >= f_min - 1e-9 && frf.frequency[i] <= f_max + 1e-9 && coherence[i] >= min_coherence) {
      lines.push_back(i);
    }
  }
  return lines;
}

}  // namespace

std::complex<double> LearningFilter::Response(double frequency_hz, double sample_time) const {
  std::complex<double> b2, b2e, b1, b4;
  Basis(frequency_hz, sample_time, shift, &b2, &b2e, &b1, &b4);
  return inertia * b2 + inertia_early * b2e + snap * b4 + damping * b1 + stiffness;
}

Eigen::VectorXd LearningFilter::Apply(const Eigen::VectorXd& e, double sample_time) const {
  const Eigen::Index n = e.size();
  Eigen::VectorXd out(n);
  if (n == 0) return out;
  auto at = [&](Eigen::Index i) { return e[std::clamp<Eigen::Index>(i, 0, n - 1)]; };
  const double h = sample_time;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Index c = k + shift;
    out[k] = (inertia * (at(c + 1) - 2 * at(c) + at(c - 1)) + inertia_early * (at(c + 2) - 2 * at(c + 1) + at(c))) /
                 (h * h) +
             damping * (at(k + 1) - at(k - 1)) / (2 * h) + stiffness * at(k);
    if (snap != 0) {
      auto fourth = [&](Eigen::Index m) { return at(m + 2) - 4 * at(m + 1) + 6 * at(m) - 4 * at(m - 1) + at(m - 2); };
      out[k] += snap * 0.5 * (fourth(c) + fourth(c + 1)) / (h * h * h * h);
    }
  }
  return out;
}

Eigen::SparseMatrix<double> LearningFilter::Matrix(Eigen::Index n, double sample_time) const {
  // The rows of Apply: each coefficient lands on its clamped index, as e holds its first
  // and last value beyond the ends.
  std::vector<Eigen::Triplet<double>> entries;
  const double h = sample_time;
  for (Eigen::Index k = 0; k < n; ++k) {
    auto add = [&](Eigen::Index i, double value) {
      if (value != 0) entries.emplace_back(k, std::clamp<Eigen::Index>(i, 0, n - 1), value);
    };
    const Eigen::Index c = k + shift;
    for (int d = -1; d <= 1; ++d) add(c + d, inertia * (d == 0 ? -2 : 1) / (h * h));
    for (int d = 0; d <= 2; ++d) add(c + d, inertia_early * (d == 1 ? -2 : 1) / (h * h));
    add(k + 1, damping / (2 * h));
    add(k - 1, -damping / (2 * h));
    add(k, stiffness);
    if (snap != 0) {
      const double w[5] = {1, -4, 6, -4, 1};
      for (int m : {0, 1}) {
        for (int d = -2; d <= 2; ++d) add(c + m + d, snap * 0.5 * w[d + 2] / (h * h * h * h));
      }
    }
  }
  Eigen::SparseMatrix<double> l(n, n);
  l.setFromTriplets(entries.begin(), entries.end());  // sums duplicates
  return l;
}

Eigen::VectorXd NormOptimalStep(const LearningFilter& filter, double weight, const Eigen::VectorXd& e,
                                double sample_time) {
  const Eigen::SparseMatrix<double> l = filter.Matrix(e.size(), sample_time);
  Eigen::SparseMatrix<double> a = weight * (l * Eigen::SparseMatrix<double>(l.transpose()));
  for (Eigen::Index i = 0; i < e.size(); ++i) a.coeffRef(i, i) += 1;
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(a);
  if (ldlt.info() != Eigen::Success) throw std::runtime_error("NormOptimalStep: I + w L L^T did not factor");
  return ldlt.solve(Eigen::VectorXd(l * e));
}

double NormOptimalWeight(const LearningFilter& filter, double bandwidth_hz, double sample_time) {
  return 1 / std::norm(filter.Response(bandwidth_hz, sample_time));
}

std::string LearningFilter::Summary() const {
  std::ostringstream out;
  out.precision(4);
  out << "tau " << shift << " samples, inertia " << inertia + inertia_early << " kg m^2 (" << inertia << " at tau, "
      << inertia_early << " at tau + 1), ";
  if (snap != 0) out << "snap " << snap << " kg m^2 s^2, ";
  out << "damping " << damping << " N m s/rad, stiffness " << stiffness << " N m/rad";
  if (residual > 0) out << " (fit residual RMS |PS L - 1| = " << residual << ")";
  return out.str();
}

LearningFilter FitLearningFilter(const ClosedLoopFrf& frf, int joint, double f_min, double f_max, int max_shift) {
  CheckJoint(frf, joint);
  if (max_shift < 0) throw InputError("FitLearningFilter: max_shift must be >= 0");
  const std::vector<Eigen::Index> lines = LinesInBand(frf, f_min, f_max, Eigen::VectorXd::Ones(frf.frequency.size()), 0);
  if (lines.size() < 2) {
    throw InputError("FitLearningFilter: fewer than 2 measured lines in [" + std::to_string(f_min) + ", " +
                     std::to_string(f_max) + "] Hz");
  }
  const auto& responses = frf.response[static_cast<std::size_t>(joint)];
  const auto rows = static_cast<Eigen::Index>(2 * lines.size() * responses.size());
  LearningFilter best;
  best.residual = std::numeric_limits<double>::infinity();
  for (int shift = 0; shift <= max_shift; ++shift) {
    // PS (a2 B2 + a1 B1 + a0) = 1, real and imaginary parts, each column scaled to unit
    // norm so that the inertia (~1) and the stiffness (~1e3) are solved alike.
    Eigen::MatrixXd a(rows, 4);
    Eigen::VectorXd b(rows);
    Eigen::Index r = 0;
    for (const Eigen::VectorXcd& ps : responses) {
      for (Eigen::Index i : lines) {
        std::complex<double> b2, b2e, b1;
        Basis(frf.frequency[i], frf.sample_time, shift, &b2, &b2e, &b1);
        const std::complex<double> c[4] = {ps[i] * b2, ps[i] * b2e, ps[i] * b1, ps[i]};
        for (int k = 0; k < 4; ++k) a(r, k) = c[k].real(), a(r + 1, k) = c[k].imag();
        b[r] = 1, b[r + 1] = 0;
        r += 2;
      }
    }
    const Eigen::Vector4d scale = a.colwise().norm().transpose().cwiseMax(1e-300);
    const Eigen::Vector4d x = (a * scale.cwiseInverse().asDiagonal()).colPivHouseholderQr().solve(b).cwiseQuotient(scale);
    LearningFilter f;
    f.shift = shift, f.inertia = x[0], f.inertia_early = x[1], f.damping = x[2], f.stiffness = x[3];
    double sum = 0;
    for (const Eigen::VectorXcd& ps : responses) {
      for (Eigen::Index i : lines) sum += std::norm(ps[i] * f.Response(frf.frequency[i], frf.sample_time) - 1.0);
    }
    f.residual = std::sqrt(sum / static_cast<double>(rows / 2));
    if (f.residual < best.residual) best = f;
  }
  return best;
}

bool PlantFitOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  if (!(f_min > 0 && f_max > f_min)) return fail("the fit band must be [low, high] Hz with 0 < low < high");
  if (max_shift < 0) return fail("max_shift must be >= 0");
  if (!(min_coherence >= 0 && min_coherence <= 1)) return fail("coherence must lie in [0, 1]");
  if (order != 2 && order != 4) return fail("model_order must be 2 (rigid) or 4 (with a series spring)");
  return true;
}

LearningFilter FitPlantLearningFilter(const ClosedLoopFrf& frf, int joint, const LearningFilter& feedback,
                                      double viscous, const PlantFitOptions& options) {
  CheckJoint(frf, joint);
  std::string why;
  if (!options.IsValid(&why)) throw InputError("the learning filter's fit: " + why);
  const Eigen::VectorXcd ps = frf.Nominal(joint);
  const std::vector<Eigen::Index> lines =
      LinesInBand(frf, options.f_min, options.f_max, frf.WorstCoherence(joint), options.min_coherence);
  // The fitted coefficients: both inertias, and at order 4 the snap.
  const int unknowns = options.order == 4 ? 3 : 2;
  // Each line gives two equations (real and imaginary parts); at least two lines, and
  // one per coefficient, so that the delay is told from the inertia.
  const int needed = std::max(2, unknowns);
  if (lines.size() < static_cast<std::size_t>(needed)) {
    std::ostringstream msg;
    msg << "fewer than " << needed << " measured lines in [" << options.f_min << ", " << options.f_max
        << "] Hz with coherence >= " << options.min_coherence << " for a model of order " << options.order;
    throw InputError("the learning filter's fit: " + msg.str());
  }
  const auto rows = static_cast<Eigen::Index>(2 * lines.size());
  LearningFilter best;
  best.residual = std::numeric_limits<double>::infinity();
  for (int shift = 0; shift <= options.max_shift; ++shift) {
    LearningFilter f = feedback;
    f.shift = shift;
    f.snap = 0;
    f.order = options.order;
    f.damping = feedback.damping + viscous;
    // Start from the equation error (weights 1), then weight each line by 1 / |L|^2 of
    // the last iterate, so that |PS L - 1|^2 / |L|^2 = |PS - 1/L|^2: the output error.
    Eigen::VectorXd weight = Eigen::VectorXd::Ones(static_cast<Eigen::Index>(lines.size()));
    for (int iteration = 0; iteration < 8; ++iteration) {
      // PS (a2 B2 + a2' B2e [+ a4 B4]) = 1 - PS (a1 B1 + a0), real and imaginary parts.
      Eigen::MatrixXd a(rows, unknowns);
      Eigen::VectorXd b(rows);
      for (std::size_t k = 0; k < lines.size(); ++k) {
        const Eigen::Index i = lines[k];
        std::complex<double> basis[3], b1;
        Basis(frf.frequency[i], frf.sample_time, shift, &basis[0], &basis[1], &b1, &basis[2]);
        const double w = std::sqrt(weight[static_cast<Eigen::Index>(k)]);
        const std::complex<double> rhs = (1.0 - ps[i] * (f.damping * b1 + f.stiffness)) * w;
        const auto r = static_cast<Eigen::Index>(2 * k);
        for (int u = 0; u < unknowns; ++u) {
          const std::complex<double> c = ps[i] * basis[u] * w;
          a(r, u) = c.real(), a(r + 1, u) = c.imag();
        }
        b[r] = rhs.real(), b[r + 1] = rhs.imag();
      }
      // An inertia cannot be negative (a negative one would stand for damping the fit
      // must not take), nor can J_m J_l / k.
      const Eigen::VectorXd x = NonNegativeLeastSquares(a, b);
      f.inertia = x[0], f.inertia_early = x[1];
      if (unknowns == 3) f.snap = x[2];
      for (std::size_t k = 0; k < lines.size(); ++k) {
        weight[static_cast<Eigen::Index>(k)] =
            1 / std::max(std::norm(f.Response(frf.frequency[lines[k]], frf.sample_time)), 1e-300);
      }
    }
    double sum = 0;
    for (Eigen::Index i : lines) sum += std::norm(ps[i] * f.Response(frf.frequency[i], frf.sample_time) - 1.0);
    f.residual = std::sqrt(sum / static_cast<double>(lines.size()));
    f.lines = static_cast<int>(lines.size());
    f.band_min = frf.frequency[lines.front()], f.band_max = frf.frequency[lines.back()];
    if (f.residual < best.residual) best = f;
  }
  return best;
}

LearningFilter ModelLearningFilter(const ArmModel& hat, const TrackingOptions& tracking, const Eigen::VectorXd& q,
                                   const Eigen::VectorXd& q_start, int joint) {
  if (joint < 0 || joint >= hat.dof()) throw std::invalid_argument("ModelLearningFilter: no such joint");
  if (q.size() != hat.dof() || q_start.size() != hat.dof()) throw std::invalid_argument("ModelLearningFilter: bad posture size");
  const double m = MassMatrix(hat, q)(joint, joint);
  LearningFilter f;
  f.shift = hat.delay_samples;
  f.inertia = f.inertia_early = m / 2;
  if (tracking.controller == TrackingController::kPdFeedforward) {
    const TrackingGains g = PdFeedforwardGains(hat, q_start, tracking.bandwidth, tracking.damping);
    f.damping = g.kd[joint], f.stiffness = g.kp[joint];
  } else {
    const TrackingGains g = ComputedTorqueGains(hat.dof(), tracking.bandwidth, tracking.damping);
    f.damping = m * g.kd[joint], f.stiffness = m * g.kp[joint];
  }
  return f;
}

double IlcOptions::Cutoff(int joint) const {
  return joint >= 0 && static_cast<std::size_t>(joint) < q_cutoffs.size() ? q_cutoffs[static_cast<std::size_t>(joint)]
                                                                           : q_cutoff;
}

bool IlcOptions::IsValid(double sample_time, std::string* why) const {
  auto fail = [&](const std::string& text) {
    if (why) *why = text;
    return false;
  };
  if (trials < 0) return fail("trials must be >= 0");
  if (!(std::isfinite(gain) && gain > 0)) return fail("gain must be > 0");
  if (q_order < 0 || q_order > 16) return fail("q_order must be 0 (no robustness filter) to 16");
  if (q_order > 0 && !(q_cutoff > 0 && q_cutoff < 0.5 / sample_time)) {
    return fail("q_cutoff must lie between 0 and the Nyquist frequency " + std::to_string(0.5 / sample_time) + " Hz");
  }
  for (double c : q_cutoffs) {
    if (q_order > 0 && !(c > 0 && c < 0.5 / sample_time)) {
      return fail("every joint's q_cutoff must lie between 0 and the Nyquist frequency " +
                  std::to_string(0.5 / sample_time) + " Hz");
    }
  }
  if (!(safeguard.growth == 0 || (std::isfinite(safeguard.growth) && safeguard.growth > 1)))
    return fail("safeguard.growth must be > 1 (or 0: no safeguard)");
  if (!(safeguard.cutoff_factor > 0 && safeguard.cutoff_factor < 1)) return fail("safeguard.cutoff_factor must lie in (0, 1)");
  if (!(std::isfinite(safeguard.min_cutoff) && safeguard.min_cutoff > 0)) return fail("safeguard.min_cutoff must be > 0");
  if (safeguard.patience < 1) return fail("safeguard.patience must be >= 1");
  if (q_criterion != "lines" && q_criterion != "robust") return fail("q_criterion must be lines or robust");
  if (update != "standard" && update != "norm_optimal") return fail("update must be standard or norm_optimal");
  if (!(std::isfinite(norm_optimal_bandwidth) && norm_optimal_bandwidth >= 0 && norm_optimal_bandwidth < 0.5 / sample_time))
    return fail("norm_optimal_bandwidth must lie between 0 (each joint's Q cutoff) and the Nyquist frequency");
  if (safeguard.lowerings < 0) return fail("safeguard.lowerings must be >= 0");
  return true;
}

Eigen::VectorXd ConvergenceFactor(const ClosedLoopFrf& frf, int joint, const LearningFilter& filter,
                                  const IlcOptions& options) {
  CheckJoint(frf, joint);
  std::string why;
  if (!options.IsValid(frf.sample_time, &why)) throw InputError("IlcOptions: " + why);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(frf.frequency.size());
  for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
    double q = 1;
    if (options.q_order > 0) {
      const ButterworthFilter bw = DesignButterworthLowPass(options.q_order, options.Cutoff(joint), 1 / frf.sample_time);
      q = std::norm(FrequencyResponse(bw, frf.frequency[i]));
    }
    const std::complex<double> l = LearningStepResponse(filter, options, joint, frf.frequency[i], frf.sample_time);
    for (const Eigen::VectorXcd& ps : frf.response[static_cast<std::size_t>(joint)]) {
      out[i] = std::max(out[i], q * std::abs(1.0 - options.gain * ps[i] * l));
    }
  }
  return out;
}

std::complex<double> LearningStepResponse(const LearningFilter& filter, const IlcOptions& options, int joint,
                                          double frequency_hz, double sample_time) {
  const std::complex<double> l = filter.Response(frequency_hz, sample_time);
  if (options.update != "norm_optimal") return l;
  return l / (1 + NormOptimalWeight(filter, options.NormOptimalBandwidth(joint), sample_time) * std::norm(l));
}

RobustCriterion RobustConvergenceFactor(const ClosedLoopFrf& frf, int joint, const LearningFilter& filter,
                                        const IlcOptions& options, double step_hz) {
  CheckJoint(frf, joint);
  std::string why;
  if (!options.IsValid(frf.sample_time, &why)) throw InputError("IlcOptions: " + why);
  if (!(step_hz > 0)) throw std::invalid_argument("RobustConvergenceFactor: step_hz must be > 0");
  const auto& postures = frf.response[static_cast<std::size_t>(joint)];
  const Eigen::Index lines = frf.frequency.size();
  if (lines == 0 || postures.empty()) throw InputError("RobustConvergenceFactor: no measured lines");
  const double nyquist = 0.5 / frf.sample_time;
  const double h = frf.sample_time;
  ButterworthFilter q_filter;
  if (options.q_order > 0) q_filter = DesignButterworthLowPass(options.q_order, options.Cutoff(joint), 1 / h);
  RobustCriterion out;
  std::vector<std::complex<double>> ps(postures.size());
  for (double f = frf.frequency[0]; f < nyquist; f += step_hz) {
    // Each posture's response at f: linear between lines, beyond the last line the last
    // line's PS L held (the fitted model's shape, the last measured error of it).
    const double last = frf.frequency[lines - 1];
    if (f >= last) {
      const std::complex<double> scale = filter.Response(last, h) / filter.Response(f, h);
      for (std::size_t p = 0; p < postures.size(); ++p) ps[p] = postures[p][lines - 1] * scale;
    } else {
      Eigen::Index i = 0;
      while (i + 2 < lines && frf.frequency[i + 1] <= f) ++i;
      const double t = (f - frf.frequency[i]) / (frf.frequency[i + 1] - frf.frequency[i]);
      for (std::size_t p = 0; p < postures.size(); ++p) ps[p] = (1 - t) * postures[p][i] + t * postures[p][i + 1];
    }
    std::complex<double> nominal = 0;
    for (const auto& v : ps) nominal += v / static_cast<double>(ps.size());
    double spread = 0;
    for (const auto& v : ps) spread = std::max(spread, std::abs(v - nominal) / std::abs(nominal));
    const std::complex<double> step = options.gain * nominal * LearningStepResponse(filter, options, joint, f, h);
    const double q = options.q_order > 0 ? std::norm(FrequencyResponse(q_filter, f)) : 1.0;
    out.frequency.push_back(f);
    out.spread.push_back(spread);
    out.factor.push_back(q * (std::abs(1.0 - step) + std::abs(step) * spread));
  }
  return out;
}

double AutoQCutoff(const ClosedLoopFrf& frf, int joint, const LearningFilter& filter, const IlcOptions& options,
                   double* worst) {
  CheckJoint(frf, joint);
  std::string why;
  if (!options.IsValid(frf.sample_time, &why)) throw InputError("IlcOptions: " + why);
  if (frf.frequency.size() == 0) throw InputError("AutoQCutoff: no measured lines");
  const double bottom = frf.frequency[0];
  // Above the measured band nothing is known: at most half its highest line, where Q has
  // fallen by 12 dB per order (96 dB for the default 4th order through FiltFilt).
  const double top = std::min(frf.frequency[frf.frequency.size() - 1] / 2, 0.45 / frf.sample_time);
  auto none = [&](const std::string& reason) {
    std::ostringstream msg;
    msg << "joint " << joint + 1 << ": no robustness filter cutoff between " << bottom << " and " << top
        << " Hz makes |Q|^2 |1 - gain PS L| < 1 at every measured line and posture" << reason
        << "; lower the gain or refit the learning filter";
    return InputError(msg.str());
  };
  if (options.q_order == 0) throw none(" (q_order is 0: no filter)");
  IlcOptions o = options;
  o.q_cutoffs.clear();
  // The highest passing cutoff: from the top down (the factor is not monotone in the
  // cutoff in general, so every grid point is tried until one passes).
  for (double cutoff = std::floor(top * 2) / 2; cutoff >= bottom - 1e-9; cutoff -= 0.5) {
    o.q_cutoff = cutoff;
    double factor = ConvergenceFactor(frf, joint, filter, o).maxCoeff();
    if (options.q_criterion == "robust") {
      const RobustCriterion robust = RobustConvergenceFactor(frf, joint, filter, o, kRobustGridHz);
      factor = std::max(factor, *std::max_element(robust.factor.begin(), robust.factor.end()));
    }
    if (factor < 1) {
      if (worst) *worst = factor;
      return cutoff;
    }
  }
  throw none("");
}

double LearningLimitFrequency(const ClosedLoopFrf& frf, int joint, const LearningFilter& filter, double gain) {
  CheckJoint(frf, joint);
  for (Eigen::Index i = 0; i < frf.frequency.size(); ++i) {
    const std::complex<double> l = filter.Response(frf.frequency[i], frf.sample_time);
    for (const Eigen::VectorXcd& ps : frf.response[static_cast<std::size_t>(joint)]) {
      if (std::abs(1.0 - gain * ps[i] * l) >= 1) return frf.frequency[i];
    }
  }
  return std::numeric_limits<double>::infinity();
}

Eigen::MatrixXd IlcUpdate(const Eigen::MatrixXd& f, const Eigen::MatrixXd& e, const std::vector<LearningFilter>& filters,
                          const IlcOptions& options, double sample_time) {
  std::string why;
  if (!options.IsValid(sample_time, &why)) throw InputError("IlcOptions: " + why);
  if (f.rows() != e.rows() || f.cols() != e.cols() || static_cast<Eigen::Index>(filters.size()) != f.cols()) {
    throw std::invalid_argument("IlcUpdate: f, e and the filters must agree in samples and joints");
  }
  Eigen::MatrixXd next = f;
  for (Eigen::Index j = 0; j < f.cols(); ++j) {
    const LearningFilter& l = filters[static_cast<std::size_t>(j)];
    if (options.update == "norm_optimal") {
      const double w = NormOptimalWeight(l, options.NormOptimalBandwidth(static_cast<int>(j)), sample_time);
      next.col(j) += options.gain * NormOptimalStep(l, w, e.col(j), sample_time);
    } else {
      next.col(j) += options.gain * l.Apply(e.col(j), sample_time);
    }
  }
  if (options.q_order > 0) {
    for (Eigen::Index j = 0; j < f.cols(); ++j) {
      const ButterworthFilter q = DesignButterworthLowPass(options.q_order, options.Cutoff(static_cast<int>(j)), 1 / sample_time);
      next.col(j) = FiltFiltColumns(q, Eigen::MatrixXd(next.col(j)));
    }
  }
  return next;
}

std::string IlcResult::BriefReport() const {
  std::ostringstream out;
  out.precision(4);
  const int last = static_cast<int>(error_rms.size()) - 1;
  out << "ILC: " << last << " learning trials, worst joint RMS error " << WorstRms(0) << " -> " << WorstRms(last)
      << " rad (" << Reduction() << "x) in " << wall_seconds << " s";
  return out.str();
}

std::string IlcResult::FullReport() const {
  std::ostringstream out;
  out.precision(4);
  out << BriefReport() << "\n";
  for (std::size_t k = 0; k < error_rms.size(); ++k) {
    out << "  trial " << k << ": RMS";
    for (Eigen::Index j = 0; j < error_rms[k].size(); ++j) out << " " << error_rms[k][j];
    out << " max";
    for (Eigen::Index j = 0; j < error_max[k].size(); ++j) out << " " << error_max[k][j];
    out << " rad\n";
  }
  return out.str();
}

IlcSafeguardWatch::IlcSafeguardWatch(const IlcSafeguard& safeguard, int q_order, std::vector<double> cutoffs)
    : safeguard_(safeguard),
      q_order_(q_order),
      cutoffs_(std::move(cutoffs)),
      best_rms_(Eigen::VectorXd::Constant(static_cast<Eigen::Index>(cutoffs_.size()), INFINITY)),
      best_trial_of_(cutoffs_.size(), 0),
      learning_(cutoffs_.size(), true),
      back_off_(cutoffs_.size(), false),
      above_(cutoffs_.size(), 0),
      lowered_(cutoffs_.size(), 0),
      best_relative_(INFINITY) {}

std::vector<IlcSafeguardEvent> IlcSafeguardWatch::Observe(int trial, const Eigen::VectorXd& error_rms,
                                                          const Eigen::MatrixXd& f) {
  const int n = static_cast<int>(cutoffs_.size());
  if (error_rms.size() != n || f.cols() != n) throw std::invalid_argument("IlcSafeguardWatch: one error per joint needed");
  if (first_rms_.size() == 0) {
    first_rms_ = error_rms;
    best_f_ = f;
  }
  const double relative = (error_rms.array() / first_rms_.array().max(1e-300)).maxCoeff();
  if (relative < best_relative_) {
    best_relative_ = relative;
    best_trial_ = trial;
    best_feedforward_ = f;
  }
  // Which joints back off: their error grew past `growth` times their best. A joint that
  // no longer learns can still grow through the others (the arm couples them): then
  // every joint goes back to the best trial's feedforward and learning ends.
  std::vector<IlcSafeguardEvent> events;
  std::fill(back_off_.begin(), back_off_.end(), false);
  for (int j = 0; j < n && !stopped_; ++j) {
    const auto js = static_cast<std::size_t>(j);
    if (error_rms[j] < best_rms_[j]) {
      best_rms_[j] = error_rms[j];
      best_trial_of_[js] = trial;
      best_f_.col(j) = f.col(j);
      above_[js] = 0;
    } else if (!(safeguard_.growth > 0 && error_rms[j] > safeguard_.growth * best_rms_[j])) {
      above_[js] = 0;
    } else if (++above_[js] >= safeguard_.patience) {
      above_[js] = 0;
      IlcSafeguardEvent event{trial, j, error_rms[j], best_rms_[j], best_trial_of_[js], 0, ""};
      const double lower = cutoffs_[js] * safeguard_.cutoff_factor;
      if (!learning_[js]) {
        stopped_ = true;
        event.best_trial = best_trial_;
        event.action = "stop_all";
      } else if (q_order_ > 0 && lower >= safeguard_.min_cutoff && lowered_[js] < safeguard_.lowerings) {
        back_off_[js] = true;
        cutoffs_[js] = event.cutoff = lower;
        event.action = "lower_q";
        ++lowered_[js];
      } else {
        back_off_[js] = true;
        learning_[js] = false;
        event.action = "stop_joint";
      }
      events.push_back(event);
    }
  }
  if (stopped_) std::fill(learning_.begin(), learning_.end(), false);
  return events;
}

Eigen::MatrixXd IlcSafeguardWatch::Next(const Eigen::MatrixXd& updated) const {
  if (stopped_) return best_feedforward_;  // the best trial, replayed from now on
  Eigen::MatrixXd f = updated;
  for (int j = 0; j < static_cast<int>(cutoffs_.size()); ++j) {
    const auto js = static_cast<std::size_t>(j);
    if (back_off_[js] || !learning_[js]) f.col(j) = best_f_.col(j);  // its best trial's, replayed
  }
  return f;
}

IlcResult RunIlc(const ArmModel& plant, const ArmModel& hat, const ArmReference& reference,
                 const TrackingOptions& tracking, const std::vector<LearningFilter>& filters, const IlcOptions& options,
                 const std::function<void(int, const TrackingTrial&)>& on_trial) {
  std::string why;
  if (!options.IsValid(plant.sample_time, &why)) throw InputError("IlcOptions: " + why);
  if (static_cast<int>(filters.size()) != plant.dof()) throw std::invalid_argument("RunIlc: one learning filter per joint needed");
  const auto start = std::chrono::steady_clock::now();
  const int n = plant.dof();
  IlcResult result;
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(reference.q.rows(), n);
  IlcOptions now = options;  // Q's cutoffs as the safeguard lowers them
  now.q_cutoffs.resize(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) now.q_cutoffs[static_cast<std::size_t>(j)] = options.Cutoff(j);
  IlcSafeguardWatch watch(options.safeguard, options.q_order, now.q_cutoffs);
  TrackingOptions o = tracking;
  for (int trial = 0; trial <= options.trials; ++trial) {
    o.feedforward = &f;
    TrackingTrial run = RunTrackingTrial(plant, hat, reference, o);
    result.error_rms.push_back(run.error_rms);
    result.error_max.push_back(run.error_max);
    if (on_trial) on_trial(trial, run);
    if (trial == 0) result.first = run;
    const std::vector<IlcSafeguardEvent> events = watch.Observe(trial, run.error_rms, f);
    result.safeguard.insert(result.safeguard.end(), events.begin(), events.end());
    now.q_cutoffs = watch.cutoffs();
    if (trial == options.trials) {
      // What the safeguard decided on the last trial applies to the feedforward handed on.
      result.feedforward = watch.Next(f);
      result.last = std::move(run);
    } else if (watch.stopped()) {
      f = watch.best_feedforward();
    } else {
      f = watch.Next(IlcUpdate(f, reference.q - run.q, filters, now, plant.sample_time));
    }
  }
  result.best_trial = watch.best_trial();
  result.best_feedforward = watch.best_feedforward();
  result.final_cutoffs.resize(n);
  for (int j = 0; j < n; ++j) result.final_cutoffs[j] = watch.learning(j) ? now.q_cutoffs[static_cast<std::size_t>(j)] : 0;
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace twinsim

#include "signal/butterworth.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/math_constants.h"

namespace twinsim {
namespace {

// DC group delay of one section in samples: N'(1)/N(1) - D'(1)/D(1) in powers of z^-1.
double DcDelay(const Biquad& s) {
  return (s.b1 + 2 * s.b2) / (s.b0 + s.b1 + s.b2) - (s.a1 + 2 * s.a2) / (1 + s.a1 + s.a2);
}

// Runs the cascade over `x` in place, each section in transposed direct form II. With
// `steady` the sections start as if the straight line through x's first samples had
// been running forever: every section (unit DC gain) then passes that line on, late by
// its DC group delay, so a ramp comes through without a start-up transient.
void RunCascade(const ButterworthFilter& filter, bool steady, Eigen::VectorXd* x) {
  double level = 0, slope = 0;  // the line a + s k through the first samples, at k = 0
  if (steady && x->size() > 0) {
    const Eigen::Index m = std::min<Eigen::Index>(
        x->size(), std::max<Eigen::Index>(2, static_cast<Eigen::Index>(filter.sample_rate_hz / filter.cutoff_hz)));
    if (m >= 2) {
      const double mean_k = 0.5 * (m - 1);
      const double mean_x = x->head(m).mean();
      double sxy = 0, sxx = 0;
      for (Eigen::Index k = 0; k < m; ++k) {
        sxy += (k - mean_k) * ((*x)[k] - mean_x);
        sxx += (k - mean_k) * (k - mean_k);
      }
      slope = sxy / sxx;
      level = mean_x - slope * mean_k;
    } else {
      level = (*x)[0];
    }
  }
  for (const Biquad& s : filter.sections) {
    double z1 = 0, z2 = 0;
    if (steady) {
      // Input u_k = level + slope k, output y_k = u_k - slope delay, for k = -1 and 0.
      const double delay = DcDelay(s);
      const double u0 = level, um1 = level - slope;
      const double y0 = u0 - slope * delay, ym1 = um1 - slope * delay;
      z2 = s.b2 * um1 - s.a2 * ym1;
      z1 = y0 - s.b0 * u0;
      level -= slope * delay;
    }
    for (Eigen::Index k = 0; k < x->size(); ++k) {
      const double in = (*x)[k];
      const double out = s.b0 * in + z1;
      z1 = s.b1 * in - s.a1 * out + z2;
      z2 = s.b2 * in - s.a2 * out;
      (*x)[k] = out;
    }
  }
}

void CheckSamples(const Eigen::VectorXd& t, const Eigen::VectorXd& x) {
  if (t.size() != x.size()) {
    throw std::invalid_argument("derivatives: " + std::to_string(t.size()) + " sample times but " +
                                std::to_string(x.size()) + " samples");
  }
  if (t.size() < 3) throw InputError("derivatives need at least 3 samples, got " + std::to_string(t.size()));
  for (Eigen::Index k = 1; k < t.size(); ++k) {
    if (!(t[k] > t[k - 1])) {
      std::ostringstream s;
      s << "derivatives: sample times must increase, t[" << k << "] = " << t[k] << " after " << t[k - 1];
      throw InputError(s.str());
    }
  }
}

}  // namespace

ButterworthFilter DesignButterworthLowPass(int order, double cutoff_hz, double sample_rate_hz) {
  if (order < 1 || order > 16) throw InputError("Butterworth filter order must be 1 to 16, got " + std::to_string(order));
  if (!(sample_rate_hz > 0) || !std::isfinite(sample_rate_hz)) {
    std::ostringstream s;
    s << "sample rate must be positive, got " << sample_rate_hz << " Hz";
    throw InputError(s.str());
  }
  const double nyquist = 0.5 * sample_rate_hz;
  if (!(cutoff_hz > 0) || !(cutoff_hz < nyquist)) {
    std::ostringstream s;
    s << "filter cut-off must lie between 0 and the Nyquist frequency " << nyquist << " Hz (half the sample rate "
      << sample_rate_hz << " Hz), got " << cutoff_hz << " Hz";
    throw InputError(s.str());
  }
  ButterworthFilter f;
  f.order = order;
  f.cutoff_hz = cutoff_hz;
  f.sample_rate_hz = sample_rate_hz;
  // Bilinear transform s = k (1 - 1/z) / (1 + 1/z), k = 2 fs, with the analog cut-off
  // prewarped so that the digital -3 dB point lands exactly on cutoff_hz.
  const double k = 2 * sample_rate_hz;
  const double wc = k * std::tan(kPi * cutoff_hz / sample_rate_hz);  // rad/s
  // Conjugate pole pairs of the prototype: s^2 + 2 sin(theta) wc s + wc^2.
  for (int p = 1; p <= order / 2; ++p) {
    const double zeta2 = 2 * std::sin(kPi * (2 * p - 1) / (2.0 * order));
    const double a1 = zeta2 * wc, a0 = wc * wc;
    const double d0 = k * k + a1 * k + a0;
    Biquad s;
    s.b0 = a0 / d0;
    s.b1 = 2 * a0 / d0;
    s.b2 = a0 / d0;
    s.a1 = (2 * a0 - 2 * k * k) / d0;
    s.a2 = (k * k - a1 * k + a0) / d0;
    f.sections.push_back(s);
  }
  // The real pole of an odd order: wc / (s + wc).
  if (order % 2 == 1) {
    const double d0 = k + wc;
    Biquad s;
    s.b0 = wc / d0;
    s.b1 = wc / d0;
    s.a1 = (wc - k) / d0;
    f.sections.push_back(s);
  }
  return f;
}

std::complex<double> FrequencyResponse(const ButterworthFilter& filter, double frequency_hz) {
  const std::complex<double> zi = std::polar(1.0, -2 * kPi * frequency_hz / filter.sample_rate_hz);  // z^-1
  std::complex<double> h = 1.0;
  for (const Biquad& s : filter.sections) {
    h *= (s.b0 + zi * (s.b1 + zi * s.b2)) / (1.0 + zi * (s.a1 + zi * s.a2));
  }
  return h;
}

Eigen::VectorXd FilterCausal(const ButterworthFilter& filter, const Eigen::VectorXd& x) {
  Eigen::VectorXd y = x;
  RunCascade(filter, false, &y);
  return y;
}

int PaddingLength(const ButterworthFilter& filter, int samples) {
  const int periods = static_cast<int>(std::ceil(3 * filter.sample_rate_hz / filter.cutoff_hz));
  const int wanted = std::max(periods, 3 * static_cast<int>(filter.sections.size()) * 2 + 3);
  return std::max(0, std::min(wanted, samples - 1));
}

Eigen::VectorXd FiltFilt(const ButterworthFilter& filter, const Eigen::VectorXd& x) {
  const int n = static_cast<int>(x.size());
  if (n < 2) return x;
  const int pad = PaddingLength(filter, n);
  // Odd reflection about each end: keeps the value and the slope continuous there.
  Eigen::VectorXd ext(n + 2 * pad);
  for (int k = 0; k < pad; ++k) {
    ext[k] = 2 * x[0] - x[pad - k];
    ext[pad + n + k] = 2 * x[n - 1] - x[n - 2 - k];
  }
  ext.segment(pad, n) = x;
  RunCascade(filter, true, &ext);
  ext.reverseInPlace();
  RunCascade(filter, true, &ext);
  ext.reverseInPlace();
  return ext.segment(pad, n);
}

Eigen::MatrixXd FiltFiltColumns(const ButterworthFilter& filter, const Eigen::MatrixXd& x) {
  Eigen::MatrixXd y(x.rows(), x.cols());
  for (Eigen::Index c = 0; c < x.cols(); ++c) y.col(c) = FiltFilt(filter, x.col(c));
  return y;
}

SignalDerivatives ThreePointDerivatives(const Eigen::VectorXd& t, const Eigen::VectorXd& x) {
  CheckSamples(t, x);
  const Eigen::Index n = x.size();
  SignalDerivatives d;
  d.value = x;
  d.first.resize(n);
  d.second.resize(n);
  // The parabola through samples (c-1, c, c+1): its slope at sample `at` (one of the
  // three) and its curvature.
  auto fit = [&](Eigen::Index c, Eigen::Index at, double* slope, double* curvature) {
    const double h1 = t[c] - t[c - 1], h2 = t[c + 1] - t[c];
    const double x0 = x[c - 1], x1 = x[c], x2 = x[c + 1];
    if (at == c - 1) {
      *slope = -(2 * h1 + h2) / (h1 * (h1 + h2)) * x0 + (h1 + h2) / (h1 * h2) * x1 - h1 / (h2 * (h1 + h2)) * x2;
    } else if (at == c) {
      *slope = -h2 / (h1 * (h1 + h2)) * x0 + (h2 - h1) / (h1 * h2) * x1 + h1 / (h2 * (h1 + h2)) * x2;
    } else {
      *slope = h2 / (h1 * (h1 + h2)) * x0 - (h1 + h2) / (h1 * h2) * x1 + (h1 + 2 * h2) / (h2 * (h1 + h2)) * x2;
    }
    *curvature = 2 * (x0 / (h1 * (h1 + h2)) - x1 / (h1 * h2) + x2 / (h2 * (h1 + h2)));
  };
  for (Eigen::Index k = 1; k + 1 < n; ++k) fit(k, k, &d.first[k], &d.second[k]);
  fit(1, 0, &d.first[0], &d.second[0]);
  fit(n - 2, n - 1, &d.first[n - 1], &d.second[n - 1]);
  return d;
}

SignalDerivatives FilteredDerivatives(const ButterworthFilter& filter, const Eigen::VectorXd& t,
                                      const Eigen::VectorXd& x) {
  CheckSamples(t, x);
  return ThreePointDerivatives(t, FiltFilt(filter, x));
}

SignalDerivatives FilteredDerivatives(const ButterworthFilter& filter, double sample_period, const Eigen::VectorXd& x) {
  if (!(sample_period > 0) || !std::isfinite(sample_period)) {
    std::ostringstream s;
    s << "derivatives: the sample period must be positive, got " << sample_period << " s";
    throw InputError(s.str());
  }
  if (x.size() < 3) throw InputError("derivatives need at least 3 samples, got " + std::to_string(x.size()));
  return ThreePointDerivatives(Eigen::VectorXd::LinSpaced(x.size(), 0.0, sample_period * (x.size() - 1)),
                               FiltFilt(filter, x));
}

}  // namespace twinsim

// Random-phase multisines and their spectra; see multisine.h.
#include "signal/multisine.h"

#include <cmath>
#include <complex>
#include <stdexcept>

#include "core/error.h"
#include "core/math_constants.h"
#include "core/rng.h"

namespace twinsim {

Eigen::VectorXd Multisine::Repeat(int periods) const {
  Eigen::VectorXd x(static_cast<Eigen::Index>(periods) * period_samples);
  for (int p = 0; p < periods; ++p) x.segment(static_cast<Eigen::Index>(p) * period_samples, period_samples) = one_period;
  return x;
}

Multisine RandomPhaseMultisine(int period_samples, double sample_time, double f_min, double f_max, double rms,
                               std::uint64_t seed) {
  if (period_samples < 4) throw InputError("multisine: a period needs >= 4 samples");
  if (!(sample_time > 0)) throw InputError("multisine: the sample time must be > 0");
  if (!(rms >= 0)) throw InputError("multisine: the RMS value must be >= 0");
  Multisine m;
  m.period_samples = period_samples;
  m.sample_time = sample_time;
  for (int k = 1; 2 * k < period_samples; ++k) {
    const double f = m.Frequency(k);
    if (f >= f_min - 1e-9 && f <= f_max + 1e-9) m.lines.push_back(k);
  }
  if (m.lines.empty()) {
    throw InputError("multisine: no harmonic of " + std::to_string(m.Frequency(1)) + " Hz lies in [" +
                     std::to_string(f_min) + ", " + std::to_string(f_max) +
                     "] Hz below the Nyquist frequency");
  }
  Rng rng = Rng::Derived(seed, 0x6d73);  // "ms"
  // Each line contributes amplitude^2 / 2 to the mean square.
  const double amplitude = rms * std::sqrt(2.0 / static_cast<double>(m.lines.size()));
  m.one_period = Eigen::VectorXd::Zero(period_samples);
  for (int k : m.lines) {
    const double phase = rng.Uniform(0, 2 * kPi);
    for (int n = 0; n < period_samples; ++n) {
      m.one_period[n] += amplitude * std::cos(2 * kPi * k * n / period_samples + phase);
    }
  }
  return m;
}

Eigen::VectorXcd DftAtLines(const Eigen::VectorXd& x, const std::vector<int>& lines) {
  const Eigen::Index p = x.size();
  Eigen::VectorXcd out(static_cast<Eigen::Index>(lines.size()));
  for (std::size_t i = 0; i < lines.size(); ++i) {
    std::complex<double> sum = 0;
    // The exact angle per sample (k n mod P), so long periods keep full precision.
    for (Eigen::Index n = 0; n < p; ++n) {
      const double angle = -2 * kPi * static_cast<double>((static_cast<long long>(lines[i]) * n) % p) /
                           static_cast<double>(p);
      sum += x[n] * std::polar(1.0, angle);
    }
    out[static_cast<Eigen::Index>(i)] = sum;
  }
  return out;
}

}  // namespace twinsim

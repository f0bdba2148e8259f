#include "signal/spectrum.h"

#include <unsupported/Eigen/FFT>
#include <algorithm>
#include <cmath>
#include <complex>

#include "core/math_constants.h"

namespace twinsim {

void WelchPsd(const std::vector<double>& x, double rate, int segment, std::vector<double>* frequency,
              std::vector<double>* psd) {
  frequency->clear();
  psd->clear();
  segment = std::min<int>(segment, static_cast<int>(x.size()));
  segment -= segment % 2;
  if (segment < 8) return;
  std::vector<double> window(static_cast<std::size_t>(segment));
  double window_power = 0;
  for (int i = 0; i < segment; ++i) {
    window[static_cast<std::size_t>(i)] = 0.5 - 0.5 * std::cos(2 * kPi * i / segment);
    window_power += window[static_cast<std::size_t>(i)] * window[static_cast<std::size_t>(i)];
  }
  Eigen::FFT<double> fft;
  std::vector<double> buffer(static_cast<std::size_t>(segment));
  std::vector<std::complex<double>> spectrum;
  const int bins = segment / 2 + 1;
  psd->assign(static_cast<std::size_t>(bins), 0.0);
  int count = 0;
  for (std::size_t start = 0; start + static_cast<std::size_t>(segment) <= x.size(); start += static_cast<std::size_t>(segment / 2)) {
    double mean = 0;
    for (int i = 0; i < segment; ++i) mean += x[start + static_cast<std::size_t>(i)];
    mean /= segment;
    for (int i = 0; i < segment; ++i) {
      buffer[static_cast<std::size_t>(i)] = (x[start + static_cast<std::size_t>(i)] - mean) * window[static_cast<std::size_t>(i)];
    }
    fft.fwd(spectrum, buffer);
    for (int b = 0; b < bins; ++b) {
      const double scale = (b == 0 || b == segment / 2) ? 1.0 : 2.0;
      (*psd)[static_cast<std::size_t>(b)] += scale * std::norm(spectrum[static_cast<std::size_t>(b)]) / (rate * window_power);
    }
    ++count;
  }
  for (double& p : *psd) p /= std::max(count, 1);
  frequency->resize(static_cast<std::size_t>(bins));
  for (int b = 0; b < bins; ++b) (*frequency)[static_cast<std::size_t>(b)] = b * rate / segment;
}

}  // namespace twinsim

// Welch's power spectral density (signal/spectrum.h): Parseval (the spectrum sums to the
// series' variance), a sine's peak at its frequency, white noise flat at its level.
#include "signal/spectrum.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/math_constants.h"
#include "core/rng.h"

namespace twinsim {
namespace {

double Variance(const std::vector<double>& psd, double rate, int segment) {
  double sum = 0;
  for (double p : psd) sum += p;
  return sum * rate / segment;
}

// A sine of amplitude 2 at 12.5 Hz (a bin's centre) sampled at 100 Hz: the peak in its
// bin, the spectrum's sum its variance 2 (the Hann window's leakage counted by its power).
TEST(Spectrum, ASinesPeakAndItsVariance) {
  const double rate = 100, f0 = 12.5;
  const int segment = 256;
  std::vector<double> x(8192);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = 2 * std::sin(2 * kPi * f0 * static_cast<double>(i) / rate) + 0.3;
  std::vector<double> f, psd;
  WelchPsd(x, rate, segment, &f, &psd);
  ASSERT_EQ(psd.size(), static_cast<std::size_t>(segment / 2 + 1));
  EXPECT_EQ(f[1], rate / segment);
  const auto peak = std::max_element(psd.begin(), psd.end()) - psd.begin();
  EXPECT_EQ(f[static_cast<std::size_t>(peak)], f0);
  EXPECT_NEAR(Variance(psd, rate, segment), 2.0, 0.02);  // the 0.3 offset removed per segment
}

// White noise of standard deviation 0.5 at 200 Hz: one-sided level 2 sigma^2 / rate =
// 0.0025 per Hz on every bin between 0 and Nyquist, within what 4096 samples allow.
TEST(Spectrum, WhiteNoiseIsFlatAtItsLevelAndShortSeriesGiveNothing) {
  Rng rng(3);
  const double rate = 200;
  std::vector<double> x(65536);
  for (double& v : x) v = 0.5 * rng.Gaussian();
  std::vector<double> f, psd;
  WelchPsd(x, rate, 128, &f, &psd);
  double mean = 0;
  for (std::size_t b = 1; b + 1 < psd.size(); ++b) mean += psd[b];
  mean /= static_cast<double>(psd.size() - 2);
  EXPECT_NEAR(mean, 2 * 0.25 / rate, 0.03 * 2 * 0.25 / rate);
  EXPECT_NEAR(Variance(psd, rate, 128), 0.25, 0.01);
  WelchPsd(std::vector<double>(7, 1.0), rate, 64, &f, &psd);
  EXPECT_TRUE(psd.empty());
  EXPECT_TRUE(f.empty());
}

}  // namespace
}  // namespace twinsim

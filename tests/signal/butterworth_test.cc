// Butterworth design and zero-phase filtering against closed forms.
#include "signal/butterworth.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "core/error.h"
#include "core/math_constants.h"

namespace twinsim {
namespace {

Eigen::VectorXd Times(int n, double fs) { return Eigen::VectorXd::LinSpaced(n, 0.0, (n - 1) / fs); }

TEST(Butterworth, MagnitudeIsTheClosedFormWithUnitDcGainAndMinus3DbAtTheCutoff) {
  // The bilinear transform with prewarping maps the analog |H|^2 = 1 / (1 + (w/wc)^2N)
  // to |H(f)|^2 = 1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^2N).
  for (int order : {1, 2, 3, 4, 5, 8}) {
    for (double fc : {0.5, 10.0, 120.0, 400.0}) {
      const double fs = 1000;
      const ButterworthFilter f = DesignButterworthLowPass(order, fc, fs);
      // A cut-off far below the sample rate puts the poles near z = 1, where the
      // coefficients' rounding costs digits: 5e-11 at fc / fs = 0.0005.
      const double tol = fc / fs < 0.01 ? 2e-10 : 1e-12;
      EXPECT_EQ(static_cast<int>(f.sections.size()), (order + 1) / 2);
      EXPECT_NEAR(std::abs(FrequencyResponse(f, 0)), 1.0, tol);
      EXPECT_NEAR(std::abs(FrequencyResponse(f, fc)), 1 / std::sqrt(2.0), tol) << order << " " << fc;
      for (double fr : {0.1, 0.5, 0.9, 1.5, 3.0}) {
        const double freq = fr * fc;
        if (freq >= fs / 2) continue;
        const double ratio = std::tan(kPi * freq / fs) / std::tan(kPi * fc / fs);
        const double expected = 1 / std::sqrt(1 + std::pow(ratio, 2 * order));
        EXPECT_NEAR(std::abs(FrequencyResponse(f, freq)), expected, tol) << order << " " << fc << " " << freq;
      }
      // All poles inside the unit circle: a2 < 1 and |a1| < 1 + a2 for each section.
      for (const Biquad& s : f.sections) {
        EXPECT_LT(std::abs(s.a2), 1.0);
        EXPECT_LT(std::abs(s.a1), 1 + s.a2);
      }
    }
  }
}

TEST(Butterworth, CausalStepResponseSettlesToOne) {
  const ButterworthFilter f = DesignButterworthLowPass(4, 10, 1000);
  const Eigen::VectorXd y = FilterCausal(f, Eigen::VectorXd::Ones(2000));
  EXPECT_NEAR(y[0], f.sections[0].b0 * f.sections[1].b0, 1e-15);  // starts from rest
  EXPECT_NEAR(y[1999], 1.0, 1e-9);
}

TEST(Butterworth, FiltFiltHasZeroPhaseAndSquaredGainOnASinusoid) {
  const double fs = 1000, fc = 10;
  const ButterworthFilter f = DesignButterworthLowPass(4, fc, fs);
  for (double freq : {2.0, 10.0, 15.0}) {
    const Eigen::VectorXd t = Times(6000, fs);
    const Eigen::VectorXd x = (2 * kPi * freq * t).array().sin();
    const Eigen::VectorXd y = FiltFilt(f, x);
    const double gain = std::norm(FrequencyResponse(f, freq));  // |H|^2: forwards and backwards
    double worst = 0;
    for (int k = 1000; k < 5000; ++k) worst = std::max(worst, std::abs(y[k] - gain * x[k]));
    // In phase (a lag of even 1 sample would leave 2 pi f / fs = 0.0126 at 2 Hz).
    EXPECT_LT(worst, 1e-9) << freq << " Hz";
    if (freq == fc) {
      EXPECT_NEAR(gain, 0.5, 1e-12);  // -6 dB at the cut-off after two passes
    }
  }
}

TEST(Butterworth, FiltFiltKeepsConstantsAndRampsUpToTheEnds) {
  const ButterworthFilter f = DesignButterworthLowPass(4, 5, 200);
  const Eigen::VectorXd c = Eigen::VectorXd::Constant(300, 1.75);
  EXPECT_LT((FiltFilt(f, c) - c).cwiseAbs().maxCoeff(), 1e-12);
  // Odd reflection continues a ramp as the same ramp and each pass starts in the ramp's
  // steady state, so nothing rings at the ends.
  const Eigen::VectorXd t = Times(300, 200);
  const Eigen::VectorXd ramp = 0.3 + 2.0 * t.array();
  EXPECT_LT((FiltFilt(f, ramp) - ramp).cwiseAbs().maxCoeff(), 1e-9);
  // A sinusoid's ends move by far less than a zero-padded filter would (which starts at 0).
  const Eigen::VectorXd s = (2 * kPi * 0.5 * t).array().cos();  // 1 at t = 0
  const Eigen::VectorXd y = FiltFilt(f, s);
  EXPECT_NEAR(y[0], s[0], 2e-3);
  EXPECT_NEAR(y[299], s[299], 2e-3);
}

TEST(Butterworth, FilteredDerivativesOfASinusoid) {
  // x = A sin(w t) at 1 kHz, 1.5 Hz, cut-off 20 Hz: x' = A w cos(w t), x'' = -A w^2 sin(w t).
  // Errors: the filter's gain at 1.5 Hz (1 - 1e-9) and the three-point differences'
  // (w h)^2 / 6 = 1.5e-5 relative (first) and (w h)^2 / 12 (second).
  const double fs = 1000, freq = 1.5, a = 0.8, w = 2 * kPi * freq;
  const ButterworthFilter f = DesignButterworthLowPass(4, 20, fs);
  const Eigen::VectorXd t = Times(4000, fs);
  const Eigen::VectorXd x = a * (w * t).array().sin();
  const SignalDerivatives d = FilteredDerivatives(f, t, x);
  double first = 0, second = 0, first_ends = 0, second_ends = 0;
  for (int k = 0; k < 4000; ++k) {
    const double e1 = std::abs(d.first[k] - a * w * std::cos(w * t[k])) / (a * w);
    const double e2 = std::abs(d.second[k] + a * w * w * std::sin(w * t[k])) / (a * w * w);
    const bool inside = k >= 200 && k < 3800;
    (inside ? first : first_ends) = std::max(inside ? first : first_ends, e1);
    (inside ? second : second_ends) = std::max(inside ? second : second_ends, e2);
  }
  EXPECT_LT(first, 2e-5);
  EXPECT_LT(second, 2e-5);
  // The first and last 0.2 s (4 cut-off periods): odd reflection keeps the slope, not the
  // curvature, so the second derivative is worse there.
  EXPECT_LT(first_ends, 1e-2);
  EXPECT_LT(second_ends, 0.3);
}

TEST(Butterworth, UniformGridDerivativesIgnoreStampJitter) {
  // Samples of sin(w t) taken every 5 ms; the uniform-grid version on the sampling
  // period matches the time-stamp version on exact stamps, and is what stays right when
  // the stamps jitter (the KUKA logs' do, by up to 1.5 ms).
  const double fs = 200, w = 2 * kPi * 0.4;
  const ButterworthFilter f = DesignButterworthLowPass(4, 5, fs);
  const Eigen::VectorXd t = Times(2000, fs);
  const Eigen::VectorXd x = (w * t).array().sin();
  const SignalDerivatives uniform = FilteredDerivatives(f, 1 / fs, x);
  const SignalDerivatives stamped = FilteredDerivatives(f, t, x);
  EXPECT_LT((uniform.second - stamped.second).cwiseAbs().maxCoeff(), 1e-9);
  Eigen::VectorXd jittered = t;
  for (int k = 1; k < 1999; k += 7) jittered[k] += 0.0005;
  const SignalDerivatives wrong = FilteredDerivatives(f, jittered, x);
  double error_uniform = 0, error_stamped = 0;
  for (int k = 200; k < 1800; ++k) {
    error_uniform = std::max(error_uniform, std::abs(uniform.second[k] + w * w * std::sin(w * t[k])));
    error_stamped = std::max(error_stamped, std::abs(wrong.second[k] + w * w * std::sin(w * t[k])));
  }
  EXPECT_LT(error_uniform, 1e-3 * w * w);
  EXPECT_GT(error_stamped, 0.5 * w * w);
  EXPECT_THROW(FilteredDerivatives(f, 0.0, x), InputError);
}

TEST(Butterworth, ThreePointDerivativesAreExactForParabolasOnUnevenTimes) {
  Eigen::VectorXd t(6);
  t << 0, 0.004, 0.011, 0.015, 0.021, 0.024;
  const Eigen::VectorXd x = (1.0 + 2.0 * t.array() - 3.0 * t.array().square()).matrix();
  const SignalDerivatives d = ThreePointDerivatives(t, x);
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(d.first[k], 2.0 - 6.0 * t[k], 1e-10);
    EXPECT_NEAR(d.second[k], -6.0, 1e-7);
  }
}

TEST(Butterworth, BadDesignsAndSamplesAreInputErrors) {
  try {
    DesignButterworthLowPass(4, 100, 200);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("between 0 and the Nyquist frequency 100 Hz"), std::string::npos) << e.what();
  }
  EXPECT_THROW(DesignButterworthLowPass(0, 10, 200), InputError);
  EXPECT_THROW(DesignButterworthLowPass(4, -1, 200), InputError);
  EXPECT_THROW(ThreePointDerivatives(Eigen::VectorXd::Zero(2), Eigen::VectorXd::Zero(2)), InputError);
  Eigen::VectorXd t(3);
  t << 0, 1, 1;
  EXPECT_THROW(ThreePointDerivatives(t, Eigen::VectorXd::Zero(3)), InputError);
  // Times and samples of different lengths are the caller's bug, not the data's.
  EXPECT_THROW(ThreePointDerivatives(Eigen::VectorXd::LinSpaced(4, 0, 3), Eigen::VectorXd::Zero(3)),
               std::invalid_argument);
}

}  // namespace
}  // namespace twinsim

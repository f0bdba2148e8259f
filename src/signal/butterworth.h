// Butterworth low-pass filters, zero-phase filtering and filtered differentiation
// (seed 001, section IV: positions are measured, velocities and accelerations are not).
//
// DesignButterworthLowPass() gives the digital filter as second-order sections: the
// analog prototype's poles (evenly spaced on the left half of a circle of radius
// 2 pi f_c), mapped by the bilinear transform with the cut-off prewarped, so that the
// digital filter is exactly -3 dB at f_c. FiltFilt() runs it forwards and backwards:
// zero phase, magnitude |H|^2 (so -6 dB at f_c), the ends padded by odd reflection and
// the filter started in the steady state of the signal's trend, so the ends do not ring.
// FilteredDerivatives() filters, then differentiates by central differences on the
// sample times, which is how measured joint positions become velocities and
// accelerations for identification, and what the ILC robustness filter reuses.
//
//   ButterworthFilter f = DesignButterworthLowPass(4, 10.0, 1000.0);
//   Eigen::VectorXd smooth = FiltFilt(f, q);
//   SignalDerivatives d = FilteredDerivatives(f, t, q);   // d.value, d.first, d.second
#pragma once

#include <Eigen/Core>
#include <complex>
#include <vector>

namespace twinsim {

// One second-order section, a0 = 1:
//   y[k] = b0 x[k] + b1 x[k-1] + b2 x[k-2] - a1 y[k-1] - a2 y[k-2].
// A first-order section has b2 = a2 = 0.
struct Biquad {
  double b0 = 1, b1 = 0, b2 = 0;
  double a1 = 0, a2 = 0;
};

struct ButterworthFilter {
  int order = 0;               // number of poles
  double cutoff_hz = 0;        // Hz, the -3 dB frequency of one pass
  double sample_rate_hz = 0;   // Hz
  std::vector<Biquad> sections;  // cascaded; each has unit gain at DC
};

// Designs an order-`order` low-pass at `cutoff_hz` for samples at `sample_rate_hz`.
// Throws InputError for order outside 1..16 or a cut-off not strictly between 0 and the
// Nyquist frequency (sample_rate_hz / 2).
ButterworthFilter DesignButterworthLowPass(int order, double cutoff_hz, double sample_rate_hz);

// The filter's frequency response H(e^{j 2 pi f / fs}) at `frequency_hz` (one pass).
std::complex<double> FrequencyResponse(const ButterworthFilter& filter, double frequency_hz);

// One causal pass with zero initial state (as a real-time filter would run).
Eigen::VectorXd FilterCausal(const ButterworthFilter& filter, const Eigen::VectorXd& x);

// Zero-phase filtering: forward then backward, with odd-reflection padding of
// PaddingLength() samples at each end, each pass started in the steady state of the
// straight line through its first samples (so constants and ramps pass exactly).
// Signals of fewer than 2 samples are returned unchanged.
Eigen::VectorXd FiltFilt(const ButterworthFilter& filter, const Eigen::VectorXd& x);
// FiltFilt() of every column of `x` (samples x channels).
Eigen::MatrixXd FiltFiltColumns(const ButterworthFilter& filter, const Eigen::MatrixXd& x);

// Samples of odd-reflection padding FiltFilt() uses for a signal of `samples` samples:
// three periods of the cut-off (at least 3 per section), at most samples - 1.
int PaddingLength(const ButterworthFilter& filter, int samples);

// A filtered signal and its first and second time derivatives (per second, per second^2).
struct SignalDerivatives {
  Eigen::VectorXd value;
  Eigen::VectorXd first;
  Eigen::VectorXd second;
};

// Filters `x` (sampled at times `t`, s, strictly increasing) with FiltFilt(), then
// differentiates the filtered samples by three-point central differences on the actual
// sample times (one-sided three-point formulas at the two ends). Throws InputError when
// fewer than 3 samples are given or t does not increase, std::invalid_argument when t
// and x differ in length.
SignalDerivatives FilteredDerivatives(const ButterworthFilter& filter, const Eigen::VectorXd& t,
                                      const Eigen::VectorXd& x);

// The same for samples taken every `sample_period` seconds (a uniform grid): central
// differences (x[k+1] - x[k-1]) / 2h and (x[k+1] - 2 x[k] + x[k-1]) / h^2. Logs whose time
// stamps jitter around a fixed rate are differentiated this way: on the stamps
// themselves, a 0.5 ms jitter at 200 Hz would put 7 rad/s^2 of noise into a second
// derivative at 0.35 rad/s. Throws InputError for fewer than 3 samples or a step <= 0.
SignalDerivatives FilteredDerivatives(const ButterworthFilter& filter, double sample_period, const Eigen::VectorXd& x);

// Three-point derivatives of samples `x` at times `t` without filtering (the second
// step of FilteredDerivatives()); same requirements and errors.
SignalDerivatives ThreePointDerivatives(const Eigen::VectorXd& t, const Eigen::VectorXd& x);

}  // namespace twinsim

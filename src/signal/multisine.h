// Periodic random-phase multisines, the excitation for measuring frequency responses:
// one period of P samples holds equal-amplitude sines at every harmonic k / (P Ts) of
// the period inside a band, each with a seeded uniformly random phase. Repeated over
// whole periods, the signal and (after the transient) the response are periodic, so the
// DFT over whole periods has no leakage, and averaging the spectra of several periods
// removes what does not repeat.
//
//   Multisine m = RandomPhaseMultisine(500, 0.001, 2, 200, 1.0, 7);  // 2..200 Hz, 1 N·m RMS
//   Eigen::VectorXd x = m.Repeat(5);                                   // 5 periods
//   Eigen::VectorXcd X = DftAtLines(x.segment(500, 500), m.lines);     // one period's spectrum
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace twinsim {

struct Multisine {
  int period_samples = 0;       // P
  double sample_time = 0;       // s
  std::vector<int> lines;       // the excited harmonics k (frequency k / (P Ts))
  Eigen::VectorXd one_period;   // P samples

  // The frequency of harmonic k, Hz.
  double Frequency(int k) const { return k / (period_samples * sample_time); }
  // `periods` copies of one period, one after the other.
  Eigen::VectorXd Repeat(int periods) const;
};

// A multisine of `period_samples` samples every `sample_time` s with every harmonic in
// [f_min, f_max] (Hz) excited at equal amplitude and random phase (from `seed`), scaled
// to the RMS value `rms`. Throws InputError when period_samples < 4,
// sample_time <= 0, rms < 0, or the band holds no harmonic below the Nyquist frequency.
Multisine RandomPhaseMultisine(int period_samples, double sample_time, double f_min, double f_max, double rms,
                               std::uint64_t seed);

// X(k) = sum_n x[n] exp(-j 2 pi k n / P) of one period x (P samples) at harmonics `lines`.
Eigen::VectorXcd DftAtLines(const Eigen::VectorXd& x, const std::vector<int>& lines);

}  // namespace twinsim

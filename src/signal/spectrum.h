// Spectra of sampled series (the diagnosis's residual spectra; docs/diagnose.md).
#pragma once

#include <vector>

namespace twinsim {

// Welch's power spectral density of x sampled at `rate` Hz: Hann windows of `segment`
// samples (at most x's length, made even; nothing below 8), half overlapping, each
// segment's mean removed, one-sided (the bins between 0 and Nyquist doubled), averaged;
// fills frequency (Hz, b rate / segment) and psd (unit^2/Hz), so that the sum of psd
// times rate / segment is the series' variance.
void WelchPsd(const std::vector<double>& x, double rate, int segment, std::vector<double>* frequency,
              std::vector<double>* psd);

}  // namespace twinsim

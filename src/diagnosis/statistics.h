// The diagnosis's statistics (docs/diagnose.md, "Statistics"): tests on series whose
// rows are correlated (residuals of a filtered log, overlapping predictions), so every
// standard error is a long-run one, and every test that is one of many is corrected.
//
//   LongRunTest t = LongRunMeanTest(gain, 30);       // H0: mean(gain) <= 0
//   std::vector<bool> keep = HolmReject(p_values, 0.05);
//   Whiteness w = LjungBox(residual, 20, 4);          // every 4th row, lags 1..20
#pragma once

#include <limits>
#include <string>
#include <vector>

namespace twinsim {

// P(T >= t) for Student's t with `df` degrees of freedom (df > 0; real-valued).
double StudentTUpperTail(double t, double df);
// P(X >= x) for a chi-square variable with k degrees of freedom (k > 0).
double ChiSquareUpperTail(double x, double k);

// The two-sided normal quantile z with P(|Z| > z) = p (0 < p < 1).
double TwoSidedNormalQuantile(double p);

// The one-sided p-value that the worst of `channels` series is really below zero, given
// its t (negative) and degrees of freedom: the worst of several is picked after looking,
// so its tail probability is Bonferroni-corrected, min(1, channels P(T <= t)).
double WorstChannelP(double t, double df, int channels);

// The one-sided test that a series' mean is above zero, with the Newey-West (Bartlett
// kernel) long-run variance: rows closer than the bandwidth are not independent evidence.
struct LongRunTest {
  double mean = 0;
  double standard_error = 0;  // of the mean
  double t = 0;
  double df = 0;              // rows / bandwidth - 1, at least 1
  double p = 1;               // one-sided, P(T >= t) under a zero mean
  int bandwidth = 1;          // rows
  double effective_rows = 0;  // rows * (plain variance / long-run variance), at most rows
};
// `min_bandwidth` rows at least; longer where the series stays correlated longer
// (six times its correlation length, CorrelationLength in diagnosis.h; at three, 10.3 % of
// 400 AR(1) series with phi = 0.9 were rejected at the 5 % level, measured).
LongRunTest LongRunMeanTest(const std::vector<double>& x, int min_bandwidth);

// The test of `x`'s mean made to count its blocks (`block`, one number per row; rows of
// a block consecutive): rows from B blocks that lie apart are B pieces of evidence at
// most, however many rows and however short their correlation looks within a block. The
// standard error becomes the larger of the long-run one and the blocks' (the cluster-
// robust one, sqrt(B / (B - 1) sum_b (sum_{i in b} (x_i - mean))^2) / n), the degrees of
// freedom at most B - 1, and t and p follow. Nothing changes with fewer than 2 blocks.
void AccountForBlocks(const std::vector<double>& x, const std::vector<int>& block, LongRunTest* test);

// One coefficient of a least-squares fit y ~ x tested against zero with the rows'
// blocks as the evidence (rows of a block need not be consecutive): its standard error
// is the delete-one-block jackknife's, sqrt((B - 1) / B sum_b (c_(-b) - mean c_(-b))^2),
// so rows correlated within a block count as one piece of evidence, as in
// AccountForBlocks. Two-sided p with B - 1 degrees of freedom. A column zero on every
// row of a fit (the whole's or one without a block) is left out of that fit. p NaN (and
// blocks 0) where fewer than 3 blocks hold rows, the rows differ in length, or a fit
// leaves the coefficient undetermined.
struct BlockCoefficientTest {
  double value = 0;           // the coefficient, from every row
  double standard_error = 0;  // the jackknife's
  double t = 0;
  double p = std::numeric_limits<double>::quiet_NaN();
  int blocks = 0;
};
// x: one row of regressors per y (all of one length), column: the coefficient tested.
BlockCoefficientTest TestBlockCoefficient(const std::vector<std::vector<double>>& x, const std::vector<double>& y,
                                          const std::vector<int>& block, int column);

// Holm's step-down procedure: which of the hypotheses with these p-values are rejected
// at family-wise level alpha. NaN p-values are never rejected and do not count.
std::vector<bool> HolmReject(const std::vector<double>& p, double alpha);

// Ljung-Box portmanteau test of whiteness on every `step`-th row of x (step spaces the
// rows beyond a known correlation: a filter's span, a prediction's overlap).
struct Whiteness {
  std::vector<double> autocorrelation;  // lags 1..max_lag (of the subsampled series)
  double bound = 0;                     // 95 % band for a white series: 1.96 / sqrt(n)
  double q = 0;                         // Ljung-Box statistic
  double p = 1;                         // P(chi2(max_lag) >= q): small means not white
  int rows = 0;                         // after subsampling
  int step = 1;
};
Whiteness LjungBox(const std::vector<double>& x, int max_lag, int step);

// The largest cross-correlation of a residual with an input within +-max_lag rows (the
// input leading for positive lags), over rows a `step` apart, and the 95 % band for that
// largest of the 2 max_lag + 1 lags (times `family`: the inputs tested together) on a
// residual that does not depend on the input: z / sqrt(effective rows), z the two-sided
// quantile at the Sidak level 1 - 0.95^(1 / tests). (A pointwise band, 1.96, is crossed
// somewhere by 66 % of white residuals over 21 lags, measured.)
struct CrossCorrelation {
  std::string input;
  double peak = 0;   // the correlation of largest magnitude
  int lag = 0;       // rows at which it occurs
  double bound = 0;  // z / sqrt(effective rows)
};
CrossCorrelation PeakCrossCorrelation(const std::vector<double>& residual, const std::vector<double>& input, int max_lag,
                                      int step, const std::string& name, int family = 1);

}  // namespace twinsim

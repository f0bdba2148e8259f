// The ILC report from a hand-made run: the CSV tables, the Bode plot's unwrapped phase,
// and the files in the order `twinsim ilc` writes them.
#include "control/ilc_report.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>

#include "core/math_constants.h"
#include "io/csv_table.h"
#include "test_util.h"

namespace twinsim {
namespace {

// One joint measured at one posture on 40 lines, 1..40 Hz: a pure delay of 30 ms, whose
// phase falls by 10.8 degrees per line, through several turns.
ClosedLoopFrf DelayFrf() {
  ClosedLoopFrf frf;
  frf.sample_time = 0.001;
  frf.frequency = Eigen::VectorXd::LinSpaced(40, 1, 40);
  frf.postures = {Eigen::VectorXd::Zero(1)};
  Eigen::VectorXcd ps(40);
  for (int i = 0; i < 40; ++i) ps[i] = 0.01 * std::polar(1.0, -2 * kPi * frf.frequency[i] * 0.03);
  frf.response = {{ps}};
  return frf;
}

// Trial 0 and one learning trial of three samples.
IlcResult TwoTrials() {
  IlcResult r;
  r.error_rms = {Eigen::VectorXd::Constant(1, 0.01), Eigen::VectorXd::Constant(1, 0.001)};
  r.error_max = {Eigen::VectorXd::Constant(1, 0.02), Eigen::VectorXd::Constant(1, 0.002)};
  for (TrackingTrial* t : {&r.first, &r.last}) {
    t->t = Eigen::VectorXd::LinSpaced(3, 0, 0.002);
    t->q = Eigen::MatrixXd::Zero(3, 1);
    t->q_ref = Eigen::MatrixXd::Constant(3, 1, t == &r.first ? 0.01 : 0.001);
  }
  r.feedforward = Eigen::MatrixXd::Constant(3, 1, 0.5);
  return r;
}

LearningFilter Filter() {
  LearningFilter l;
  l.shift = 1;
  l.inertia = l.inertia_early = 0.05;
  l.damping = 2;
  l.stiffness = 100;
  return l;
}

TEST(IlcReport, TrialsCsvHasTheContractColumns) {
  const std::string n1 = FormatCsvNumber(0.01), n2 = FormatCsvNumber(0.02);
  EXPECT_EQ(FormatIlcTrialsCsv(TwoTrials()), "trial,rms1,max1\n0," + n1 + "," + n2 + "\n1," +
                                                 FormatCsvNumber(0.001) + "," + FormatCsvNumber(0.002) + "\n");
  const std::string frf = FormatIlcFrfCsv(DelayFrf(), {Filter()});
  EXPECT_EQ(frf.substr(0, frf.find('\n')),
            "joint,posture,frequency,magnitude,phase,coherence,filter_magnitude,filter_phase");
  EXPECT_EQ(std::count(frf.begin(), frf.end(), '\n'), 81);  // the nominal (posture 0) and the posture, 40 lines each
}

TEST(IlcReport, BodePhaseIsUnwrappedAndMagnitudeInDecibels) {
  const IlcBodePlot bode = IlcBodePlots(DelayFrf(), Filter(), 0, "delay");
  ASSERT_EQ(bode.phase.series.size(), 3u);  // the posture (grey), the nominal and 1/L
  EXPECT_TRUE(bode.phase.series[0].color.has_value());
  EXPECT_EQ(bode.phase.series[1].name, "nominal (their average)");
  EXPECT_EQ(bode.phase.series[2].name, "1 / L (learning filter)");
  const PlotSeries& phase = bode.phase.series[0];
  for (std::size_t i = 0; i < phase.y.size(); ++i) EXPECT_NEAR(phase.y[i], -10.8 * (i + 1), 1e-9) << i;
  EXPECT_NEAR(bode.magnitude.series[0].y[5], -40, 1e-9);  // |PS| = 0.01 rad/(N m)
  EXPECT_NEAR(bode.magnitude.series[0].x[9], 1, 1e-12);   // log10(10 Hz)
  EXPECT_THROW(IlcBodePlots(DelayFrf(), Filter(), 1, ""), std::out_of_range);
}

TEST(IlcReport, FilesInTheOrderWrittenWithoutPlotsWhenNotDrawn) {
  IlcReportSetup setup;
  setup.name = "a<b";
  setup.backend = "analytic";
  setup.hat = "rrr";
  setup.learning_filter = "fitted";
  const ArmModel plant = LoadArmModel(testing::SourcePath("models/rrr.yaml"));
  const IlcResult result = TwoTrials();
  const auto files =
      MakeIlcReport(setup, plant, result.first.t, DelayFrf(), {Filter()}, result, /*renderer=*/nullptr);
  std::vector<std::string> names;
  for (const auto& [name, bytes] : files) names.push_back(name);
  EXPECT_EQ(names, (std::vector<std::string>{"trials.csv", "frf.csv", "filters.csv", "feedforward.csv",
                                              "best_feedforward.csv", "safeguard.csv", "errors.csv", "report.html"}));
  EXPECT_EQ(files[6].second.substr(0, files[6].second.find('\n')), "t,first_e1,last_e1");
  EXPECT_EQ(files[5].second, "trial,joint,action,rms,best_rms,best_trial,q_cutoff\n");  // it never acted
  EXPECT_EQ(files[3].second, "t,f1\n" + FormatCsvNumber(0) + "," + FormatCsvNumber(0.5) + "\n" +
                                 FormatCsvNumber(0.001) + "," + FormatCsvNumber(0.5) + "\n" + FormatCsvNumber(0.002) +
                                 "," + FormatCsvNumber(0.5) + "\n");
  const std::string& html = files.back().second;
  EXPECT_NE(html.find("<h1>Iterative learning control: a&lt;b</h1>"), std::string::npos) << html;
  EXPECT_NE(html.find("<b>" + FormatCsvNumber(10) + " times smaller</b>"), std::string::npos) << html;
  EXPECT_EQ(html.find("<img"), std::string::npos);
  EXPECT_NE(html.find("<h2>4. Safeguard</h2>"), std::string::npos) << html;
}

}  // namespace
}  // namespace twinsim

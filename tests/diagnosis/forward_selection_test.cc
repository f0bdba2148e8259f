// Forward selection's rules on problems small enough to know the answer: a linear
// regression whose candidate effects each scale one feature of the rows.
#include "diagnosis/forward_selection.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>

#include "core/rng.h"

namespace twinsim {
namespace {

enum class Kind { kFit, kSelection, kTest };

// Rows y; an effect k is a feature f_k with a coefficient (its one parameter, "theta"):
// the residual is y - sum theta_k f_k. Rows are fit, selection and test in blocks of 50
// (three of fit, one of each other).
class LinearProblem : public DiagnosisProblem {
 public:
  struct Feature {
    std::string name;
    int joint = 0;
    std::vector<double> values;
  };

  LinearProblem(std::vector<double> y, std::vector<Feature> features) : y_(std::move(y)), features_(std::move(features)) {
    for (std::size_t i = 0; i < y_.size(); ++i) {
      const std::size_t block = (i / 50) % 5;
      kind_.push_back(block < 3 ? Kind::kFit : (block == 3 ? Kind::kSelection : Kind::kTest));
    }
  }

  double Gap(double mean_squared) const override { return std::sqrt(mean_squared); }
  int ChunkRows() const override { return 5; }
  double FloorRatio() const override { return 4; }

  std::vector<double> Residual(const std::vector<TrialEffect>& effects) const {
    std::vector<double> r = y_;
    for (const TrialEffect& e : effects) {
      const std::vector<double>& f = Find(e.name).values;
      const double theta = e.parameters.count("theta") ? e.parameters.at("theta") : 0.0;
      for (std::size_t i = 0; i < r.size(); ++i) r[i] -= theta * f[i];
    }
    return r;
  }

  SquaredResiduals Evaluate(const std::vector<TrialEffect>& effects) const override {
    const std::vector<double> r = Residual(effects);
    SquaredResiduals out;
    out.selection_by_channel.resize(1);
    for (std::size_t i = 0; i < r.size(); ++i) {
      const double s = r[i] * r[i];
      switch (kind_[i]) {
        case Kind::kFit: out.fit.push_back(s); break;
        case Kind::kSelection:
          out.selection.push_back(s);
          out.selection_by_channel[0].push_back(s);
          out.selection_block.push_back(static_cast<int>(i / 50));
          break;
        case Kind::kTest: out.test.push_back(s); break;
      }
    }
    return out;
  }

  std::vector<TrialEffect> Candidates(const std::vector<TrialEffect>& current) const override {
    std::vector<TrialEffect> out;
    for (const Feature& f : features_) {
      bool taken = false;
      for (const TrialEffect& e : current) taken = taken || e.name == f.name;
      if (!taken) out.push_back({f.name, f.joint, {}});
    }
    return out;
  }

  // Least squares of the free coefficients on the fit rows, the others held.
  std::vector<TrialEffect> Fit(std::vector<TrialEffect> effects, const std::vector<int>& free) const override {
    std::vector<TrialEffect> held;
    for (std::size_t k = 0; k < effects.size(); ++k) {
      if (std::find(free.begin(), free.end(), static_cast<int>(k)) == free.end()) held.push_back(effects[k]);
    }
    const std::vector<double> r = Residual(held);
    std::vector<std::size_t> rows;
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (kind_[i] == Kind::kFit) rows.push_back(i);
    }
    Eigen::MatrixXd a(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(free.size()));
    Eigen::VectorXd b(a.rows());
    for (std::size_t i = 0; i < rows.size(); ++i) {
      b[static_cast<Eigen::Index>(i)] = r[rows[i]];
      for (std::size_t k = 0; k < free.size(); ++k) {
        a(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) =
            Find(effects[static_cast<std::size_t>(free[k])].name).values[rows[i]];
      }
    }
    const Eigen::VectorXd theta = a.colPivHouseholderQr().solve(b);
    for (std::size_t k = 0; k < free.size(); ++k) {
      effects[static_cast<std::size_t>(free[k])].parameters["theta"] = theta[static_cast<Eigen::Index>(k)];
    }
    return effects;
  }

  std::vector<double> FitResiduals(const std::vector<TrialEffect>& effects) const override {
    const std::vector<double> r = Residual(effects);
    std::vector<double> out;
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (kind_[i] == Kind::kFit) out.push_back(r[i]);
    }
    return out;
  }

  TestResiduals TestRowResiduals(const std::vector<TrialEffect>& effects, bool) const override {
    TestResiduals t;
    t.channels = {"joint 1"};
    t.noise = {1};
    t.residual.resize(1);
    const std::vector<double> r = Residual(effects);
    for (std::size_t i = 0; i < r.size(); ++i) {
      if (kind_[i] == Kind::kTest) t.residual[0].push_back(r[i]);
    }
    return t;
  }

 private:
  const Feature& Find(const std::string& name) const {
    for (const Feature& f : features_) {
      if (f.name == name) return f;
    }
    throw std::logic_error("no feature " + name);
  }

  std::vector<double> y_;
  std::vector<Feature> features_;
  std::vector<Kind> kind_;
};

DiagnosisOptions Options() {
  DiagnosisOptions o;
  o.threads = 1;
  return o;
}

// An effect that fits what the fit and selection rows hold and the opposite of what the
// test rows hold (as a saturation limit clipping the noise's peaks did, issue 41): it
// passes every test on the rows that chose it, and is vetoed by the rows that did not.
// A real effect beside it is added.
TEST(ForwardSelection, AnEffectThatMakesTheTestRowsWorseIsVetoed) {
  Rng rng(3);
  const std::size_t n = 4000;
  std::vector<double> y(n), noise_fit(n), real(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double e = rng.Gaussian();
    real[i] = std::sin(0.05 * static_cast<double>(i));
    y[i] = e + 0.8 * real[i];
    const bool test = (i / 50) % 5 == 4;
    noise_fit[i] = test ? -e : e;
  }
  const LinearProblem problem(y, {{"torque_saturation", 1, noise_fit}, {"viscous_friction", 0, real}});
  const SelectionResult s = SelectEffects(problem, Options());
  ASSERT_EQ(s.effects.size(), 1u);
  EXPECT_EQ(s.effects[0].name, "viscous_friction");
  EXPECT_NEAR(s.effects[0].parameters.at("theta"), 0.8, 0.05);
  bool vetoed = false;
  for (const DiagnosisCandidate& c : s.candidates) {
    if (c.name == "torque_saturation" && !c.veto.empty()) {
      vetoed = true;
      EXPECT_FALSE(c.selected);
      EXPECT_NE(c.veto.find("test rows worse"), std::string::npos) << c.veto;
    }
  }
  EXPECT_TRUE(vetoed);
  // The test rows' gap: what the real effect leaves (the noise).
  EXPECT_NEAR(std::sqrt(Mean(s.after.test)), 1.0, 0.1);
}

// A saturation whose limit must be determined, on fit rows whose residual carries extra
// noise of `fit_noise` (30: the limit's standard error is larger than the limit, though
// the selection and test rows favour the effect).
class UndeterminedLimitProblem : public LinearProblem {
 public:
  UndeterminedLimitProblem(std::vector<double> y, std::vector<Feature> features, double fit_noise)
      : LinearProblem(std::move(y), std::move(features)) {
    Rng rng(11);
    for (int i = 0; i < 4000; ++i) noise_.push_back(fit_noise * rng.Gaussian());
  }
  std::vector<double> FitResiduals(const std::vector<TrialEffect>& effects) const override {
    std::vector<double> r = LinearProblem::FitResiduals(effects);
    for (std::size_t i = 0; i < r.size(); ++i) r[i] += noise_[i];
    return r;
  }
  std::vector<std::string> MustBeDetermined(const TrialEffect& e) const override {
    if (e.name == "torque_saturation") return {"theta"};
    return {};
  }

 private:
  std::vector<double> noise_;
};

// The saturation's limit is not determined by the logs: vetoed, never added, however much
// the rows that score it gain; the effect beside it, which need not be, is added (issue
// 41: a torque limit of 0.19 ± 0.29 N·m under most of a real KUKA joint's commands).
TEST(ForwardSelection, AnEffectWhoseLimitTheLogsDoNotDetermineIsVetoed) {
  Rng rng(7);
  const std::size_t n = 4000;
  std::vector<double> y(n), limit(n), real(n);
  for (std::size_t i = 0; i < n; ++i) {
    limit[i] = std::sin(0.013 * static_cast<double>(i));
    real[i] = std::cos(0.05 * static_cast<double>(i));
    y[i] = 0.2 * rng.Gaussian() + 0.5 * limit[i] + 0.8 * real[i];
  }
  const UndeterminedLimitProblem problem(y, {{"torque_saturation", 1, limit}, {"viscous_friction", 0, real}}, 30);
  const SelectionResult s = SelectEffects(problem, Options());
  ASSERT_EQ(s.effects.size(), 1u);
  EXPECT_EQ(s.effects[0].name, "viscous_friction");
  bool vetoed = false;
  for (const DiagnosisCandidate& c : s.candidates) {
    if (c.name != "torque_saturation" || c.veto.empty()) continue;
    vetoed = true;
    EXPECT_FALSE(c.selected);
    EXPECT_NE(c.veto.find("do not determine its theta"), std::string::npos) << c.veto;
  }
  EXPECT_TRUE(vetoed);
  // The same logs without the fit rows' extra noise: the limit is determined and added.
  const UndeterminedLimitProblem quiet(y, {{"torque_saturation", 1, limit}, {"viscous_friction", 0, real}}, 0);
  EXPECT_EQ(SelectEffects(quiet, Options()).effects.size(), 2u);
}

// Two look-alike effects on one joint (Coulomb and viscous friction: sign(v) and v
// correlate 0.85 here). The first added (viscous) takes part of the second's share;
// the second, fitted with the first held, makes the selection rows worse (-25 %: the
// motion there is twice as fast as on the fit rows, as where a periodic excitation
// lines up with the blocks), and only a joint refit gives it its due (99 %). Both must
// be found with their coefficients.
TEST(ForwardSelection, ACandidateOnAJointWithAnAddedEffectIsRefittedWithIt) {
  Rng rng(5);
  const std::size_t n = 6000;
  std::vector<double> y(n), v(n), sign(n);
  double corr_vs = 0, vv = 0, ss = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double amplitude = (i / 50) % 5 < 3 ? 0.3 : 0.6;  // fit rows : held-out rows
    v[i] = amplitude * std::sin(0.013 * static_cast<double>(i)) + 0.05 * std::sin(0.21 * static_cast<double>(i));
    sign[i] = v[i] > 0 ? 1.0 : -1.0;
    y[i] = 200 * v[i] + 20 * sign[i] + rng.Gaussian(2.0);
    corr_vs += v[i] * sign[i], vv += v[i] * v[i], ss += 1;
  }
  ASSERT_GT(corr_vs / std::sqrt(vv * ss), 0.8);
  const LinearProblem problem(y, {{"coulomb_friction", 0, sign}, {"viscous_friction", 0, v}});
  const SelectionResult s = SelectEffects(problem, Options());
  ASSERT_EQ(s.effects.size(), 2u);
  for (const TrialEffect& e : s.effects) {
    EXPECT_NEAR(e.parameters.at("theta"), e.name == "viscous_friction" ? 200.0 : 20.0, e.name == "viscous_friction" ? 10 : 1)
        << e.name;
  }
}

// An effect taken out again by the backward step: the shares of the test rows' gap that
// the effects left report are each one's on top of those before it, with the parameters
// they end with, so together they make the whole reduction: the product of (1 - share)
// is the gap after over the gap before. (Recorded when each was added, the shares of the
// effects after the one taken out were on top of it: issue 44.)
TEST(ForwardSelection, TheGapSharesAddUpAfterAnEffectIsTakenOut) {
  Rng rng(9);
  const std::size_t n = 6000;
  std::vector<double> y(n), x1(n), x2(n), mix(n);
  for (std::size_t i = 0; i < n; ++i) {
    x1[i] = rng.Gaussian(1.0);
    x2[i] = rng.Gaussian(1.0);
    // Explains most of y alone (R^2 0.67), and nothing once x1 and x2 are in.
    mix[i] = (x1[i] + x2[i]) / std::sqrt(2.0) + 0.7 * rng.Gaussian(1.0);
    y[i] = x1[i] + x2[i] + rng.Gaussian(0.05);
  }
  const LinearProblem problem(y, {{"payload", 0, mix}, {"viscous_friction", 0, x1}, {"coulomb_friction", 0, x2}});
  const SelectionResult s = SelectEffects(problem, Options());
  ASSERT_EQ(s.removed.size(), 1u);
  EXPECT_NE(s.removed[0].find("payload"), std::string::npos) << s.removed[0];
  ASSERT_EQ(s.effects.size(), 2u);
  ASSERT_EQ(s.gap_reductions.size(), 2u);
  double left = 1;
  for (double share : s.gap_reductions) left *= 1 - share;
  const double ratio = problem.Gap(Mean(s.after.test)) / problem.Gap(Mean(s.before.test));
  EXPECT_NEAR(left, ratio, 1e-9);
  EXPECT_GT(s.gap_reductions[0], 0.2);
}

// The 25 % rule (a quarter and more removed on fit and selection rows, significant or
// not) asks for most of the blocks an effect changes to improve. Here a feature that
// holds a drawn level over each 50-row block (a slow motion: the long-run t test sees
// few independent rows and is not significant) drives the residual in a third of the
// blocks (every third group of five: 6 of the 16 selection blocks) and nothing
// elsewhere. Fitted on all fit rows it removes about a third of the squared error, all
// of it from those blocks, and makes the other ten worse. Under the old rule it was
// added; now it is not. The same feature present only where it acts (zero elsewhere)
// changes only those blocks, improves all of them and is still added.
TEST(ForwardSelection, TheQuarterRuleAsksMostChangedBlocksToImprove) {
  Rng rng(11);
  const std::size_t n = 4000;
  std::vector<double> y(n), everywhere(n), where_it_acts(n);
  double level = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 50 == 0) level = rng.Gaussian(1.0);
    const bool acts = (i / 250) % 3 == 0;  // groups of five 50-row blocks
    everywhere[i] = level;
    where_it_acts[i] = acts ? level : 0.0;
    y[i] = rng.Gaussian(0.3) + (acts ? 10 * level : 0.0);
  }
  const SelectionResult spread = SelectEffects(LinearProblem(y, {{"torque_offset", 0, everywhere}}), Options());
  ASSERT_EQ(spread.candidates.size(), 1u);
  const DiagnosisCandidate& c = spread.candidates[0];
  EXPECT_GE(c.reduction, 0.25);
  EXPECT_FALSE(c.significant) << "t = " << c.t_statistic << ": the rule this test is about would not be asked";
  EXPECT_EQ(c.blocks_changed, 16);
  EXPECT_EQ(c.blocks_improved, 6);
  EXPECT_TRUE(spread.effects.empty());

  const SelectionResult local = SelectEffects(LinearProblem(y, {{"torque_offset", 0, where_it_acts}}), Options());
  ASSERT_EQ(local.effects.size(), 1u);
  EXPECT_NEAR(local.effects[0].parameters.at("theta"), 10, 0.1);
  EXPECT_EQ(local.candidates[0].blocks_changed, 6);
  EXPECT_EQ(local.candidates[0].blocks_improved, 6);
}

// A block counts as changed where the effect moved its squared error by 1 % or more
// (issue 63): an omni effect leaves a trace in blocks where it never acts (the observer
// carries its state over), and those traces, of either sign, were counted as blocks it
// changed. Here the feature of the test above also holds a ten-thousandth of the level
// where it does not act: it still changes 6 blocks, improves 6 and is added. And a
// quarter removed in one block alone is not enough: the same effect acting in one group
// of blocks only (one selection block) removes nearly all the selection rows' error,
// not significantly, and is not added.
TEST(ForwardSelection, TheQuarterRuleCountsBlocksItChangesByAPercentAndAsksTwo) {
  Rng rng(11);
  const std::size_t n = 4000;
  std::vector<double> y(n), traced(n), y_once(n), once(n);
  double level = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 50 == 0) level = rng.Gaussian(1.0);
    const bool acts = (i / 250) % 3 == 0;  // groups of five 50-row blocks
    const double noise = rng.Gaussian(0.3);
    traced[i] = acts ? level : 1e-4 * level;
    y[i] = noise + (acts ? 10 * level : 0.0);
    const bool first = i < 250;  // blocks 0-2 fit, 3 selection, 4 test
    once[i] = first ? level : 0.0;
    y_once[i] = noise + (first ? 10 * level : 0.0);
  }
  const SelectionResult spread = SelectEffects(LinearProblem(y, {{"torque_offset", 0, traced}}), Options());
  ASSERT_EQ(spread.effects.size(), 1u);
  EXPECT_NEAR(spread.effects[0].parameters.at("theta"), 10, 0.1);
  EXPECT_EQ(spread.candidates[0].blocks_changed, 6);  // 16 counted at a millionth
  EXPECT_EQ(spread.candidates[0].blocks_improved, 6);

  const SelectionResult single = SelectEffects(LinearProblem(y_once, {{"torque_offset", 0, once}}), Options());
  ASSERT_EQ(single.candidates.size(), 1u);
  EXPECT_GE(single.candidates[0].reduction, 0.25);
  EXPECT_FALSE(single.candidates[0].significant) << "t = " << single.candidates[0].t_statistic;
  EXPECT_EQ(single.candidates[0].blocks_changed, 1);
  EXPECT_EQ(single.candidates[0].blocks_improved, 1);
  EXPECT_TRUE(single.effects.empty());
}

// Two joints, each a LinearProblem over its own rows (the same row kinds and blocks): an
// arm whose joints' torques carry noise of very different sizes. An effect acts on its
// joint's rows alone; with `own_channel` it is scored there (ChannelOf), else on the sum.
class TwoJointProblem : public DiagnosisProblem {
 public:
  TwoJointProblem(LinearProblem first, LinearProblem second, bool own_channel)
      : joints_{std::move(first), std::move(second)}, own_channel_(own_channel) {}

  double Gap(double mean_squared) const override { return std::sqrt(mean_squared / 2); }
  int ChunkRows() const override { return 5; }
  double FloorRatio() const override { return 4; }
  int ChannelOf(const TrialEffect& e) const override { return own_channel_ ? e.joint : -1; }

  SquaredResiduals Evaluate(const std::vector<TrialEffect>& effects) const override {
    const SquaredResiduals a = joints_[0].Evaluate(On(effects, 0)), b = joints_[1].Evaluate(On(effects, 1));
    SquaredResiduals out;
    out.fit = Sum(a.fit, b.fit), out.selection = Sum(a.selection, b.selection), out.test = Sum(a.test, b.test);
    out.selection_by_channel = {a.selection, b.selection};
    out.fit_by_channel = {a.fit, b.fit};
    out.selection_block = a.selection_block;
    return out;
  }

  std::vector<TrialEffect> Candidates(const std::vector<TrialEffect>& current) const override {
    std::vector<TrialEffect> out = joints_[0].Candidates(On(current, 0));
    for (const TrialEffect& e : joints_[1].Candidates(On(current, 1))) out.push_back(e);
    return out;
  }

  std::vector<TrialEffect> Fit(std::vector<TrialEffect> effects, const std::vector<int>& free) const override {
    for (int j = 0; j < 2; ++j) {
      std::vector<TrialEffect> mine;
      std::vector<int> at, mine_free;
      for (std::size_t k = 0; k < effects.size(); ++k) {
        if (effects[k].joint != j) continue;
        if (std::find(free.begin(), free.end(), static_cast<int>(k)) != free.end()) mine_free.push_back(static_cast<int>(mine.size()));
        at.push_back(static_cast<int>(k));
        mine.push_back(effects[k]);
      }
      if (mine_free.empty()) continue;
      mine = joints_[static_cast<std::size_t>(j)].Fit(mine, mine_free);
      for (std::size_t m = 0; m < at.size(); ++m) effects[static_cast<std::size_t>(at[m])] = mine[m];
    }
    return effects;
  }

  std::vector<double> FitResiduals(const std::vector<TrialEffect>& effects) const override {
    std::vector<double> out = joints_[0].FitResiduals(On(effects, 0));
    for (double r : joints_[1].FitResiduals(On(effects, 1))) out.push_back(r);
    return out;
  }

  TestResiduals TestRowResiduals(const std::vector<TrialEffect>& effects, bool learn) const override {
    TestResiduals t = joints_[0].TestRowResiduals(On(effects, 0), learn);
    t.channels = {"joint 1", "joint 2"};
    t.noise = {1, 1};
    t.residual.push_back(joints_[1].TestRowResiduals(On(effects, 1), learn).residual[0]);
    return t;
  }

 private:
  static std::vector<TrialEffect> On(const std::vector<TrialEffect>& effects, int joint) {
    std::vector<TrialEffect> out;
    for (const TrialEffect& e : effects)
      if (e.joint == joint) out.push_back(e);
    return out;
  }
  static std::vector<double> Sum(const std::vector<double>& a, const std::vector<double>& b) {
    std::vector<double> out(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) out[i] = a[i] + b[i];
    return out;
  }

  std::array<LinearProblem, 2> joints_;
  bool own_channel_;
};

// Issue 41's "one error summed over joints": a delay on the MuJoCo arm's wrist removed
// a third of the wrist's error and 1 % of the error summed over joints, which the
// shoulder's noise (five times the wrist's) dominates; it was not named. Here joint 2's
// effect removes about a quarter of joint 2's squared error and 0.3 % of the sum. Scored
// on the sum it falls under the 5 % floor; scored on its joint it is added, with its
// coefficient. A feature of pure noise on joint 1 is added in neither.
TEST(ForwardSelection, AnEffectOnOneJointIsScoredOnThatJoint) {
  Rng rng(13);
  const std::size_t n = 4000;
  std::vector<double> y1(n), y2(n), decoy(n), wrist(n);
  for (std::size_t i = 0; i < n; ++i) {
    decoy[i] = rng.Gaussian(1.0);
    wrist[i] = std::sin(0.031 * static_cast<double>(i)) + 0.5 * std::sin(0.17 * static_cast<double>(i));
    y1[i] = rng.Gaussian(3.0);
    y2[i] = rng.Gaussian(0.3) + 0.25 * wrist[i];
  }
  auto problem = [&](bool own) {
    return TwoJointProblem(LinearProblem(y1, {{"torque_offset", 0, decoy}}), LinearProblem(y2, {{"time_delay", 1, wrist}}), own);
  };
  const SelectionResult summed = SelectEffects(problem(false), Options());
  EXPECT_TRUE(summed.effects.empty());
  for (const DiagnosisCandidate& c : summed.candidates) {
    if (c.name == "time_delay") {
      EXPECT_LT(c.reduction, 0.01);
    }
  }
  const SelectionResult own = SelectEffects(problem(true), Options());
  ASSERT_EQ(own.effects.size(), 1u);
  EXPECT_EQ(own.effects[0].name, "time_delay");
  EXPECT_NEAR(own.effects[0].parameters.at("theta"), 0.25, 0.02);
  for (const DiagnosisCandidate& c : own.candidates) {
    if (c.name == "time_delay") {
      EXPECT_GT(c.reduction, 0.15);
    }
  }
  ASSERT_EQ(own.evidence.size(), 1u);
  EXPECT_NE(own.evidence[0].find("of its joint's selection rows' squared error"), std::string::npos) << own.evidence[0];
}

}  // namespace
}  // namespace twinsim

#include "diagnosis/forward_selection.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>

#include "core/parallel.h"
#include "diagnosis/statistics.h"
#include "signal/spectrum.h"

namespace twinsim {
namespace {

// A share of the squared residual removed on fit and selection rows alike that counts
// as significant whatever the t test says: an effect that shows only in a few events
// (a speed limit reached now and then) leaves most rows unchanged and its long-run
// standard error large, yet a quarter removed on both sets is no accident, provided it
// is removed in most of the selection blocks the effect changes, and in two at least
// (not a few blocks of one kind of motion where the model is wrong in another way: fast
// turns of a robot recorded by ODE, diagnosed on the analytic model, issue 41).
constexpr double kStrongReduction = 0.25;
// A block's squared error counts as changed when it moved by more than this share of
// it. Where an effect never acts (a speed limit in a block of slow driving) the
// observer's filtered state still carries a trace of it into the block: a millionth
// counted those traces, of either sign, as blocks the effect changed, so that a speed
// limit on a robot written apart (tests/diagnosis/omni_foreign_diagnosis_test.cc) that
// removed 44 % of the selection rows' error, in both blocks it acted on, improved "2 of
// the 4 blocks it changed" and was not named (issue 63).
constexpr double kBlockChanged = 0.01;
constexpr int kWhitenessLags = 20;
constexpr int kCrossCorrelationsShown = 3;
// A learned yardstick is taken as trained while it predicts the test rows at most this
// share worse than the nominal model alone: a correction that learned nothing (its
// ridge kept the physics, or fitted the fit rows' noise) is a yardstick that found
// nothing predictable; one far worse is broken (below).
constexpr double kYardstickTolerance = 0.1;

// Row by row, how much `after` is below `before` (the rows of both in the same order).
std::vector<double> Gains(const std::vector<double>& before, const std::vector<double>& after) {
  std::vector<double> g(before.size());
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = before[i] - after[i];
  return g;
}

struct Score {
  double reduction = 0;      // share of the selection rows' MSE removed
  double fit_reduction = 0;  // share of the fit rows' MSE removed
  LongRunTest test;
  double information_gain = 0;
  // The channel it makes worst, by its share of that channel's MSE (negative: worse),
  // and the t of that change: a missing effect, rightly fitted, makes no channel worse.
  int worst_channel = -1;
  double worst_share = 0;
  double worst_t = 0;
  int channels = 0;  // compared: the worst is picked among them
  int blocks_changed = 0, blocks_improved = 0;  // selection blocks (SquaredResiduals::selection_block)
  int blocks = 0;                               // selection blocks in all
};

// Most of the selection blocks a candidate changes, and two at least, it improves.
bool MostBlocksImprove(int changed, int improved) { return 2 * improved > changed && improved >= 2; }

// The effective number of independent rows in a residual series.
double EffectiveRows(const std::vector<double>& squared, int min_bandwidth) {
  return LongRunMeanTest(squared, min_bandwidth).effective_rows;
}

// True when both hold `channel` (>= 0) of their selection rows, and of their fit rows
// where `fit` asks.
bool HasChannel(const SquaredResiduals& before, const SquaredResiduals& after, int channel, bool fit) {
  const auto c = static_cast<std::size_t>(channel);
  if (channel < 0 || c >= before.selection_by_channel.size() || c >= after.selection_by_channel.size()) return false;
  return !fit || (c < before.fit_by_channel.size() && c < after.fit_by_channel.size());
}

// True when `after` differs from `before` on no channel's selection rows but `channel`'s
// (a joint's effect fitted alone, or refitted beside others on the same joint; a refit
// beside a payload moves every joint).
bool OnlyChannelChanged(const SquaredResiduals& before, const SquaredResiduals& after, int channel) {
  if (!HasChannel(before, after, channel, false) || before.selection_by_channel.size() != after.selection_by_channel.size())
    return false;
  for (std::size_t c = 0; c < before.selection_by_channel.size(); ++c)
    if (static_cast<int>(c) != channel && before.selection_by_channel[c] != after.selection_by_channel[c]) return false;
  return true;
}

// `after` against `before` on the selection rows, summed over the channels or on
// `channel` alone (>= 0: DiagnosisProblem::ChannelOf); `parameters` counted against the
// effective row count of those rows (`effective_rows` for the sum).
Score Compare(const SquaredResiduals& before, const SquaredResiduals& after, int min_bandwidth, int parameters,
              double effective_rows, int channel = -1) {
  Score s;
  const bool own = HasChannel(before, after, channel, false);
  const auto c = static_cast<std::size_t>(std::max(channel, 0));
  const std::vector<double>& selection_before = own ? before.selection_by_channel[c] : before.selection;
  const std::vector<double>& selection_after = own ? after.selection_by_channel[c] : after.selection;
  const bool own_fit = own && HasChannel(before, after, channel, true);
  const std::vector<double>& fit_before = own_fit ? before.fit_by_channel[c] : before.fit;
  const std::vector<double>& fit_after = own_fit ? after.fit_by_channel[c] : after.fit;
  if (own) effective_rows = EffectiveRows(selection_before, min_bandwidth);
  const double mse = Mean(selection_before);
  if (mse <= 0 || selection_before.size() != selection_after.size()) return s;
  const std::vector<double> gain = Gains(selection_before, selection_after);
  s.reduction = Mean(gain) / mse;
  s.test = LongRunMeanTest(gain, min_bandwidth);
  const double mse_after = Mean(selection_after);
  s.information_gain = mse_after > 0 ? effective_rows * std::log(mse / mse_after) - 2.0 * parameters
                                     : std::numeric_limits<double>::infinity();
  const double fit_mse = Mean(fit_before);
  if (fit_mse > 0) s.fit_reduction = (fit_mse - Mean(fit_after)) / fit_mse;
  // Per selection block, the squared error before and the gain (blocks in row order).
  const bool blocked = before.selection_block.size() == gain.size();
  std::size_t i = 0;
  while (i < gain.size()) {
    double block_before = 0, block_gain = 0;
    const std::size_t start = i;
    do {
      block_before += selection_before[i];
      block_gain += gain[i];
      ++i;
    } while (i < gain.size() && blocked && before.selection_block[i] == before.selection_block[start]);
    ++s.blocks;
    if (std::abs(block_gain) > kBlockChanged * block_before) {
      ++s.blocks_changed;
      if (block_gain > 0) ++s.blocks_improved;
    }
  }
  // The selection blocks lie apart (fit and test blocks between them): each is one
  // independent piece of evidence at most.
  if (blocked) AccountForBlocks(gain, before.selection_block, &s.test);
  for (std::size_t c = 0; c < before.selection_by_channel.size() && c < after.selection_by_channel.size(); ++c) {
    const std::vector<double>& b = before.selection_by_channel[c];
    const std::vector<double>& a = after.selection_by_channel[c];
    const double channel_mse = Mean(b);
    if (channel_mse <= 0 || a.size() != b.size()) continue;
    ++s.channels;
    const std::vector<double> g = Gains(b, a);
    const double share = Mean(g) / channel_mse;
    if (share < s.worst_share) {
      s.worst_share = share;
      s.worst_channel = static_cast<int>(c);
      s.worst_t = LongRunMeanTest(g, min_bandwidth).t;
    }
  }
  return s;
}

// True when `s` makes a channel worse by at least `least` of its MSE, significantly at
// level alpha (one-sided, long-run standard error; the worst of the channels compared,
// so Bonferroni-corrected over them: WorstChannelP).
bool HarmsAChannel(const Score& s, double least, double alpha) {
  if (s.worst_channel < 0 || s.worst_share > -least) return false;
  return WorstChannelP(s.worst_t, std::max(1.0, s.test.df), s.channels) <= alpha;
}

std::string Percent(double share) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f %%", 100 * share);
  return buf;
}

std::string PValue(double p) {
  char buf[32];
  if (p < 1e-4) return "p < 1e-4";
  std::snprintf(buf, sizeof buf, "p = %.2g", p);
  return buf;
}

// True where a candidate's state test (DiagnosisProblem::StateTest), not its selection
// rows, is what makes it significant.
bool CarriedByState(const DiagnosisCandidate& c) { return !std::isnan(c.state_p_value) && c.state_p_value < c.p_value; }

// Whose squared error a share is of: the selection rows', or those of the one joint an
// effect was scored on (ChannelOf).
const char* ScoredRows(bool own_channel) { return own_channel ? "its joint's selection rows'" : "the selection rows'"; }

// "it removed 64 % of the selection rows' squared error (t = 23, p < 1e-4, Holm-corrected
// over 22 candidates), the closest alternatives coulomb_friction (joint 2) 41 % and ...".
// `own_channel`: the winner was scored on the channel it acts on alone (ChannelOf).
std::string RoundEvidence(const std::vector<DiagnosisCandidate>& round, const DiagnosisCandidate& best, int tested,
                          bool own_channel) {
  std::vector<const DiagnosisCandidate*> others;
  for (const auto& c : round) {
    if (&c != &best && c.note.empty()) others.push_back(&c);
  }
  std::sort(others.begin(), others.end(),
            [](const DiagnosisCandidate* a, const DiagnosisCandidate* b) { return a->reduction > b->reduction; });
  char head[512];
  if (CarriedByState(best) && best.significant) {
    std::snprintf(head, sizeof head,
                  "%s (%s; significant after Holm's correction over %d candidates); it removed %s of %s squared "
                  "error (t = %.1f)",
                  best.state_test.c_str(), PValue(best.state_p_value).c_str(), tested, Percent(best.reduction).c_str(),
                  ScoredRows(own_channel), best.t_statistic);
  } else {
    std::snprintf(head, sizeof head, "it removed %s of %s squared error (t = %.1f, %s; %s)",
                  Percent(best.reduction).c_str(), ScoredRows(own_channel), best.t_statistic,
                  PValue(best.p_value).c_str(),
                  best.significant
                      ? ("significant after Holm's correction over " + std::to_string(tested) + " candidates").c_str()
                      : ("a quarter and more on fit and selection rows alike, lower in " +
                         std::to_string(best.blocks_improved) + " of the " + std::to_string(best.blocks_changed) +
                         " selection blocks it changed")
                            .c_str());
  }
  std::string s = head;
  const std::size_t shown = std::min<std::size_t>(2, others.size());
  for (std::size_t k = 0; k < shown; ++k) {
    s += k == 0 ? ", the closest alternatives " : (k + 1 == shown ? " and " : ", ");
    s += EffectLabel(others[k]->name, others[k]->joint) + " " + Percent(std::max(0.0, others[k]->reduction));
  }
  return s;
}

}  // namespace

double Mean(const std::vector<double>& v) {
  if (v.empty()) return 0;
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

namespace {

// The problem's state test of `fitted` against `others` (DiagnosisProblem::StateTest);
// none where it fails (a replay that diverges): the selection rows then decide alone.
StateEvidence TryStateTest(const DiagnosisProblem& problem, const TrialEffect& fitted,
                           const std::vector<TrialEffect>& others) {
  try {
    return problem.StateTest(fitted, others);
  } catch (const std::exception&) {
    return {};
  }
}

// One candidate of a round, fitted beside the effects added so far and scored.
struct CandidateTrial {
  DiagnosisCandidate candidate;
  double fit_reduction = 0;          // its share of the fit rows' squared residual removed
  bool harms = false;                // it makes a channel significantly worse
  // Its information gain on the rows of every channel: what candidates scored on
  // different channels compete on (a channel's own gain is larger the smaller its share).
  double rank_gain = 0;
  bool own_channel = false;          // scored on the one channel it changed (ChannelOf)
  std::vector<TrialEffect> fitted;   // the effects with it, as fitted
};

// What a round scores its candidates against.
struct RoundBase {
  const DiagnosisProblem* problem = nullptr;
  const DiagnosisOptions* options = nullptr;
  int round = 0;
  int bandwidth = 0;                        // rows: the residuals' correlation length
  double effective_rows = 0;                // of the selection rows
  const std::vector<TrialEffect>* current;  // the effects added so far
  const SquaredResiduals* residuals;        // with them
};

// Fits `candidate` beside the effects added so far and scores it. Scored with the effects
// already added refitted too (as stepwise regression re-estimates every coefficient): an
// effect added earlier may have absorbed part of this one (a payload fitted alone takes
// up a torque offset's share), and only the joint fit gives the candidate its due. Kept
// where it fits better. Effects the problem holds while scoring (HeldWhileScoring) keep
// their fit; a candidate that removes nothing on its own is not refitted jointly (it
// would rarely pass, and the joint fits are most of a round's time). A candidate on a
// joint an added effect already acts on is always refitted with it: the added one may
// have taken its share (Coulomb friction chosen first absorbs most of a viscous term;
// viscous fitted with Coulomb held then gains nothing and would never be refitted beside
// it). Effects of the whole robot (joint -1: a payload, every omni effect) share with
// everything, and a joint refit beside them would credit the candidate with their
// refinement.
CandidateTrial TryCandidate(const RoundBase& base, const TrialEffect& candidate) {
  const DiagnosisProblem& problem = *base.problem;
  CandidateTrial out;
  DiagnosisCandidate& c = out.candidate;
  c.round = base.round;
  c.name = candidate.name;
  c.joint = candidate.joint;
  std::vector<TrialEffect> trial = *base.current;
  trial.push_back(candidate);
  try {
    trial = problem.Fit(trial, {static_cast<int>(trial.size()) - 1});
    SquaredResiduals r = problem.Evaluate(trial);
    const int parameters = static_cast<int>(trial.back().parameters.size());
    const int channel = problem.ChannelOf(candidate);
    Score s = Compare(*base.residuals, r, base.bandwidth, parameters, base.effective_rows, channel);
    std::vector<int> refit;
    bool shares = false;
    for (std::size_t m = 0; m < trial.size(); ++m) {
      if (m + 1 == trial.size() || !problem.HeldWhileScoring(trial[m])) refit.push_back(static_cast<int>(m));
      shares = shares || (m + 1 < trial.size() && trial.back().joint >= 0 && trial[m].joint == trial.back().joint);
    }
    bool refitted = false;
    if ((s.reduction > 0 || shares) && refit.size() > 1) {
      try {
        std::vector<TrialEffect> joint = problem.Fit(trial, refit);
        SquaredResiduals rj = problem.Evaluate(joint);
        if (Mean(rj.fit) < Mean(r.fit)) trial = std::move(joint), r = std::move(rj), refitted = true;
      } catch (const std::exception&) {
        // the joint refit failed: the one-at-a-time fit stands
      }
    }
    // Scored on its joint only where it changed that joint alone; scored again only where
    // the refit moved it or the score above was its joint's and may not be.
    const bool own = channel >= 0 && OnlyChannelChanged(*base.residuals, r, channel);
    if (refitted || (channel >= 0 && !own))
      s = Compare(*base.residuals, r, base.bandwidth, parameters, base.effective_rows, own ? channel : -1);
    out.own_channel = own;
    out.rank_gain = own ? Compare(*base.residuals, r, base.bandwidth, parameters, base.effective_rows).information_gain
                        : s.information_gain;
    const StateEvidence state = TryStateTest(problem, trial.back(), *base.current);
    c.state_p_value = state.p;
    c.state_test = state.what;
    c.parameters = trial.back().parameters;
    c.fit_gap = problem.Gap(Mean(r.fit));
    c.held_out_gap = problem.Gap(Mean(r.selection));
    c.reduction = s.reduction;
    c.t_statistic = s.test.t;
    c.p_value = s.test.p;
    c.information_gain = s.information_gain;
    c.blocks_changed = s.blocks_changed;
    c.blocks_improved = s.blocks_improved;
    out.fit_reduction = s.fit_reduction;
    out.harms = HarmsAChannel(s, base.options->min_improvement, base.options->alpha);
    if (out.harms) {
      char why[160];
      std::snprintf(why, sizeof why, "it makes channel %d worse by %s of its squared residual (t = %.1f)",
                    s.worst_channel + 1, Percent(-s.worst_share).c_str(), s.worst_t);
      c.harm = why;
    }
    out.fitted = std::move(trial);
  } catch (const std::exception& e) {
    c.note = e.what();
    c.reduction = -std::numeric_limits<double>::infinity();
    c.p_value = std::numeric_limits<double>::quiet_NaN();
  }
  return out;
}

// The candidates that pass, by information gain over every channel (one that fails the
// test must not hide another that passes; ties go to the earlier candidate), each marked significant or not
// by Holm's correction over the candidates that could be fitted: the best of many is held
// to the family's level, not to one test's. *tested counts those.
std::vector<std::size_t> PassingOrder(const DiagnosisOptions& options, std::vector<CandidateTrial>* trials, int* tested) {
  std::vector<double> p;
  *tested = 0;
  for (const CandidateTrial& t : *trials) {
    const DiagnosisCandidate& c = t.candidate;
    // With a state test beside the selection rows' the smaller p counts, doubled
    // (Bonferroni over the candidate's two tests).
    const double own = std::isnan(c.state_p_value) ? c.p_value : std::min(1.0, 2 * std::min(c.p_value, c.state_p_value));
    p.push_back(c.note.empty() ? own : std::numeric_limits<double>::quiet_NaN());
    *tested += c.note.empty() ? 1 : 0;
  }
  const std::vector<bool> significant = HolmReject(p, options.alpha);
  std::vector<std::size_t> order;
  for (std::size_t k = 0; k < trials->size(); ++k) {
    DiagnosisCandidate& c = (*trials)[k].candidate;
    c.significant = significant[k];
    const bool strong = c.reduction >= kStrongReduction && (*trials)[k].fit_reduction >= kStrongReduction &&
                        c.t_statistic > 0 && MostBlocksImprove(c.blocks_changed, c.blocks_improved);
    // By the selection rows: a share removed that earns its parameters. By the state
    // test: the selection rows not made worse (their noise may hide what the state shows).
    const bool earns = c.reduction >= options.min_improvement && c.information_gain > 0;
    const bool by_state = CarriedByState(c) && c.reduction > 0;
    if (c.note.empty() && !(*trials)[k].harms && ((earns && (significant[k] || strong)) || (by_state && significant[k])))
      order.push_back(k);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return (*trials)[a].rank_gain > (*trials)[b].rank_gain;
  });
  return order;
}

// Why the last of `effects` is not added for a parameter the logs do not determine
// (DiagnosisProblem::MustBeDetermined), or "".
std::string Undetermined(const DiagnosisProblem& problem, const std::vector<TrialEffect>& effects) {
  const std::vector<std::string> keys = problem.MustBeDetermined(effects.back());
  if (keys.empty()) return "";
  const std::map<std::string, double> errors = StandardErrors(problem, effects).back();
  for (const std::string& key : keys) {
    const double value = effects.back().parameters.at(key), error = errors.at(key);
    if (std::isfinite(error) && error < std::abs(value)) continue;
    return "vetoed: the logs do not determine its " + key + " (" + FormatParameter(value) + ", standard error " +
           (std::isfinite(error) ? FormatParameter(error) : std::string("none")) + ")";
  }
  return "";
}

// The best passing candidate, all added effects refitted with it, unless that makes the
// test rows worse: the test rows choose nothing, but they veto. An effect that fits the
// fit and selection rows and not the rows neither saw is fitted to something else (the
// noise's peaks, a derivative filter's error); it is reported, never added. So is one
// whose parameters the problem asks to be determined and the logs do not determine
// (Undetermined). Returns its index (trials->size(): none), with the effects and their
// residuals in *next and *r.
std::size_t BestUnvetoed(const RoundBase& base, const std::vector<std::size_t>& order,
                         std::vector<CandidateTrial>* trials, std::vector<TrialEffect>* next, SquaredResiduals* r) {
  const DiagnosisProblem& problem = *base.problem;
  for (std::size_t k : order) {
    *next = (*trials)[k].fitted;
    std::vector<int> all(next->size());
    for (std::size_t m = 0; m < all.size(); ++m) all[m] = static_cast<int>(m);
    // Refit every added effect together, a single one too (one more refinement from
    // where it stands): the next round's candidates, scored with a joint refit, must
    // not be credited with what more refinement of these alone would have found.
    try {
      *next = problem.Fit(*next, all);
    } catch (const std::exception&) {
      *next = (*trials)[k].fitted;  // the joint refit failed: keep the one-at-a-time fit
    }
    *r = problem.Evaluate(*next);
    const double test_before = Mean(base.residuals->test), test_after = Mean(r->test);
    if (test_after > test_before) {
      char why[200];
      std::snprintf(why, sizeof why, "vetoed: it makes the test rows worse (gap %s -> %s)",
                    FormatParameter(problem.Gap(test_before)).c_str(), FormatParameter(problem.Gap(test_after)).c_str());
      (*trials)[k].candidate.veto = why;
      continue;
    }
    if (std::string undetermined = Undetermined(problem, *next); !undetermined.empty()) {
      (*trials)[k].candidate.veto = undetermined;
      continue;
    }
    return k;
  }
  return trials->size();
}

// Backward step: an effect added earlier that the new one (`winner`) made redundant (its
// removal, the others held, costs less than it must earn) goes out again, and the rest
// are refitted. *current and their residuals *r are updated; the removal is recorded.
void BackwardStep(const RoundBase& base, const DiagnosisCandidate& winner, std::vector<TrialEffect>* current,
                  SquaredResiduals* r, SelectionResult* out) {
  if (current->size() <= 1) return;
  const DiagnosisProblem& problem = *base.problem;
  const DiagnosisOptions& options = *base.options;
  std::size_t weakest = current->size();
  Score weakest_score;
  bool weakest_own = false;  // scored on its joint
  for (std::size_t m = 0; m + 1 < current->size(); ++m) {
    std::vector<TrialEffect> without = *current;
    without.erase(without.begin() + static_cast<std::ptrdiff_t>(m));
    const SquaredResiduals rw = problem.Evaluate(without);
    const int channel = problem.ChannelOf((*current)[m]);
    const bool own = OnlyChannelChanged(rw, *r, channel);
    const Score keep = Compare(rw, *r, base.bandwidth, static_cast<int>((*current)[m].parameters.size()),
                               EffectiveRows(rw.selection, base.bandwidth), own ? channel : -1);
    // An effect its state test carried earns its place by that test, the others held.
    const StateEvidence state = TryStateTest(problem, (*current)[m], without);
    const bool earns = (keep.reduction >= options.min_improvement && keep.information_gain > 0 &&
                        (keep.test.p <= options.alpha ||
                         (keep.reduction >= kStrongReduction && keep.fit_reduction >= kStrongReduction &&
                          MostBlocksImprove(keep.blocks_changed, keep.blocks_improved)))) ||
                       (state.p <= options.alpha && keep.reduction > 0);
    if (!earns && (weakest == current->size() || keep.test.p > weakest_score.test.p)) {
      weakest = m;
      weakest_score = keep;
      weakest_own = own;
    }
  }
  if (weakest == current->size()) return;
  char why[320];
  std::snprintf(why, sizeof why,
                "round %d: %s was taken out again: beside %s it removes only %s of %s squared "
                "error (t = %.1f, %s)",
                base.round, EffectLabel((*current)[weakest].name, (*current)[weakest].joint).c_str(),
                EffectLabel(winner.name, winner.joint).c_str(), Percent(weakest_score.reduction).c_str(),
                ScoredRows(weakest_own),
                weakest_score.test.t, PValue(weakest_score.test.p).c_str());
  out->removed.push_back(why);
  current->erase(current->begin() + static_cast<std::ptrdiff_t>(weakest));
  out->evidence.erase(out->evidence.begin() + static_cast<std::ptrdiff_t>(weakest));
  std::vector<int> rest(current->size());
  for (std::size_t k = 0; k < rest.size(); ++k) rest[k] = static_cast<int>(k);
  try {
    *current = problem.Fit(*current, rest);
  } catch (const std::exception&) {
    // the refit failed: the others keep their parameters
  }
  *r = problem.Evaluate(*current);
}

// Each effect's share of the test rows' gap on top of those before it, with the
// parameters they all end with: the shares recorded as each was added no longer add up
// once a refit changed the earlier ones or the backward step took one out.
std::vector<double> GapReductions(const DiagnosisProblem& problem, const SelectionResult& out) {
  std::vector<double> shares;
  double gap = problem.Gap(Mean(out.before.test));
  for (std::size_t k = 1; k <= out.effects.size(); ++k) {
    const double next =
        k == out.effects.size()
            ? problem.Gap(Mean(out.after.test))
            : problem.Gap(Mean(problem.Evaluate(std::vector<TrialEffect>(out.effects.begin(),
                                                                         out.effects.begin() + static_cast<std::ptrdiff_t>(k)))
                                   .test));
    shares.push_back(gap > 0 ? (gap - next) / gap : 0.0);
    gap = next;
  }
  return shares;
}

}  // namespace

SelectionResult SelectEffects(const DiagnosisProblem& problem, const DiagnosisOptions& options,
                              const std::function<void(const std::string&)>& progress) {
  SelectionResult out;
  out.before = problem.Evaluate({});
  SquaredResiduals current_residuals = out.before;
  std::vector<TrialEffect> current;
  for (int round = 1; round <= options.max_effects; ++round) {
    const std::vector<TrialEffect> candidates = problem.Candidates(current);
    if (candidates.empty()) break;
    if (progress) {
      progress("round " + std::to_string(round) + ": fitting " + std::to_string(candidates.size()) + " candidates");
    }
    RoundBase base;
    base.problem = &problem;
    base.options = &options;
    base.round = round;
    base.bandwidth = problem.ChunkRows();
    base.effective_rows = EffectiveRows(current_residuals.selection, base.bandwidth);
    base.current = &current;
    base.residuals = &current_residuals;
    std::vector<CandidateTrial> trials(candidates.size());
    ParallelFor(static_cast<int>(candidates.size()), options.threads, [&](int i) {
      trials[static_cast<std::size_t>(i)] = TryCandidate(base, candidates[static_cast<std::size_t>(i)]);
    });
    int tested = 0;
    const std::vector<std::size_t> order = PassingOrder(options, &trials, &tested);
    std::vector<TrialEffect> next;
    SquaredResiduals r;
    const std::size_t best = BestUnvetoed(base, order, &trials, &next, &r);
    std::vector<DiagnosisCandidate> tried;
    for (const CandidateTrial& t : trials) tried.push_back(t.candidate);
    const bool passes = best < tried.size();
    if (passes) {
      DiagnosisCandidate& winner = tried[best];
      winner.selected = true;
      const std::string evidence = RoundEvidence(tried, winner, tested, trials[best].own_channel);
      current = next;
      std::string signature = problem.Signature(current.back());
      out.evidence.push_back(EffectLabel(winner.name, winner.joint) + ": " + evidence +
                             (signature.empty() ? "" : "; " + signature) + ".");
      BackwardStep(base, winner, &current, &r, &out);
      current_residuals = r;
    }
    out.candidates.insert(out.candidates.end(), tried.begin(), tried.end());
    if (!passes) break;
  }
  out.effects = current;
  out.after = current_residuals;
  out.gap_reductions = GapReductions(problem, out);
  return out;
}

std::vector<std::map<std::string, double>> StandardErrors(const DiagnosisProblem& problem,
                                                          const std::vector<TrialEffect>& effects) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::map<std::string, double>> out(effects.size());
  struct Slot {
    std::size_t effect;
    std::string key;
  };
  std::vector<Slot> slots;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    for (const auto& [key, value] : effects[i].parameters) {
      if (problem.Derived(effects[i], key)) continue;
      slots.push_back({i, key});
      out[i][key] = nan;
    }
  }
  if (slots.empty()) return out;
  std::vector<double> r0;
  try {
    r0 = problem.FitResiduals(effects);
  } catch (const std::exception&) {
    return out;
  }
  const auto n = static_cast<Eigen::Index>(r0.size());
  const auto k = static_cast<Eigen::Index>(slots.size());
  if (n <= k) return out;
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(n, k);
  std::vector<bool> usable(slots.size(), false);
  for (std::size_t s = 0; s < slots.size(); ++s) {
    const double value = effects[slots[s].effect].parameters.at(slots[s].key);
    const double h = problem.RelativeStep() * std::max(std::abs(value), 1e-3);
    auto at = [&](double v, std::vector<double>* r) {
      std::vector<TrialEffect> trial = effects;
      trial[slots[s].effect].parameters[slots[s].key] = v;
      try {
        *r = problem.FitResiduals(trial);
        return r->size() == r0.size();
      } catch (const std::exception&) {
        return false;
      }
    };
    std::vector<double> plus, minus;
    const bool up = at(value + h, &plus), down = at(value - h, &minus);
    if (!up && !down) continue;
    for (Eigen::Index row = 0; row < n; ++row) {
      const auto i = static_cast<std::size_t>(row);
      jacobian(row, static_cast<Eigen::Index>(s)) =
          up && down ? (plus[i] - minus[i]) / (2 * h) : (up ? (plus[i] - r0[i]) / h : (r0[i] - minus[i]) / h);
    }
    usable[s] = jacobian.col(static_cast<Eigen::Index>(s)).squaredNorm() > 0;
  }
  // Residual variance per row, inflated by how long the residual stays correlated:
  // neighbouring rows are not independent evidence.
  double rss = 0;
  for (double v : r0) rss += v * v;
  const int components = std::max(1, problem.ResidualComponents());
  int correlation = 1;
  for (int c = 0; c < components; ++c) {
    std::vector<double> series;
    for (std::size_t i = static_cast<std::size_t>(c); i < r0.size(); i += static_cast<std::size_t>(components)) series.push_back(r0[i]);
    correlation = std::max(correlation, CorrelationLength(series, std::max(1, static_cast<int>(series.size() / 4))));
  }
  const double variance = rss / static_cast<double>(n - k) * correlation;
  // A parameter gets an error only where the logs determine it: its unit vector lies in
  // the range of the information matrix (always, when that has full rank).
  const Eigen::MatrixXd information = jacobian.transpose() * jacobian;
  const Eigen::MatrixXd inverse = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(information).pseudoInverse();
  for (std::size_t s = 0; s < slots.size(); ++s) {
    const auto c = static_cast<Eigen::Index>(s);
    if (!usable[s]) continue;
    Eigen::VectorXd back = information * inverse.col(c);
    back[c] -= 1;
    if (back.norm() < 1e-6) out[slots[s].effect][slots[s].key] = std::sqrt(std::max(0.0, inverse(c, c) * variance));
  }
  return out;
}

namespace {

// The adequacy of the repaired model on one channel of the test rows.
ChannelAdequacy CheckChannel(const TestResiduals& t, std::size_t c, int bandwidth) {
  ChannelAdequacy a;
  const std::vector<double>& r = t.residual[c];
  a.channel = t.channels[c];
  a.rms = Rms(r);
  a.noise = c < t.noise.size() ? t.noise[c] : 0.0;
  const Whiteness w = LjungBox(r, kWhitenessLags, t.step);
  a.autocorrelation = w.autocorrelation;
  a.step_seconds = t.step / t.rate;
  a.whiteness_bound = w.bound;
  a.whiteness_p = w.p;
  for (std::size_t i = 0; i < t.inputs.size(); ++i) {
    // The inputs are read together (the report shows the largest against its band).
    a.inputs.push_back(PeakCrossCorrelation(r, t.inputs[i], 10 * t.step, t.step, t.input_names[i],
                                            static_cast<int>(t.inputs.size())));
  }
  std::stable_sort(a.inputs.begin(), a.inputs.end(), [](const CrossCorrelation& x, const CrossCorrelation& y) {
    return std::abs(x.peak) / std::max(x.bound, 1e-12) > std::abs(y.peak) / std::max(y.bound, 1e-12);
  });
  if (a.inputs.size() > static_cast<std::size_t>(kCrossCorrelationsShown)) a.inputs.resize(kCrossCorrelationsShown);
  if (c < t.learned.size() && t.learned[c].size() == r.size()) {
    const std::vector<double>& l = t.learned[c];
    a.learned_rms = Rms(l);
    std::vector<double> r2(r.size()), l2(l.size());
    for (std::size_t i = 0; i < r.size(); ++i) r2[i] = r[i] * r[i], l2[i] = l[i] * l[i];
    const double mse = Mean(r2);
    const LongRunTest test = LongRunMeanTest(Gains(r2, l2), bandwidth);
    a.learned_reduction = mse > 0 ? test.mean / mse : 0.0;
    a.learned_p = test.p;
    // The band: where the learned correction (what it predicts of the residual) has
    // its power, the peak and the bins around it above a quarter of it.
    const std::vector<double> correction = Gains(r, l);
    const int segment = static_cast<int>(std::min<double>(1024, std::pow(2, std::floor(std::log2(std::max(8.0, r.size() / 8.0))))));
    std::vector<double> f, pc;
    WelchPsd(correction, t.rate, segment, &f, &pc);
    std::size_t peak = 0;
    for (std::size_t b = 1; b < pc.size(); ++b) {
      if (pc[b] > pc[peak] || peak == 0) peak = b;
    }
    if (peak > 0 && pc[peak] > 0) {
      std::size_t lo = peak, hi = peak;
      while (lo > 1 && pc[lo - 1] > 0.25 * pc[peak]) --lo;
      while (hi + 1 < pc.size() && pc[hi + 1] > 0.25 * pc[peak]) ++hi;
      a.band_low = f[lo];
      a.band_high = f[hi];
    }
  } else {
    a.learned_p = std::numeric_limits<double>::quiet_NaN();
  }
  return a;
}

// The gap of per-channel test residuals (row means of the channels' squares summed).
double ChannelGap(const DiagnosisProblem& problem, const std::vector<std::vector<double>>& channels) {
  if (channels.empty()) return std::numeric_limits<double>::quiet_NaN();  // nothing learned
  std::vector<double> rows(channels.front().size(), 0.0);
  for (const auto& c : channels) {
    for (std::size_t i = 0; i < rows.size() && i < c.size(); ++i) rows[i] += c[i] * c[i];
  }
  return problem.Gap(Mean(rows));
}

}  // namespace

void ReportSelection(const DiagnosisReportHeader& header, const DiagnosisProblem& problem,
                     const SelectionResult& selection, const DiagnosisOptions& options, DiagnosisReport* report) {
  report->robot = header.robot;
  report->model_name = header.model_name;
  report->metric = header.metric;
  report->block_seconds = header.block_seconds;
  report->held_out_share = options.held_out;
  report->logs = header.logs;
  report->guard_seconds = header.guard_seconds;
  report->alpha = options.alpha;
  report->min_improvement = options.min_improvement;
  report->max_effects = options.max_effects;
  report->floor_ratio = problem.FloorRatio();
  report->learned_floor = problem.LearnedFloor();
  report->gap_before = problem.Gap(Mean(selection.before.test));
  report->gap_after = problem.Gap(Mean(selection.after.test));
  report->selection_gap_before = problem.Gap(Mean(selection.before.selection));
  report->selection_gap_after = problem.Gap(Mean(selection.after.selection));
  report->fit_gap_before = problem.Gap(Mean(selection.before.fit));
  report->fit_gap_after = problem.Gap(Mean(selection.after.fit));
  report->fit_rows = static_cast<int>(selection.before.fit.size());
  report->selection_rows = static_cast<int>(selection.before.selection.size());
  report->test_rows = static_cast<int>(selection.before.test.size());
  report->held_out_rows = report->selection_rows + report->test_rows;
  report->candidates = selection.candidates;
  report->removed = selection.removed;
  const std::vector<std::map<std::string, double>> errors = StandardErrors(problem, selection.effects);
  for (std::size_t k = 0; k < selection.effects.size(); ++k) {
    const TrialEffect& e = selection.effects[k];
    report->effects.push_back({e.name, e.joint, e.parameters, errors[k], selection.gap_reductions[k], selection.evidence[k]});
  }

  // Adequacy of the repaired model, and the learned yardstick beside both models.
  report->adequacy.clear();
  report->yardstick = {};
  if (!options.check_adequacy) {
    report->yardstick.nominal = report->yardstick.repaired = report->yardstick.physics_share =
        std::numeric_limits<double>::quiet_NaN();
    return;
  }
  // With nothing added the repaired model is the nominal one: one check serves both.
  const TestResiduals nominal = problem.TestRowResiduals({}, true);
  const TestResiduals repaired = selection.effects.empty() ? nominal : problem.TestRowResiduals(selection.effects, true);
  std::vector<double> p;
  for (std::size_t c = 0; c < repaired.channels.size(); ++c) {
    report->adequacy.push_back(CheckChannel(repaired, c, problem.ChunkRows()));
    p.push_back(report->adequacy.back().learned_p);
  }
  // Unexplained: the learned correction removes a significant share (Holm over the
  // channels) of at least min_improvement, and at least LearnedFloor() noise in RMS.
  const std::vector<bool> significant = HolmReject(p, options.alpha);
  for (std::size_t c = 0; c < report->adequacy.size(); ++c) {
    ChannelAdequacy& a = report->adequacy[c];
    a.above_floor = a.noise > 0 && a.rms > problem.FloorRatio() * a.noise;
    a.learned_significant = significant[c] && a.learned_reduction >= options.min_improvement &&
                            a.rms - a.learned_rms >= problem.LearnedFloor() * a.noise;
    a.unexplained = a.learned_significant || a.above_floor;
  }
  LearnedYardstick& y = report->yardstick;
  y.learner = repaired.learner;
  y.available = !repaired.learned.empty();
  y.nominal = ChannelGap(problem, nominal.learned);
  y.repaired = ChannelGap(problem, repaired.learned);
  // A learned correction that predicts the test rows clearly worse than the nominal model
  // alone learned nothing it can stand for (on EMPS: 345.8 against 46.96): not trained.
  if (y.available && std::isfinite(y.nominal) && y.nominal > (1 + kYardstickTolerance) * report->gap_before) {
    y.available = false;
    y.learner += ", which predicts the test rows worse than the nominal model alone (" + FormatParameter(y.nominal) +
                 " against " + FormatParameter(report->gap_before) + "): counted as not trained";
  }
  double best = std::min(report->gap_before, report->gap_after);
  for (double g : {y.nominal, y.repaired}) {
    if (std::isfinite(g)) best = std::min(best, g);
  }
  const double predictable = report->gap_before * report->gap_before - best * best;
  y.physics_share = predictable > 0 && y.available
                        ? (report->gap_before * report->gap_before - report->gap_after * report->gap_after) / predictable
                        : std::numeric_limits<double>::quiet_NaN();
}

void ReportRefit(const DiagnosisProblem& given, const std::string& refitted, DiagnosisReport* report) {
  const SquaredResiduals r = given.Evaluate({});
  report->refit_gap = report->gap_before;
  report->gap_before = given.Gap(Mean(r.test));
  report->fit_gap_before = given.Gap(Mean(r.fit));
  report->selection_gap_before = given.Gap(Mean(r.selection));
  report->notes.push_back(refitted + " before effects were sought: test-row gap " + FormatParameter(report->gap_before) +
                          " -> " + FormatParameter(report->refit_gap) + ". 'Nominal' in the plots is the refitted model.");
}

}  // namespace twinsim

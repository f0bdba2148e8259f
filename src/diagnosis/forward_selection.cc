#include "diagnosis/forward_selection.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>

#include "core/parallel.h"

namespace twinsim {
namespace {

// A share of the squared residual removed on fit and held-out rows alike that counts
// as significant whatever the t statistic.
constexpr double kStrongReduction = 0.25;

struct Score {
  double reduction = 0;      // share of the held-out MSE removed
  double fit_reduction = 0;  // share of the fit rows' MSE removed
  double t = 0;
};

Score Compare(const SquaredResiduals& before, const SquaredResiduals& after, int chunk) {
  Score s;
  const double mse = Mean(before.held_out);
  if (mse <= 0 || before.held_out.size() != after.held_out.size()) return s;
  std::vector<double> gain(before.held_out.size());
  for (std::size_t i = 0; i < gain.size(); ++i) gain[i] = before.held_out[i] - after.held_out[i];
  s.reduction = Mean(gain) / mse;
  s.t = ChunkedTStatistic(gain, chunk);
  const double fit_mse = Mean(before.fit);
  if (fit_mse > 0) s.fit_reduction = (fit_mse - Mean(after.fit)) / fit_mse;
  return s;
}

std::string Percent(double share) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f %%", 100 * share);
  return buf;
}

// "it removed 64 % of the held-out squared error (t = 23), where coulomb_friction (joint 2)
// removed 41 % and viscous_friction (joint 2) 12 %".
std::string RoundEvidence(const std::vector<DiagnosisCandidate>& round, const DiagnosisCandidate& best) {
  std::vector<const DiagnosisCandidate*> others;
  for (const auto& c : round) {
    if (&c != &best && c.note.empty()) others.push_back(&c);
  }
  std::sort(others.begin(), others.end(),
            [](const DiagnosisCandidate* a, const DiagnosisCandidate* b) { return a->reduction > b->reduction; });
  char head[160];
  std::snprintf(head, sizeof head, "it removed %s of the held-out squared error (t = %.0f)",
                Percent(best.reduction).c_str(), best.t_statistic);
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

SelectionResult SelectEffects(const DiagnosisProblem& problem, const DiagnosisOptions& options,
                              const std::function<void(const std::string&)>& progress) {
  SelectionResult out;
  out.before = problem.Evaluate({});
  // Chunks at least as long as the nominal residual stays correlated: rows closer than
  // that are not independent evidence.
  const int chunk = std::max(problem.ChunkRows(), CorrelationLength(out.before.held_out, 20 * problem.ChunkRows()));
  SquaredResiduals current_residuals = out.before;
  std::vector<TrialEffect> current;
  for (int round = 1; round <= options.max_effects; ++round) {
    const std::vector<TrialEffect> candidates = problem.Candidates(current);
    if (candidates.empty()) break;
    if (progress) {
      progress("round " + std::to_string(round) + ": fitting " + std::to_string(candidates.size()) + " candidates");
    }
    std::vector<DiagnosisCandidate> tried(candidates.size());
    std::vector<double> fit_reduction(candidates.size(), 0.0);
    std::vector<std::vector<TrialEffect>> fitted(candidates.size());
    ParallelFor(static_cast<int>(candidates.size()), options.threads, [&](int i) {
      const auto k = static_cast<std::size_t>(i);
      DiagnosisCandidate& c = tried[k];
      c.round = round;
      c.name = candidates[k].name;
      c.joint = candidates[k].joint;
      std::vector<TrialEffect> trial = current;
      trial.push_back(candidates[k]);
      try {
        trial = problem.Fit(trial, {static_cast<int>(trial.size()) - 1});
        SquaredResiduals r = problem.Evaluate(trial);
        // Scored with the effects already added refitted too (as stepwise regression
        // re-estimates every coefficient): an effect added earlier may have absorbed
        // part of this one (a payload fitted alone takes up a torque offset's share),
        // and only the joint fit gives the candidate its due. Kept where it fits better.
        // Effects the problem holds while scoring (HeldWhileScoring) keep their fit; a
        // candidate that removes nothing on its own is not refitted jointly (it would
        // rarely pass, and the joint fits are most of a round's time).
        Score s = Compare(current_residuals, r, chunk);
        std::vector<int> refit;
        for (std::size_t m = 0; m < trial.size(); ++m) {
          if (m + 1 == trial.size() || !problem.HeldWhileScoring(trial[m])) refit.push_back(static_cast<int>(m));
        }
        if (s.reduction > 0 && refit.size() > 1) {
          try {
            std::vector<TrialEffect> joint = problem.Fit(trial, refit);
            SquaredResiduals rj = problem.Evaluate(joint);
            if (Mean(rj.fit) < Mean(r.fit)) {
              trial = std::move(joint), r = std::move(rj);
              s = Compare(current_residuals, r, chunk);
            }
          } catch (const std::exception&) {
            // the joint refit failed: the one-at-a-time fit stands
          }
        }
        c.parameters = trial.back().parameters;
        c.fit_gap = problem.Gap(Mean(r.fit));
        c.held_out_gap = problem.Gap(Mean(r.held_out));
        c.reduction = s.reduction;
        c.t_statistic = s.t;
        fit_reduction[k] = s.fit_reduction;
        fitted[k] = std::move(trial);
      } catch (const std::exception& e) {
        c.note = e.what();
        c.reduction = -std::numeric_limits<double>::infinity();
      }
    });
    // Significant by the t test, or so large on both the fit and the held-out rows that
    // chance is out of the question even where the effect shows only in a few events
    // (a speed limit reached now and then leaves most chunks unchanged: t stays small).
    auto passes_test = [&](std::size_t k) {
      const DiagnosisCandidate& c = tried[k];
      const bool strong = c.reduction >= kStrongReduction && fit_reduction[k] >= kStrongReduction && c.t_statistic > 0;
      return c.note.empty() && c.reduction >= options.min_improvement &&
             (c.t_statistic >= options.significance || strong);
    };
    // The largest held-out reduction among the candidates that pass (one that fails the
    // test must not hide another that passes); ties go to the earlier candidate.
    std::size_t best = tried.size();
    for (std::size_t k = 0; k < tried.size(); ++k) {
      if (passes_test(k) && (best == tried.size() || tried[k].reduction > tried[best].reduction)) best = k;
    }
    const bool passes = best < tried.size();
    if (passes) {
      DiagnosisCandidate& winner = tried[best];
      winner.selected = true;
      const std::string evidence = RoundEvidence(tried, winner);
      std::vector<TrialEffect> next = fitted[best];
      std::vector<int> all(next.size());
      for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
      // Refit every added effect together, a single one too (one more refinement from
      // where it stands): the next round's candidates, scored with a joint refit, must
      // not be credited with what more refinement of these alone would have found.
      try {
        next = problem.Fit(next, all);
      } catch (const std::exception&) {
        next = fitted[best];  // the joint refit failed: keep the one-at-a-time fit
      }
      const SquaredResiduals r = problem.Evaluate(next);
      const double gap_before = problem.Gap(Mean(current_residuals.held_out));
      const double gap_after = problem.Gap(Mean(r.held_out));
      current = next;
      current_residuals = r;
      out.gap_reductions.push_back(gap_before > 0 ? (gap_before - gap_after) / gap_before : 0.0);
      std::string signature = problem.Signature(current.back());
      out.evidence.push_back(EffectLabel(winner.name, winner.joint) + ": " + evidence +
                             (signature.empty() ? "" : "; " + signature) + ".");
    }
    out.candidates.insert(out.candidates.end(), tried.begin(), tried.end());
    if (!passes) break;
  }
  out.effects = current;
  out.after = current_residuals;
  return out;
}

void ReportSelection(const DiagnosisProblem& problem, const SelectionResult& selection, DiagnosisReport* report) {
  report->gap_before = problem.Gap(Mean(selection.before.held_out));
  report->gap_after = problem.Gap(Mean(selection.after.held_out));
  report->fit_gap_before = problem.Gap(Mean(selection.before.fit));
  report->fit_gap_after = problem.Gap(Mean(selection.after.fit));
  report->fit_rows = static_cast<int>(selection.before.fit.size());
  report->held_out_rows = static_cast<int>(selection.before.held_out.size());
  report->candidates = selection.candidates;
  for (std::size_t k = 0; k < selection.effects.size(); ++k) {
    const TrialEffect& e = selection.effects[k];
    report->effects.push_back({e.name, e.joint, e.parameters, selection.gap_reductions[k], selection.evidence[k]});
  }
}

void ReportRefit(const DiagnosisProblem& given, const std::string& refitted, DiagnosisReport* report) {
  const SquaredResiduals r = given.Evaluate({});
  report->refit_gap = report->gap_before;
  report->gap_before = given.Gap(Mean(r.held_out));
  report->fit_gap_before = given.Gap(Mean(r.fit));
  report->notes.push_back(refitted + " before effects were sought: held-out gap " + FormatParameter(report->gap_before) +
                          " -> " + FormatParameter(report->refit_gap) + ". 'Nominal' in the plots is the refitted model.");
}

}  // namespace twinsim

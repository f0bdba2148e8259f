// Forward selection of missing effects, the same for both robots (docs/diagnose.md).
//
// A DiagnosisProblem knows one robot's model and logs: it evaluates the model plus a
// set of effects into squared residuals on the fit rows and on the held-out rows,
// lists the candidate effects, and fits their parameters on the fit rows. Selection
// then runs rounds:
//   1. every candidate not yet added is fitted with the added ones held, and scored on
//      the held-out rows by how much of the held-out mean squared error it removes and
//      how significant that is (ChunkedTStatistic over chunks of correlated rows);
//   2. the best is added when it passes both thresholds of DiagnosisOptions, and all
//      added effects are refitted together;
//   3. until none passes or max_effects are in.
// The candidates of a round are fitted in parallel (ParallelFor); the result does not
// depend on the thread count.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include "diagnosis/diagnosis.h"

namespace twinsim {

// An effect with parameters, as the problems exchange them (joint 0-based, -1: robot).
struct TrialEffect {
  std::string name;
  int joint = -1;
  std::map<std::string, double> parameters;
};

// Squared residuals per row, each row's channels summed, in time order.
struct SquaredResiduals {
  std::vector<double> fit;
  std::vector<double> held_out;
};

class DiagnosisProblem {
 public:
  virtual ~DiagnosisProblem() = default;
  // The metric of a mean squared residual per row (e.g. its square root per channel).
  virtual double Gap(double mean_squared) const = 0;
  // The nominal model plus `effects`, evaluated.
  virtual SquaredResiduals Evaluate(const std::vector<TrialEffect>& effects) const = 0;
  // The effects that may be added to `current`, parameters unset.
  virtual std::vector<TrialEffect> Candidates(const std::vector<TrialEffect>& current) const = 0;
  // `effects` with the parameters of those at `free` (indices) fitted on the fit rows,
  // the others held. Throws CheckFailed when a fit fails; the candidate is then
  // reported with the message.
  virtual std::vector<TrialEffect> Fit(std::vector<TrialEffect> effects, const std::vector<int>& free) const = 0;
  // The fewest held-out rows per chunk of the significance test (longer where the
  // residual stays correlated longer).
  virtual int ChunkRows() const = 0;
  // A clause of evidence particular to this effect (its signature in the data), or "".
  virtual std::string Signature(const TrialEffect& effect) const { return ""; }
  // True when `effect`, already added, keeps its fit while the next candidates are
  // scored (the others are refitted with each candidate).
  virtual bool HeldWhileScoring(const TrialEffect& effect) const { return false; }
};

struct SelectionResult {
  std::vector<TrialEffect> effects;           // added, in order, after the final refit
  std::vector<double> gap_reductions;         // per added effect: share of the held-out gap it removed
  std::vector<std::string> evidence;          // per added effect
  std::vector<DiagnosisCandidate> candidates; // every candidate of every round
  SquaredResiduals before, after;
};

// Runs forward selection. `progress` (may be empty) hears each round's start.
SelectionResult SelectEffects(const DiagnosisProblem& problem, const DiagnosisOptions& options,
                              const std::function<void(const std::string&)>& progress = {});

// Fills the report's gaps (held-out and fit, before and after), row counts, candidates
// and effects (joint as the problem gave it) from a selection.
void ReportSelection(const DiagnosisProblem& problem, const SelectionResult& selection, DiagnosisReport* report);

// With --refit-model: the report's gap before becomes the given model's (`given`, the
// problem over the model as the user gave it) and refit_gap the refitted model's; a note
// says what `refitted` ("The model's ... were refitted on the fit blocks (...)") did and
// how far it took the gap.
void ReportRefit(const DiagnosisProblem& given, const std::string& refitted, DiagnosisReport* report);

// The mean of v (0 when empty).
double Mean(const std::vector<double>& v);

}  // namespace twinsim

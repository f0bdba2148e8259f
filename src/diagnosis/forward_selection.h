// Forward selection of missing effects, the same for both robots (docs/diagnose.md).
//
// A DiagnosisProblem knows one robot's model and logs: it evaluates the model plus a
// set of effects into squared residuals on the fit, selection and test rows, lists the
// candidate effects, and fits their parameters on the fit rows. Selection then runs
// rounds:
//   1. every candidate not yet added is fitted with the added ones, and scored on the
//      selection rows: the share of their mean squared error it removes, a one-sided t
//      test of that reduction with a long-run (Newey-West) standard error, and an
//      information criterion that counts its parameters;
//   2. the candidates significant after Holm's correction over the round, removing at
//      least min_improvement, earning their parameters, and making no joint or axis
//      significantly worse, compete on the criterion (a candidate the problem also
//      tests on its state, StateTest, may pass by that test: then the selection rows
//      must only not get worse);
//      the best is added and all added effects refitted together;
//   3. a backward step takes out an effect added earlier that no longer earns its place;
//   4. until none passes or max_effects are in.
// The test rows choose nothing: they give the reported gaps. The candidates of a round
// are fitted in parallel (ParallelFor); the result does not depend on the thread count.
#pragma once

#include <functional>
#include <limits>
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
  std::vector<double> selection;
  std::vector<double> test;
  std::vector<std::vector<double>> selection_by_channel;  // channel x selection row, unsummed
  std::vector<std::vector<double>> fit_by_channel;        // channel x fit row, unsummed (may be empty)
  // Per selection row, the block it lies in (numbered over every log; rows of one block
  // share it): the 25 % rule asks most blocks an effect changes to improve. Empty: one
  // block per row.
  std::vector<int> selection_block;
};

// The test rows of one model, per channel, for the adequacy checks (diagnosis.h,
// ChannelAdequacy) and the learned yardstick.
struct TestResiduals {
  std::vector<std::string> channels;           // "joint 1", "forward", ...
  std::vector<double> noise;                   // per channel, the noise floor's share
  std::vector<std::vector<double>> residual;   // channel x test row, time order
  std::vector<std::vector<double>> learned;    // the same, corrected by the learned residual (may be empty)
  std::vector<std::string> input_names;        // what the residual may correlate with
  std::vector<std::vector<double>> inputs;     // input x test row
  int step = 1;         // rows between the samples the whiteness tests use (a filter's span, a prediction's overlap)
  double rate = 1;      // rows per second
  std::string learner;  // what the learned residual is, in words
};

// Evidence for a candidate that needs no fit (DiagnosisProblem::StateTest).
struct StateEvidence {
  double p = std::numeric_limits<double>::quiet_NaN();  // two-sided; NaN: no such test
  std::string what;  // the finding in words, with its numbers
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
  // The fewest rows of the long-run variance's bandwidth (longer where the residual
  // stays correlated longer).
  virtual int ChunkRows() const = 0;
  // The fit rows' residual components, concatenated (a fixed length for one log set):
  // what the fit minimises. `components` residuals per row.
  virtual std::vector<double> FitResiduals(const std::vector<TrialEffect>& effects) const = 0;
  virtual int ResidualComponents() const { return 1; }
  // The relative step of the numeric derivatives of FitResiduals for standard errors.
  virtual double RelativeStep() const { return 1e-3; }
  // How far above its noise floor a channel's test RMS may stand and still be noise:
  // beyond it the channel is unexplained whatever the learned residual says (the floor
  // is an estimate; for arms a lower bound).
  virtual double FloorRatio() const = 0;
  // How much a learned residual must lower a channel's test RMS, in units of its noise
  // floor, to count: what the problem's own processing leaves that is predictable but
  // not physics (0: any significant drop counts).
  virtual double LearnedFloor() const { return 0; }
  // The test rows of the model with `effects`; with `learn`, also corrected by a
  // learned residual predictor trained on the fit rows.
  virtual TestResiduals TestRowResiduals(const std::vector<TrialEffect>& effects, bool learn) const = 0;
  // A clause of evidence particular to this effect (its signature in the data), or "".
  virtual std::string Signature(const TrialEffect& effect) const { return ""; }
  // True when `effect`, already added, keeps its fit while the next candidates are
  // scored (the others are refitted with each candidate).
  virtual bool HeldWhileScoring(const TrialEffect& effect) const { return false; }
  // The one channel `effect` acts on, where it is scored (its share of that channel's
  // squared residual, its parameters against that channel's rows) wherever no other
  // channel's residual moved with it (a refit beside a payload moves them all: then the
  // sum); -1 where it acts on several, scored on their sum. An arm joint's effect changes
  // that joint's torque alone: scored on the sum, a wrist's delay that removes a third of
  // the wrist's error is 1 % of an error the shoulder's noise dominates (issue 41).
  virtual int ChannelOf(const TrialEffect& effect) const { return -1; }
  // The parameters of `effect` the logs must determine for it to be added (its standard
  // error under its value; none where empty): an effect whose fit the data does not pin down
  // stands for something else (a torque limit under most commands fits a model that
  // needs too little torque on its joint; issue 41, the KUKA's joint 5).
  virtual std::vector<std::string> MustBeDetermined(const TrialEffect& effect) const { return {}; }
  // A test of `candidate` (as fitted) on the rows before the test rows that fits nothing: for an
  // effect whose trace a state estimate absorbs within frames (the omni observer learns a
  // drift's turn, so the predictions from it hardly show the drift), the estimate's own
  // dependence on what drives the effect, with the model as `current` makes it. Its p
  // stands beside the selection rows' (Bonferroni over the two); where it carries the
  // candidate, the selection rows must still not get worse and the effect's fitted
  // change must have the estimate's sign. NaN p: none for it.
  virtual StateEvidence StateTest(const TrialEffect& candidate, const std::vector<TrialEffect>& current) const {
    return {};
  }
  // True for a parameter of `effect` that follows from the others (a flag, or a damping
  // set from a stiffness): it gets no standard error and is not varied for them.
  virtual bool Derived(const TrialEffect& effect, const std::string& key) const { return false; }
};

struct SelectionResult {
  std::vector<TrialEffect> effects;           // added, in order, after the final refit
  // per effect kept: its share of the test rows' gap on top of those before it, with the
  // parameters all end with (the product of 1 - share is gap after / gap before)
  std::vector<double> gap_reductions;
  std::vector<std::string> evidence;          // per added effect
  std::vector<DiagnosisCandidate> candidates; // every candidate of every round
  SquaredResiduals before, after;
  std::vector<std::string> removed;           // the backward step's removals, with why
};

// Runs forward selection. `progress` (may be empty) hears each round's start.
SelectionResult SelectEffects(const DiagnosisProblem& problem, const DiagnosisOptions& options,
                              const std::function<void(const std::string&)>& progress = {});

// What a report says of itself: the robot ("arm" or "omni"), the model, the metric, the
// held-out blocks and the logs.
struct DiagnosisReportHeader {
  std::string robot;
  std::string model_name;
  std::string metric;
  double block_seconds = 0;
  double guard_seconds = 0;
  std::vector<std::string> logs;
};

// Fills the report's header (`header`, the held-out share from `options`), its gaps
// (test, selection and fit rows, before and after), row counts, candidates, effects with
// their standard errors, the adequacy of the repaired model and the learned yardstick,
// from a selection.
void ReportSelection(const DiagnosisReportHeader& header, const DiagnosisProblem& problem,
                     const SelectionResult& selection, const DiagnosisOptions& options, DiagnosisReport* report);

// One standard error per parameter of each effect: the covariance of the fit
// (Gauss-Newton, from numeric derivatives of FitResiduals), scaled by the residual's
// variance and its correlation length. NaN where the parameter is not determined.
std::vector<std::map<std::string, double>> StandardErrors(const DiagnosisProblem& problem,
                                                          const std::vector<TrialEffect>& effects);

// With --refit-model: the report's gap before becomes the given model's (`given`, the
// problem over the model as the user gave it) and refit_gap the refitted model's; a note
// says what `refitted` ("The model's ... were refitted on the fit blocks (...)") did and
// how far it took the gap.
void ReportRefit(const DiagnosisProblem& given, const std::string& refitted, DiagnosisReport* report);

// The mean of v (0 when empty).
double Mean(const std::vector<double>& v);

}  // namespace twinsim

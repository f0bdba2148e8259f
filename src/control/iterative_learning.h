// Iterative learning control (ILC) of an arm (seed 001, Bukkems et al., sections V and
// VII-B): the arm runs the same reference from the same initial state trial after
// trial; between trials, offline, a feedforward torque f is learned per joint from the
// last trial's tracking error e = q_ref - q and added to the controller's output in the
// next trial (TrackingOptions::feedforward):
//
//   f_{k+1} = Q (f_k + alpha L e_k),   f_0 = 0,
//
// with L the learning filter, ideally the inverse of the process sensitivity PS (the
// closed-loop response from f to q, control/closed_loop_frf.h), so that one
// trial would remove the whole repeating error, and Q a zero-phase Butterworth low-pass
// (FiltFilt, signal/butterworth.h, magnitude |H|^2) that stops learning where L is
// wrong. In the frequency domain e_{k+1} = Q (1 - alpha PS L) e_k + (1 - Q) e_0-terms:
// the learning converges where |Q|^2 |1 - alpha PS L| < 1 (ConvergenceFactor).
//
// The learning filter is non-causal (it runs offline on a whole trial) and has the
// structure of a rigid joint's inverse PS under PD feedback with a command delay (and,
// for a model of order 4, a snap term for a series spring; LearningFilter):
//
//   L(z) = (a2 z^tau + a2' z^(tau+1)) (z - 2 + z^-1) / Ts^2 + a1 (z - z^-1) / (2 Ts) + a0,
//
// an inertia a2 + a2' (kg m^2) acting tau to tau + 1 samples early (the command delay
// plus the half sample by which a torque held over a sample acts late: the exact
// sampled inverse has (z^D (z - 1)^2 / Ts^2) 2z / (z + 1), and 2z / (z + 1) ~ (1 + z) / 2
// to second order in w Ts, so a2 = a2' = J/2, tau = D), a damping a1 and a stiffness a0
// (the feedback's D through a central difference, for the same reason, and its P).
// FitPlantLearningFilter takes a1, a0 from the known feedback and fits the plant's
// inertia (and snap) for each tau by output error to the nominal response, keeping the
// best tau; FitLearningFilter (the earlier equation-error fit) fits all four over every
// posture; ModelLearningFilter takes them a priori from the controller's model and gains.
//
//   ClosedLoopFrf frf = MeasureProcessSensitivity(plant, hat, postures, tracking, {});
//   std::vector<LearningFilter> l;
//   for (int j = 0; j < 3; ++j) {
//     const LearningFilter feedback = ModelLearningFilter(hat, tracking, postures[0], q_start, j);
//     l.push_back(FitPlantLearningFilter(frf, j, feedback, hat.joints[j].viscous, PlantFitOptions{}));
//   }
//   IlcResult r = RunIlc(plant, hat, reference, tracking, l, IlcOptions{});
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <complex>
#include <functional>
#include <string>
#include <vector>

#include "control/closed_loop_frf.h"
#include "control/computed_torque.h"
#include "control/writing_task.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// L(z) = (inertia z^shift + inertia_early z^(shift+1)) (z - 2 + 1/z) / Ts^2
//        + snap (z^shift + z^(shift+1)) / 2 (z - 2 + 1/z)^2 / Ts^4
//        + damping (z - 1/z) / (2 Ts) + stiffness.
// The snap term is the fourth-order model's (PlantFitOptions::order 4): neglecting the
// spring's damping, the inverse of a joint whose drive is a series spring k between
// motor and link inertias J_m and J_l, measured at the link, is
// (J_m + J_l) s^2 + (J_m J_l / k) s^4 (docs/ilc.md).
struct LearningFilter {
  int shift = 0;             // samples the inertia term acts early (tau)
  double inertia = 0;        // kg m^2 (kg for a prismatic joint): a2, at z^tau
  double inertia_early = 0;  // kg m^2: a2', at z^(tau+1)
  double snap = 0;           // kg m^2 s^2: a4, centred at z^(tau+1/2) (0 for the rigid model)
  double damping = 0;        // N·m·s/rad: a1
  double stiffness = 0;   // N·m/rad: a0
  double residual = 0;    // RMS |PS L - 1| over the fitted lines (0 when not fitted)
  int order = 2;          // the plant model's order: 2 (rigid) or 4 (with a series spring)
  int lines = 0;          // lines the fit used (0 when not fitted)
  double band_min = 0, band_max = 0;  // Hz, the lowest and highest of them

  // L(e^{j 2 pi f Ts}) (N·m/rad) at `frequency_hz`.
  std::complex<double> Response(double frequency_hz, double sample_time) const;
  // L applied to a whole trial's error e (N samples, rad), non-causally; beyond the ends
  // e holds its first and last value. Returns N samples, N·m.
  Eigen::VectorXd Apply(const Eigen::VectorXd& e, double sample_time) const;
  // Apply as an n x n matrix (the same clamping at the ends).
  Eigen::SparseMatrix<double> Matrix(Eigen::Index n, double sample_time) const;
  // "tau 1 samples, inertia 0.51 kg m^2, damping 64 N m s/rad, stiffness 2e3 N m/rad".
  std::string Summary() const;
};

// Fits joint `joint`'s learning filter to the measured process sensitivity over the
// lines in [f_min, f_max] (Hz) at every posture, trying shifts 0..max_shift and keeping
// the one with the smallest residual. Throws InputError for max_shift < 0 or fewer
// than 2 lines in the band, std::invalid_argument for a joint that does not exist.
LearningFilter FitLearningFilter(const ClosedLoopFrf& frf, int joint, double f_min, double f_max, int max_shift);

// How FitPlantLearningFilter fits the plant (the scene's `ilc.frf` keys fit_band,
// max_shift, coherence, model_order).
struct PlantFitOptions {
  double f_min = 2, f_max = 80;  // Hz, the band fitted
  int max_shift = 5;             // samples, the largest delay tau tried
  double min_coherence = 0.9;    // lines below it at any posture are not fitted
  // 2: rigid (inertia and delay); 4: adds the snap term of a series spring between
  // motor and link, for a drive whose resonance lies near the learning band.
  int order = 2;

  // True when usable; else says why in *why.
  bool IsValid(std::string* why) const;
};

// The learning filter as the inverse of the process sensitivity put together from its
// two parts, PS^-1 = P^-1 + C (seed 001, section VII-B; docs/ilc.md):
//  - C, the feedback the controller applies, is known exactly: `feedback`'s damping and
//    stiffness (ModelLearningFilter's gains), to which the controller model's viscous
//    friction `viscous` is added as the plant's known damping;
//  - the plant's inertia and delay, what the controller's model may have wrong (a
//    payload, an unmodelled inertia, a lag), and at order 4 its series spring's snap
//    term, are fitted to joint `joint`'s nominal response (the average over the
//    postures, eq. 23) by output-error least squares, sum |PS_nom - 1/L|^2 over the
//    lines in [f_min, f_max] whose coherence is at least `min_coherence` at every
//    posture, by Sanathanan-Koerner iterations (a linear least-squares problem weighted
//    by the last iterate's 1/|L|^2), for each shift 0..max_shift, keeping the one with
//    the smallest residual. Every fitted coefficient is kept >= 0 (inertias and
//    J_m J_l / k cannot be negative).
// The damping is not fitted: measured at rest, a joint's Coulomb friction reverses with
// every swing of the multisine and acts as damping that the task, in motion, does not
// have (the elbow of models/rrr_plant.yaml: 11.4 N m s/rad fitted against 5.8 in
// motion), and an L with that damping has PS L ~ 2 at the closed loop's natural
// frequency, where learning at gain 1 then stalls (docs/ilc.md gives the evidence).
// Throws InputError for options that are not IsValid, a band with fewer coherent lines
// than 2 or than the coefficients fitted; std::invalid_argument for a joint that does not exist.
LearningFilter FitPlantLearningFilter(const ClosedLoopFrf& frf, int joint, const LearningFilter& feedback,
                                      double viscous, const PlantFitOptions& options);

// The learning filter the controller's model predicts for joint `joint` at posture q:
// inertia M_hat_jj(q) split evenly over shifts delay_samples and delay_samples + 1, and the feedback gains of
// `tracking` (PD + feedforward: Kp', Kd' at the reference's start q_start; computed
// torque: M_hat_jj(q) Kp, M_hat_jj(q) Kd). Throws std::invalid_argument for bad sizes.
LearningFilter ModelLearningFilter(const ArmModel& hat, const TrackingOptions& tracking, const Eigen::VectorXd& q,
                                   const Eigen::VectorXd& q_start, int joint);

// The watch over the trials that a user on a real arm expects (docs/ilc.md, "Staying
// converged"): after every trial each joint's RMS error is compared with its best so
// far. When it stands above `growth` times that best for `patience` trials in a row
// (one bump of a transient is not yet growth), learning on the joint has gone
// past what its filters get right (measured: Coulomb and Stribeck friction at the
// reversals, which the frequency responses, measured well above the friction, do not
// show): the joint's feedforward goes back to the one of its best trial and its Q
// cutoff is multiplied by `cutoff_factor` (with no Q, q_order 0, it stops learning).
// After `lowerings` such steps, or below `min_cutoff`, the joint stops learning and
// keeps its best feedforward; if a stopped joint's error then grows the same way (the
// others move it through the coupling), every joint goes back to the feedforward of the
// best trial (IlcResult::best_trial) and learning ends: a lower Q filters the whole feedforward learned so far,
// and each lowering costs a jump in the error (measured: 45 times on the shoulder with
// three times the payload after a third lowering).
//
struct IlcSafeguard {
  double growth = 1.1;         // > 1; 0 = no watch
  double cutoff_factor = 0.7;  // in (0, 1)
  double min_cutoff = 2;       // Hz, > 0
  int patience = 2;            // >= 1
  int lowerings = 1;           // >= 0
};

// One action of the safeguard.
struct IlcSafeguardEvent {
  int trial = 0;            // the trial whose error grew
  int joint = 0;            // 0-based
  double rms = 0;           // rad or m: its RMS error there
  double best_rms = 0;      // rad or m: its best before
  int best_trial = 0;       // the trial whose feedforward it went back to
  double cutoff = 0;        // Hz, Q's new cutoff; 0 when the joint stopped learning
  // "lower_q", "stop_joint" (the joint keeps its best trial's feedforward), or
  // "stop_all": a joint that had stopped grew again through the others, and every joint
  // went back to the best trial's feedforward (best_trial is then that trial).
  std::string action;
};

// The safeguard's state machine, trial by trial (RunIlc's watch; IlcSafeguard above):
// per joint the best RMS error so far, the trial and the feedforward that gave it, the
// trials in a row above `growth` times it, Q's cutoff now and whether the joint still
// learns; for the arm the best trial (the lowest worst-joint error relative to trial 0)
// and its feedforward, and whether learning ended.
//
//   IlcSafeguardWatch watch(options.safeguard, options.q_order, cutoffs);
//   for each trial k run with feedforward f:
//     events = watch.Observe(k, run.error_rms, f);
//     f = watch.stopped() ? watch.best_feedforward() : watch.Next(IlcUpdate(f, ...watch.cutoffs()...));
class IlcSafeguardWatch {
 public:
  // `cutoffs`: Q's cutoff per joint (Hz) at the start.
  IlcSafeguardWatch(const IlcSafeguard& safeguard, int q_order, std::vector<double> cutoffs);

  // Records trial `trial`'s RMS error per joint, run with feedforward `f` (N x dof), and
  // returns what the safeguard decided on it (in joint order; after a stop_all no more).
  std::vector<IlcSafeguardEvent> Observe(int trial, const Eigen::VectorXd& error_rms, const Eigen::MatrixXd& f);

  // The feedforward to run next (or, after the last trial, to hand on) from `updated`,
  // the learned update or the last trial's own: joints that backed off on the last
  // Observe or no longer learn take their best trial's columns; after a stop_all, every
  // joint the best trial's feedforward.
  Eigen::MatrixXd Next(const Eigen::MatrixXd& updated) const;

  const std::vector<double>& cutoffs() const { return cutoffs_; }  // Hz, Q's cutoff per joint now
  bool learning(int joint) const { return learning_[static_cast<std::size_t>(joint)]; }
  bool stopped() const { return stopped_; }  // stop_all happened: learning ended
  int best_trial() const { return best_trial_; }
  const Eigen::MatrixXd& best_feedforward() const { return best_feedforward_; }

 private:
  IlcSafeguard safeguard_;
  int q_order_;
  std::vector<double> cutoffs_;
  Eigen::VectorXd first_rms_, best_rms_;  // trial 0's and each joint's best RMS
  std::vector<int> best_trial_of_;        // per joint
  Eigen::MatrixXd best_f_;                // per joint, the column of its best trial
  std::vector<bool> learning_, back_off_;
  std::vector<int> above_, lowered_;      // trials in a row above growth x best; Q's lowerings so far
  double best_relative_;
  int best_trial_ = 0;
  Eigen::MatrixXd best_feedforward_;
  bool stopped_ = false;
};

// The norm-optimal update (Amann, Owens and Rogers 1996) with the learning filter's
// model of the plant, P = L^-1: the feedforward step that minimises
// |e_{k+1}|^2 + w |f_{k+1} - f_k|^2 for that model over the whole trial,
//   f_{k+1} - f_k = (P^T P + w I)^-1 P^T e_k = (I + w L L^T)^-1 L e_k,
// a banded system solved by sparse LDL^T. In frequency, the step is L / (1 + w |L|^2):
// for the model the error falls by w|L|^2 / (1 + w|L|^2) < 1 every trial at every
// frequency, quickly where |L| is small (low frequencies) and ever more slowly above the
// frequency where w |L|^2 = 1. NormOptimalWeight sets that frequency.
Eigen::VectorXd NormOptimalStep(const LearningFilter& filter, double weight, const Eigen::VectorXd& e,
                                double sample_time);
// w = 1 / |L(bandwidth)|^2: learning at half speed at `bandwidth_hz`.
double NormOptimalWeight(const LearningFilter& filter, double bandwidth_hz, double sample_time);

struct IlcOptions {
  int trials = 10;        // learning trials after trial 0 (which runs without learning)
  // "standard": f + gain L e (seed 001); "norm_optimal": f + gain (I + w L L^T)^-1 L e
  // (NormOptimalStep), w from norm_optimal_bandwidth (Hz; 0 = each joint's Q cutoff).
  // Q filters the result in both.
  std::string update = "standard";
  double norm_optimal_bandwidth = 0;
  // How AutoQCutoff checks a cutoff: "lines", |Q|^2 |1 - gain PS_i S| < 1 at every
  // measured line and posture (seed 001); "robust", also RobustConvergenceFactor < 1 on
  // a 0.25 Hz grid to Nyquist.
  std::string q_criterion = "lines";
  double gain = 1;        // alpha
  int q_order = 4;        // the robustness filter's Butterworth order; 0 = no filter Q
  double q_cutoff = 40;   // Hz, its -3 dB frequency per pass (-6 dB after FiltFilt)
  // Hz, one per joint (AutoQCutoff's), used instead of q_cutoff when given.
  std::vector<double> q_cutoffs;
  IlcSafeguard safeguard;

  // Joint `joint`'s cutoff: q_cutoffs[joint] when given, else q_cutoff.
  double Cutoff(int joint) const;
  // Where joint `joint`'s norm-optimal step learns at half speed (Hz):
  // norm_optimal_bandwidth when given, else Cutoff(joint).
  double NormOptimalBandwidth(int joint) const {
    return norm_optimal_bandwidth > 0 ? norm_optimal_bandwidth : Cutoff(joint);
  }

  // True when usable for sample time `sample_time` (s); else says why in *why.
  bool IsValid(double sample_time, std::string* why) const;
};

// The highest cutoff (Hz) of Q for joint `joint`, on a 0.5 Hz grid from the lowest to
// the highest measured line, at which the convergence criterion |Q|^2 |1 - gain PS_i L|
// < 1 holds at every measured line for every posture i (seed 001: the cutoffs 18, 25 and
// 27 Hz of its arm); *worst (if given) gets the largest factor left there, so that
// 1 - *worst is the margin. Above the measured band nothing is known, so the cutoff
// never exceeds half its highest line (where Q is down by 12 dB per order). Throws InputError when no cutoff on the grid
// satisfies the criterion (q_order 0 included: then L itself fails it), or for invalid
// options.
double AutoQCutoff(const ClosedLoopFrf& frf, int joint, const LearningFilter& filter, const IlcOptions& options,
                   double* worst = nullptr);

// What one update's learning step does at `frequency_hz` (before gain and Q): L for the
// standard update, L / (1 + w |L|^2) for the norm-optimal one.
std::complex<double> LearningStepResponse(const LearningFilter& filter, const IlcOptions& options, int joint,
                                          double frequency_hz, double sample_time);

// |Q(f)|^2 |1 - gain PS(f) S(f)| at every line of `frf` for joint `joint`, S the learning
// step (LearningStepResponse), the worst over the postures: < 1 where learning converges. Throws InputError for invalid options,
// std::invalid_argument for a joint that does not exist.
Eigen::VectorXd ConvergenceFactor(const ClosedLoopFrf& frf, int joint, const LearningFilter& filter,
                                  const IlcOptions& options);

// The convergence criterion on a dense grid to Nyquist with a margin from the postures'
// spread (a robust Q, not the edge of the criterion): at each frequency f from the first
// line up by step_hz, each posture's PS interpolated between the measured lines (above
// the last line, the last line's PS L held, i.e. the fitted model's shape), their
// average PS_nom and their spread d(f) = max_i |PS_i - PS_nom| / |PS_nom|, and
//   |Q|^2 (|1 - gain PS_nom S| + gain |PS_nom S| d),
// which bounds |Q|^2 |1 - gain PS S| for every PS within d of the nominal (a
// multiplicative uncertainty disc), the measured postures and those between them.
struct RobustCriterion {
  std::vector<double> frequency, spread, factor;  // Hz; d; the bound
};
RobustCriterion RobustConvergenceFactor(const ClosedLoopFrf& frf, int joint, const LearningFilter& filter,
                                        const IlcOptions& options, double step_hz);
inline constexpr double kRobustGridHz = 0.25;  // the grid AutoQCutoff's robust criterion uses

// The lowest measured frequency (Hz) at which |1 - gain PS L| reaches 1 at some posture,
// without Q: learning above it must be cut off. Infinity when it stays below 1.
double LearningLimitFrequency(const ClosedLoopFrf& frf, int joint, const LearningFilter& filter, double gain);

// One ILC update for all joints: Q(f + gain L e) column by column (f, e: N x dof).
// Throws InputError for invalid options, std::invalid_argument for mismatched sizes or
// filters.
Eigen::MatrixXd IlcUpdate(const Eigen::MatrixXd& f, const Eigen::MatrixXd& e, const std::vector<LearningFilter>& filters,
                          const IlcOptions& options, double sample_time);

struct IlcResult {
  std::vector<Eigen::VectorXd> error_rms, error_max;  // per trial 0..trials, dof each, rad or m
  TrackingTrial first, last;                          // trial 0 and the last trial
  // N x dof, N·m: f of the last trial, with what the safeguard decided on that trial
  // applied (a joint that backed off then hands on its best trial's columns)
  Eigen::MatrixXd feedforward;
  // The trial with the lowest worst-joint error relative to trial 0 (max_j RMS_j(k) /
  // RMS_j(0)) and its feedforward: what a user keeps.
  int best_trial = 0;
  Eigen::MatrixXd best_feedforward;                   // N x dof, N·m
  std::vector<IlcSafeguardEvent> safeguard;           // what the safeguard did, in order
  Eigen::VectorXd final_cutoffs;                      // dof, Hz: Q's cutoff per joint at the end (0: stopped)
  double wall_seconds = 0;                            // s, all trials with their updates

  // max_j RMS of trial `trial` (rad or m).
  double WorstRms(int trial) const { return error_rms[static_cast<std::size_t>(trial)].maxCoeff(); }
  // WorstRms(0) / WorstRms(last).
  double Reduction() const { return WorstRms(0) / WorstRms(static_cast<int>(error_rms.size()) - 1); }
  // True when the last trial's worst RMS is above trial 0's: learning made it worse.
  bool Diverged() const { return WorstRms(static_cast<int>(error_rms.size()) - 1) > WorstRms(0); }
  // One line: trials, the worst RMS before and after, the reduction.
  std::string BriefReport() const;
  // One line per trial.
  std::string FullReport() const;
};

// Runs trial 0 with no learned feedforward, then `options.trials` trials each with the
// feedforward learned from all before (IlcUpdate) under options.safeguard's watch,
// every one from the same initial state along `reference` with `tracking` (its
// feedforward is replaced).
// on_trial(trial, result) is called after every trial. Throws InputError for invalid
// options, std::invalid_argument for one filter per joint missing; what RunTrackingTrial
// throws.
IlcResult RunIlc(const ArmModel& plant, const ArmModel& hat, const ArmReference& reference,
                 const TrackingOptions& tracking, const std::vector<LearningFilter>& filters, const IlcOptions& options,
                 const std::function<void(int, const TrackingTrial&)>& on_trial = {});

}  // namespace twinsim

// The report of an iterative learning control run (control/iterative_learning.h, `twinsim
// ilc`, docs/ilc.md): its tables as CSV text, its plots, and a self-contained HTML page
// that tells the story from the measured process sensitivity through the learning
// filters to the convergence, with the plots embedded. Everything is built from what the
// run computed; nothing is run again (the tool path's forward kinematics aside), so a
// command, a binding or a batch runner gets the same bytes from the same run.
//
//   IlcReportSetup setup{"rrr_writing_ilc", "analytic", "rrr", tracking, frf_options,
//                        "fitted", ilc_options, tool};
//   for (const auto& [file, bytes] : MakeIlcReport(setup, plant, reference.t, frf, filters,
//                                                  result, renderer.get()))
//     WriteFileAtomically(dir + "/" + file, bytes);
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "control/closed_loop_frf.h"
#include "control/computed_torque.h"
#include "control/iterative_learning.h"
#include "io/png_image.h"
#include "render/plot.h"
#include "render/renderer.h"
#include "robots/arm/arm_model.h"

namespace twinsim {

// How an ILC run was set up, as its report tells it.
struct IlcReportSetup {
  std::string name;             // the task's (scene's) name, in titles and the page's heading
  std::string backend;          // analytic, ode or bullet
  std::string hat;              // the name of the controller's model
  TrackingOptions tracking;     // the trials' controller: its name and bandwidth are reported
  FrfOptions frf;               // how the process sensitivity was measured
  std::string learning_filter;  // "fitted" (to the measurement) or "model" (the controller's)
  IlcOptions options;           // the learning gain and the robustness filter Q
  Eigen::Vector3d tool = Eigen::Vector3d::Zero();  // m, the tool point in the last link's frame
};

// trials.csv: trial,rms1..rmsn,max1..maxn, the tracking error per trial and joint (rad or m).
std::string FormatIlcTrialsCsv(const IlcResult& result);

// frf.csv: joint,posture,frequency,magnitude,phase,coherence,filter_magnitude,filter_phase,
// the measured PS (rad/(N·m), degrees) and its coherence per joint, posture (1-based; 0
// is the nominal response, the average over the postures, with the worst coherence) and
// line (Hz), and 1/L of the joint's learning filter at the same line.
std::string FormatIlcFrfCsv(const ClosedLoopFrf& frf, const std::vector<LearningFilter>& filters);

// filters.csv: joint,shift,model_order,inertia,inertia_early,snap,damping,stiffness,
// residual,fit_lines,fit_min_hz,fit_max_hz,learning_limit_hz,q_order,q_cutoff,
// worst_factor,margin: per joint the learning filter's model order (2 rigid, 4 with a
// series spring) and coefficients, its fit (residual, the lines used and their band;
// empty for the model's filter), the frequency (Hz, empty for none) up to which learning
// converges without Q, Q's order and the joint's cut-off (Hz), the worst |Q|^2 |1 - gain
// PS L| over the lines and postures and the margin 1 - worst.
std::string FormatIlcFiltersCsv(const ClosedLoopFrf& frf, const std::vector<LearningFilter>& filters,
                                const IlcOptions& options);

// log10 of the RMS error (rad) per joint and of the worst joint over the trials.
SeriesPlot IlcConvergencePlot(const IlcResult& result, const std::string& title);

// safeguard.csv: `trial,joint,action,rms,best_rms,best_trial,q_cutoff`, one row per action
// of the safeguard (joint 1-based; action lower_q, stop_joint or stop_all; rad or m;
// q_cutoff 0 where learning stopped).
std::string FormatIlcSafeguardCsv(const IlcResult& result);

// What the safeguard did, the best trial and where the last trial stands, in words.
std::string IlcSafeguardSummary(const IlcResult& result, const IlcOptions& options);

// The tracking error of every joint (mrad) over time in trial 0 and in the last trial.
SeriesPlot IlcErrorPlot(const IlcResult& result, const std::string& title);

// A Bode plot: magnitude above phase, against log10 of the frequency.
struct IlcBodePlot {
  SeriesPlot magnitude;  // dB re 1 rad/(N·m)
  SeriesPlot phase;      // deg, unwrapped (signal/phase_unwrap.h)
};

// The measured PS of joint `joint` (0-based): one grey line per posture (seed 001, Fig.
// 8), the nominal response (their average) and 1/L of its learning filter last (Fig. 9).
// Throws std::out_of_range for a joint that was not measured.
IlcBodePlot IlcBodePlots(const ClosedLoopFrf& frf, const LearningFilter& filter, int joint, const std::string& title);

// IlcBodePlots() drawn, the magnitude stacked above the phase. Throws what the renderer
// throws.
RgbaImage RenderIlcBodePlot(const ClosedLoopFrf& frf, const LearningFilter& filter, int joint, const std::string& title,
                            Renderer& renderer);

// Seed 001, Fig. 10 for joint `joint`: above, L and 1/PS at every posture (grey); below,
// |1 - gain PS_i L| at every posture (grey) and 1/|Q|^2 (1 without Q), all in dB: the
// convergence criterion holds where the grey lines stay below the last. Throws
// std::out_of_range for a joint that was not measured.
IlcBodePlot IlcCriterionPlots(const ClosedLoopFrf& frf, const LearningFilter& filter, const IlcOptions& options,
                              int joint, const std::string& title);

// The tool point's path (ToolPathPlot, control/tracking_plots.h): the reference, trial 0
// and the last trial.
PathPlot IlcToolPathPlot(const IlcResult& result, const ArmModel& plant, const Eigen::Vector3d& tool,
                         const std::string& title);

// report.html: the setup, the Bode plots, the filters, the convergence table and the
// other plots. `images` are (file name, PNG bytes) as MakeIlcReport draws them: the
// convergence and error plots, one Bode plot per joint, the tool path; none when
// nothing was drawn.
std::string FormatIlcReportHtml(const IlcReportSetup& setup, const ArmModel& plant, const ClosedLoopFrf& frf,
                                const std::vector<LearningFilter>& filters, const IlcResult& result,
                                const std::vector<std::pair<std::string, std::string>>& images);

// Every file of the report as (file name, bytes), in the order `twinsim ilc` writes them:
// trials.csv, frf.csv, filters.csv, feedforward.csv (t,f1..fn: the last trial's
// feedforward, N·m, at the reference's times `t`, s), then with a renderer
// convergence.png, error.png, bode_joint<j>.png and path.png, and report.html last.
// Without a renderer (nullptr) no plot is drawn and the page has none. Throws what the
// renderer throws.
std::vector<std::pair<std::string, std::string>> MakeIlcReport(const IlcReportSetup& setup, const ArmModel& plant,
                                                               const Eigen::VectorXd& t, const ClosedLoopFrf& frf,
                                                               const std::vector<LearningFilter>& filters,
                                                               const IlcResult& result, Renderer* renderer);

}  // namespace twinsim

#include "identification_omni/omni_identification.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "analysis/camera_noise.h"
#include "analysis/fixed_step_cost.h"
#include "analysis/held_out_blocks.h"
#include "analysis/omni_baselines.h"
#include "analysis/omni_horizons.h"
#include "analysis/omni_replay.h"
#include "core/error.h"
#include "core/parallel.h"
#include "identification/identifiability.h"
#include "io/printf_number.h"
#include "robots/omni/omni_effects.h"
#include "robots/omni/omni_model_fields.h"
#include "signal/series_statistics.h"

namespace twinsim {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The estimated parameters besides the delay, in the solver's order.
enum Param {
  kGainX, kGainY, kGainW,
  kLagX, kLagY, kLagW,
  kSlewX, kSlewY, kSlewW,
  kTurnX, kTurnY,
  kCrossYX, kCrossXY,
  kVMax, kWMax,
  kDelay,
  kLoopX, kLoopY, kLoopW,
  kNoiseX, kNoiseY, kNoiseW, kNoiseTime, kProcessScale,
  kBraking, kFieldFrame,
  kTurn3S, kTurn3C,
  kNumParams
};

struct ParamSpec {
  const char* name;
  std::string key;  // in the model file
  const char* unit;
  const char* meaning;
  double lower, upper;
  bool log_scale;
  // Where a model holds it, for a parameter that is one number of the model file (the
  // file's own tables: robots/omni/omni_model_fields.h, omni_effects.h); empty for the
  // lags (read through a common motor_lag), the delay (frames and an effect), the loop
  // gains and the process noise's scale (factors on the model's own), which ValuesOf and
  // WithValues compute.
  std::function<double(const OmniModel&)> get = {};
  std::function<void(OmniModel*, double)> set = {};
};

// A parameter that is the model file's number at `path` (omni_model_fields.h).
ParamSpec ModelNumber(const char* name, const std::string& path, const char* meaning, double lower, double upper,
                      bool log_scale) {
  const OmniModelField& f = OmniModelFieldAt(path);
  return {name, f.path(), f.unit.c_str(), meaning, lower, upper, log_scale, f.get, f.set};
}

// The field `key` of the effect `effect` in the vocabulary's table (omni_effects.h).
const OmniEffectField& EffectField(const std::string& effect, const std::string& key) {
  const OmniEffectSpec* spec = FindOmniEffectSpec(effect);
  if (const OmniEffectField* f = spec ? spec->Field(key) : nullptr) return *f;
  throw std::logic_error("no omni effect field '" + effect + "." + key + "'");
}

std::string EffectKey(const std::string& effect, const OmniEffectField& f) { return "effects." + effect + "." + f.key; }
std::string EffectKey(const std::string& effect, const std::string& key) {
  return EffectKey(effect, EffectField(effect, key));
}

// A parameter that is the number `key` of the effect `effect`, in identify's unit.
ParamSpec EffectNumber(const char* name, const std::string& effect, const std::string& key, const char* unit,
                       const char* meaning, double lower, double upper, bool log_scale) {
  const OmniEffectField& f = EffectField(effect, key);
  return {name,      EffectKey(effect, f), unit, meaning, lower, upper, log_scale,
          [get = f.get](const OmniModel& m) { return get(m.effects); },
          [set = f.set](OmniModel* m, double v) { set(&m->effects, v); }};
}

std::vector<ParamSpec> MakeSpecs() {
  const auto section = [](const std::string& path) { return OmniModelFieldAt(path).section; };
  std::vector<ParamSpec> specs = {
      EffectNumber("forward.gain", "velocity_scale", "forward", "", "forward speed reached per unit of forward command", 0.05, 3, false),
      EffectNumber("sideways.gain", "velocity_scale", "sideways", "", "sideways speed reached per unit of sideways command", 0.05, 3, false),
      EffectNumber("turn.gain", "velocity_scale", "turn", "", "turn rate reached per unit of turn command", 0.05, 3, false),
      {"forward.lag", EffectKey("motor_lag", "forward"), "s", "first-order time constant of the forward response, before the controller", 0.002, 1, true},
      {"sideways.lag", EffectKey("motor_lag", "sideways"), "s", "first-order time constant of the sideways response, before the controller", 0.002, 1, true},
      {"turn.lag", EffectKey("motor_lag", "turn"), "s", "first-order time constant of the turn response, before the controller", 0.002, 1, true},
      ModelNumber("forward.slew", "controller.forward.slew_rate", "the controller's forward set-point ramps at most this fast", 0.05, 200, true),
      ModelNumber("sideways.slew", "controller.sideways.slew_rate", "the controller's sideways set-point ramps at most this fast", 0.05, 200, true),
      ModelNumber("turn.slew", "controller.rotation.slew_rate", "the controller's turn set-point ramps at most this fast", 0.5, 2000, true),
      EffectNumber("turn_coupling.forward", "turn_coupling", "forward", "rad/s per m/s", "turn rate per m/s of forward command", -5, 5, false),
      EffectNumber("turn_coupling.sideways", "turn_coupling", "sideways", "rad/s per m/s", "turn rate per m/s of sideways command", -5, 5, false),
      EffectNumber("cross_coupling.sideways_per_forward", "cross_coupling", "sideways_per_forward", "", "sideways speed per unit of forward command", -1, 1, false),
      EffectNumber("cross_coupling.forward_per_sideways", "cross_coupling", "forward_per_sideways", "", "forward speed per unit of sideways command", -1, 1, false),
      EffectNumber("velocity_saturation.v_max", "velocity_saturation", "v_max", "m/s", "the highest translational speed the robot reaches", 0.05, 20, true),
      EffectNumber("velocity_saturation.w_max", "velocity_saturation", "w_max", "rad/s", "the highest turn rate the robot reaches", 0.1, 200, true),
      {"delay", OmniModelFieldAt("delay.command_frames").path() + " + " + OmniModelFieldAt("delay.vision_frames").path() + " + " + EffectKey("time_delay", "delay"), "s",
       "from sending a command to the camera's pose showing its effect (command and vision together)", 0, 2, false},
      {"forward.loop_gain", section("controller.forward.kp") + ".kp, ki, kd", "x", "the forward controller's gains relative to the model's: its bandwidth", 0.05, 20, true},
      {"sideways.loop_gain", section("controller.sideways.kp") + ".kp, ki, kd", "x", "the sideways controller's gains relative to the model's: its bandwidth", 0.05, 20, true},
      {"turn.loop_gain", section("controller.rotation.kp") + ".kp, ki, kd", "x", "the rotation controller's gains relative to the model's: its bandwidth", 0.05, 20, true},
      ModelNumber("driving_noise.forward", "driving_noise.forward", "spread of the forward driving noise the wheels do not see (the observer's)", 0.002, 5, true),
      ModelNumber("driving_noise.sideways", "driving_noise.sideways", "spread of the sideways driving noise the wheels do not see (the observer's)", 0.002, 5, true),
      ModelNumber("driving_noise.turn", "driving_noise.turn", "spread of the turning driving noise the wheels do not see (the observer's)", 0.01, 50, true),
      ModelNumber("driving_noise.correlation_time", "driving_noise.correlation_time", "how long the driving noise lasts (the observer's)", 0.01, 5, true),
      {"process_noise.scale", section("observer.process_noise.forward"), "x", "the observer's process noise on the model's velocity relative to the model's: how far the model's own velocity is trusted", 0.001, 100, true},
      EffectNumber("lag.braking", "motor_lag", "braking", "x", "the lags' time constants while slowing down, relative to speeding up", 0.1, 10, true),
      // A choice, never fitted: 0 the lag acts in the robot's frame, 1 in the field's.
      EffectNumber("lag.field_frame", "motor_lag", "field_frame", "", "1: the lagged velocity keeps its direction in the field while the robot turns; 0: it turns with the robot", 0, 1, false),
      EffectNumber("turn_coupling.third_sin", "turn_coupling", "third_sin", "rad/s per m/s", "turn rate per m/s of translation command times sin 3 of its direction (three wheels)", -5, 5, false),
      EffectNumber("turn_coupling.third_cos", "turn_coupling", "third_cos", "rad/s per m/s", "turn rate per m/s of translation command times cos 3 of its direction (three wheels)", -5, 5, false),
  };
  if (specs.size() != kNumParams) throw std::logic_error("identify's parameter table is out of step with Param");
  return specs;
}

// The table, built on first use (not at every command's start-up).
const std::vector<ParamSpec>& Specs() {
  static const std::vector<ParamSpec> specs = MakeSpecs();
  return specs;
}

// True where parameter p is among the fit's free ones.
bool IsFree(const std::vector<int>& free, int p) { return std::find(free.begin(), free.end(), p) != free.end(); }

// Which of parameters that trade against each other is held at its value (larger:
// sooner; identification/identifiability.h): the controller's loop gain and ramp before the
// lag they mimic, the filter's overall trust before the driving noise's spreads, and the
// delay and the gains last, as the quantities a user reads first.
double HoldPreference(int p) {
  if (p >= kLoopX && p <= kLoopW) return 2;
  // The turn's third harmonic, a structure the held-out blocks chose, before the axis
  // couplings it may trade with.
  if ((p >= kSlewX && p <= kSlewW) || p == kProcessScale || p == kTurn3S || p == kTurn3C) return 1.5;
  if (p == kDelay || (p >= kGainX && p <= kGainW)) return 0.5;
  return 1;
}

constexpr double kPieceSeconds = 10;   // s, a log is replayed in pieces this long ...
constexpr int kBlocksPerLog = 1 << 20;  // block numbers: a log's index times this plus its block's
constexpr double kLeadInSeconds = 3;   // s, ... each after a lead-in this long, not scored
// A structure of the lag (field frame, braking) is kept where it predicts the held-out
// blocks this much better at the lookahead (a share of their RMSE) ...
constexpr double kStructureGain = 0.01;
// ... and at K frames no worse than this (also what the final joint fit may lose there).
constexpr double kStructureTolerance = 0.005;
// The lag's structures and the speed limits, which a K-frame prediction hardly sees, are
// chosen on predictions this far ahead (the lookahead).
constexpr double kLookaheadSeconds = 0.25;
constexpr double kStartLag = 0.03;  // s: a lag of 0 has no gradient to start from
// The numeric derivatives' step in the solver's coordinates (2 % for a scale): the
// replay's cost is jagged at finer scales (encoder counts, controller ticks).
constexpr double kCoordinateStep = 2e-2;

// The parameters of a model (physical units); 0 for a limit that is off.
std::array<double, kNumParams> ValuesOf(const OmniModel& m, double frame_period) {
  std::array<double, kNumParams> v{};
  const std::vector<ParamSpec>& specs = Specs();
  for (int p = 0; p < kNumParams; ++p)
    if (specs[p].get) v[static_cast<std::size_t>(p)] = specs[p].get(m);
  for (int a = 0; a < 3; ++a) {
    v[static_cast<std::size_t>(kLagX + a)] = m.effects.LagOf(a);
    v[static_cast<std::size_t>(kLoopX + a)] = 1;
  }
  v[kDelay] = m.TotalDelaySeconds(frame_period);
  v[kProcessScale] = 1;
  return v;
}

// `base` with the parameters. The total delay (s) goes into whole frames in `delay:`
// (the vision's share kept as the model has it while the total allows) and the rest
// into the time_delay effect; or, with `all_in_effect` (the fit's form, whose replays
// predict the same rows whatever the delay), all into the effect. Both act alike.
OmniModel WithValues(OmniModel m, const std::array<double, kNumParams>& v, double frame_period, bool all_in_effect) {
  const double delay = v[kDelay];
  const std::vector<ParamSpec>& specs = Specs();
  for (int p = 0; p < kNumParams; ++p)
    if (specs[p].set) specs[p].set(&m, v[static_cast<std::size_t>(p)]);
  OmniEffects& fx = m.effects;
  for (int a = 0; a < 3; ++a) fx.axis_lag[static_cast<std::size_t>(a)] = v[static_cast<std::size_t>(kLagX + a)];
  fx.motor_lag = 0;
  fx.lag_series = 0;  // a given lag in series is folded into the per-axis lags (StartValues)
  for (double& q : m.observer.process_noise) q *= v[kProcessScale];
  PidGains* gains[3] = {&m.controller.forward, &m.controller.sideways, &m.controller.rotation};
  for (int a = 0; a < 3; ++a) {
    const double k = v[static_cast<std::size_t>(kLoopX + a)];
    gains[a]->kp *= k;
    gains[a]->ki *= k;
    gains[a]->kd *= k;
  }
  const int frames = all_in_effect ? 0 : static_cast<int>(std::floor(delay / frame_period + 1e-9));
  m.vision_delay_frames = std::min(m.vision_delay_frames, frames);
  m.command_delay_frames = frames - m.vision_delay_frames;
  fx.time_delay = std::max(0.0, delay - frames * frame_period);
  if (fx.time_delay < 1e-7) fx.time_delay = 0;
  return m;
}

// A stretch of one log replayed on its own: a lead-in, where the tracker settles and
// nothing is scored, then the rows it scores, each in a fit or a held-out block.
struct Segment {
  OmniLog log;
  std::size_t score_from = 0;  // first scored row
  std::vector<char> held;      // per row: in a held-out block
  std::vector<int> block;      // per row: its block's number, unique across logs
  bool validation = false;     // a wholly held-out log
};

OmniBlockedStretch BlockedStretchOf(const Segment& s) { return {&s.log, s.score_from, &s.held, &s.block, s.validation}; }

// The report's gap of summed errors.
OmniGap ToGap(const HorizonSum& sum, const std::string& name) {
  OmniGap g;
  g.name = name;
  if (sum.rows == 0) return g;
  const double k = 1.0 / static_cast<double>(sum.rows);
  g.rmse = sum.PositionRmse();
  g.pose = sum.PoseRms();
  g.forward = std::sqrt(sum.forward * k);
  g.sideways = std::sqrt(sum.sideways * k);
  g.turn = std::sqrt(sum.turn * k);
  return g;
}

// Time blocks, some held out from the fit. Each log is replayed in pieces of
// kPieceSeconds (in parallel), each with a lead-in of kLeadInSeconds that is not scored:
// the tracker's hidden state (a slew-limited set-point, a lag) needs that long to
// forget its start. Validation logs are one piece each, all held out.
std::vector<Segment> MakeSegments(const std::vector<OmniLog>& logs, const std::vector<OmniLog>& validation,
                                  const OmniIdentificationOptions& options, double* block_seconds) {
  std::vector<double> durations;
  for (const OmniLog& log : logs) durations.push_back(log.rows.back().t - log.rows.front().t);
  const double block = HeldOutBlockSeconds(options.block_seconds, durations);
  *block_seconds = block;
  std::vector<Segment> segments;
  for (const OmniLog& log : logs) {
    std::vector<double> t;
    for (const OmniLogRow& r : log.rows) t.push_back(r.t - log.rows.front().t);
    CheckLogHoldsOut(t, 0, block, options.held_out, log.path);
    for (double from = 0; from < t.back(); from += kPieceSeconds) {
      const std::size_t first = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), from - kLeadInSeconds) - t.begin());
      const std::size_t score = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), from) - t.begin());
      std::size_t last = static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), from + kPieceSeconds) - t.begin());
      if (t.back() - (from + kPieceSeconds) < kPieceSeconds / 2) {
        last = t.size();  // a short tail joins this piece
        from = t.back();
      }
      Segment s;
      s.log = SliceOmniLog(log, first, last);
      s.score_from = score - first;
      for (std::size_t i = first; i < last; ++i) {
        s.held.push_back(InHeldOutBlock(t[i], block, options.held_out));
        s.block.push_back(static_cast<int>(&log - logs.data()) * kBlocksPerLog + TimeBlockIndex(t[i], block));
      }
      if (s.log.num_measured() >= 2 && last - first > 2) segments.push_back(std::move(s));
    }
  }
  for (const OmniLog& log : validation) {
    Segment s;
    s.log = log;
    s.held.assign(log.rows.size(), 1);
    for (const OmniLogRow& r : log.rows)
      s.block.push_back(static_cast<int>(logs.size() + static_cast<std::size_t>(&log - validation.data())) * kBlocksPerLog +
                        TimeBlockIndex(r.t - log.rows.front().t, block));
    s.validation = true;
    segments.push_back(std::move(s));
  }

  return segments;
}

// True where row i's prediction both ends and starts (K frames earlier) in blocks of the
// given kind, after the piece's lead-in: a fit row's prediction never starts from a
// tracker corrected to a held-out measurement, and a held-out row's never from a fit one.
bool ScoredRow(const Segment& s, std::size_t i, bool held_out, int horizon) {
  return ScoredInBlocks(BlockedStretchOf(s), i, held_out, horizon);
}

// Sums the errors of the held-out rows of `segments` (validation logs or the others)
// that every predictor scores: past the longest warm-up a replay can have, where the
// prediction starts on a logged frame and constant velocity has two measurements before
// it, whatever the model.
HorizonSum ScoreHeldOut(const std::vector<Segment>& segments, const OmniModel* model, bool validation_only,
                    const OmniIdentificationOptions& options, double radius, int stride = 1) {
  HorizonSum sum;
  for (const Segment& s : segments) {
    if (s.validation != validation_only) continue;
    const int first = static_cast<int>(std::ceil(options.max_delay / s.log.frame_period)) + kWarmUpFrames + options.horizon;
    const OmniReplayResult cv = ConstantVelocityPrediction(s.log, options.horizon);
    OmniReplayResult r = cv;
    if (model) {
      OmniReplayOptions o;
      o.backend = options.backend;
      o.horizon = options.horizon;
      o.state = options.state;
      o.stride = stride;
      r = ReplayOmniLog(*model, s.log, o);
    }
    for (std::size_t row = 0; row < r.predicted.size(); ++row) {
      r.predicted[row] = r.predicted[row] && cv.predicted[row] && s.log.FrameIndex(row) >= first &&
                         ScoredRow(s, row, true, options.horizon);
    }
    for (const auto& e : PoseErrorsInRobotFrame(s.log, r, radius).e) sum.Add(e);
  }
  return sum;
}

class OmniIdentificationProblem {
 public:
  OmniIdentificationProblem(const OmniModel& nominal, std::vector<Segment> segments,
                            const OmniIdentificationOptions& options)
      : nominal_(nominal), segments_(std::move(segments)), options_(options) {
    frame_period_ = segments_.front().log.frame_period;
  }

  double frame_period() const { return frame_period_; }
  int evaluations() const { return evaluations_; }
  const OmniModel& nominal() const { return nominal_; }

  // The model in the fit's form (every delay in the effect), or as written.
  OmniModel Build(const std::array<double, kNumParams>& v, bool all_in_effect = true) const {
    return WithValues(nominal_, v, frame_period_, all_in_effect);
  }

  // The errors of the scored rows of one kind (fit or held out) of every segment, in
  // segment order; the segments replayed in parallel. Throws CheckFailed when the model
  // diverges.
  std::vector<OmniPoseErrors> Errors(const OmniModel& model, bool held_out, int stride) const {
    std::vector<OmniPoseErrors> out(segments_.size());
    ParallelFor(static_cast<int>(segments_.size()), options_.threads, [&](int k) {
      const Segment& s = segments_[static_cast<std::size_t>(k)];
      if (!held_out && s.validation) return;
      OmniReplayOptions o;
      o.backend = options_.backend;
      o.horizon = options_.horizon;
      o.state = options_.state;
      o.stride = stride;
      const OmniPoseErrors all = PoseErrorsInRobotFrame(s.log, ReplayOmniLog(model, s.log, o), nominal_.chassis_radius);
      OmniPoseErrors& kept = out[static_cast<std::size_t>(k)];
      for (std::size_t r = 0; r < all.rows.size(); ++r) {
        const std::size_t row = all.rows[r];
        if (!ScoredRow(s, row, held_out, options_.horizon)) continue;
        kept.rows.push_back(row);
        kept.e.push_back(all.e[r]);
      }
    });
    ++evaluations_;
    return out;
  }

  std::vector<double> FitResidual(const std::array<double, kNumParams>& v) const {
    std::vector<double> r;
    for (const OmniPoseErrors& e : Errors(Build(v), false, options_.stride)) {
      for (const auto& x : e.e) r.insert(r.end(), x.begin(), x.end());
    }
    return r;
  }

  // Sum of squared fit residuals; infinity where the model diverges.
  double Cost(const std::array<double, kNumParams>& v) const {
    try {
      double s = 0;
      for (double x : FitResidual(v)) s += x * x;
      return s;
    } catch (const CheckFailed&) {
      return std::numeric_limits<double>::infinity();
    }
  }

  const std::vector<Segment>& segments() const { return segments_; }

 private:
  OmniModel nominal_;
  std::vector<Segment> segments_;
  OmniIdentificationOptions options_;
  double frame_period_ = 1.0 / 60;
  mutable int evaluations_ = 0;
};

// The solver's coordinate of a parameter: the logarithm for a scale (clamped to its
// range), else a logistic map onto the range, so that no bound is ever crossed and the
// cost never goes flat outside it (Ceres' own bounds add line searches that cost
// Jacobians).
double ParamUpper(int p, double max_delay) { return p == kDelay ? max_delay : Specs()[p].upper; }

double ToCoordinate(int p, double value, double max_delay) {
  const ParamSpec& s = Specs()[p];
  const double upper = ParamUpper(p, max_delay);
  if (s.log_scale) return std::log(std::clamp(value, s.lower, upper));
  const double u = std::clamp((value - s.lower) / (upper - s.lower), 1e-6, 1 - 1e-6);
  return std::log(u / (1 - u));
}

double FromCoordinate(int p, double x, double max_delay) {
  const ParamSpec& s = Specs()[p];
  const double upper = ParamUpper(p, max_delay);
  if (s.log_scale) return std::clamp(std::exp(x), s.lower, upper);
  return s.lower + (upper - s.lower) / (1 + std::exp(-x));
}

// d value / d coordinate, for the standard errors (the delta method).
double CoordinateSlope(int p, double value, double max_delay) {
  const ParamSpec& s = Specs()[p];
  if (s.log_scale) return value;
  const double upper = ParamUpper(p, max_delay);
  const double u = (value - s.lower) / (upper - s.lower);
  return (upper - s.lower) * u * (1 - u);
}

// Ceres' view: the free parameters (in the solver's scale) to the fit residual.
class FitCost : public ceres::CostFunction {
 public:
  FitCost(const OmniIdentificationProblem* problem, std::array<double, kNumParams> values, std::vector<int> free,
          std::size_t rows, double max_delay)
      : problem_(problem), values_(values), free_(std::move(free)), rows_(rows), max_delay_(max_delay) {
    mutable_parameter_block_sizes()->push_back(static_cast<int>(free_.size()));
    set_num_residuals(static_cast<int>(rows));
  }

  // The parameters (physical units) for the solver's x (ToCoordinate).
  std::array<double, kNumParams> Apply(const double* x) const {
    std::array<double, kNumParams> v = values_;
    for (std::size_t k = 0; k < free_.size(); ++k) {
      v[static_cast<std::size_t>(free_[k])] = FromCoordinate(free_[k], x[k], max_delay_);
    }
    return v;
  }

  // Central differences with a fixed step in the coordinates (analysis/fixed_step_cost.h:
  // Ceres' numeric derivatives take 1.5e-8 where a coordinate is 0, a loop gain of 1, a
  // coupling in the middle of its range).
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    if (!Residual(parameters[0], residuals)) return false;
    if (!jacobians || !jacobians[0]) return true;
    return CentralDifferences([this](const double* x, double* out) { return Residual(x, out); }, parameters[0],
                              std::vector<double>(free_.size(), kCoordinateStep), rows_, jacobians[0]);
  }

 private:
  bool Residual(const double* x, double* out) const {
    try {
      const std::vector<double> r = problem_->FitResidual(Apply(x));
      if (r.size() != rows_) return false;
      std::copy(r.begin(), r.end(), out);
      return true;
    } catch (const CheckFailed&) {
      return false;
    }
  }

  const OmniIdentificationProblem* problem_;
  std::array<double, kNumParams> values_;
  std::vector<int> free_;
  std::size_t rows_;
  double max_delay_;
};

// A parameter the fit's sensitivities cannot tell from others: held at its value.
struct HeldBack {
  int param = 0;
  std::vector<int> partners;  // empty: the fit does not depend on it
  double collinearity = 0;
};

struct SolveResult {
  std::array<double, kNumParams> values;
  std::vector<double> standard_error;  // per free parameter, physical units; NaN: undetermined or held
  std::vector<HeldBack> held;          // with `covariance`: what the logs do not determine
  double collinearity = 1;             // with `covariance`: the index of the determined set
  // With `covariance`: the determined parameters (Param) and their covariance, physical
  // units (the delta method, as the standard errors).
  std::vector<int> covariance_of;
  Eigen::MatrixXd covariance;
  int iterations = 0;
  double cost = 0;
  std::size_t rows = 0;
};

// Least squares over the free parameters (the delay up to max_delay s); with
// `covariance`, the standard errors too. max_iterations 0: no solve, the standard errors
// at `start`.
SolveResult Solve(const OmniIdentificationProblem& problem, const std::array<double, kNumParams>& start,
                  const std::vector<int>& free, double max_delay, int max_iterations, bool covariance) {
  SolveResult out;
  out.values = start;
  const std::size_t rows = problem.FitResidual(start).size();
  if (rows == 0) throw InputError("the logs leave no rows to fit: every prediction starts or ends in a held-out block");
  out.rows = rows;
  std::vector<double> x;
  for (int p : free) x.push_back(ToCoordinate(p, start[static_cast<std::size_t>(p)], max_delay));
  auto* cost = new FitCost(&problem, start, free, rows, max_delay);
  ceres::Problem ceres_problem;
  ceres_problem.AddResidualBlock(cost, nullptr, x.data());
  // No bounds in Ceres (a bounded problem adds line searches that cost Jacobians); the
  // coordinates keep each parameter in its range instead (ToCoordinate).
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = std::max(1, max_iterations);
  options.function_tolerance = 1e-6;
  options.parameter_tolerance = 1e-5;
  options.num_threads = 1;  // the cost runs the pieces in parallel itself, deterministically
  options.logging_type = ceres::SILENT;
  if (max_iterations > 0) {
    ceres::Solver::Summary summary;
    ceres::Solve(options, &ceres_problem, &summary);
    out.values = cost->Apply(x.data());
    out.iterations = static_cast<int>(summary.iterations.size());
    out.cost = 2 * summary.final_cost;
  } else {
    out.cost = problem.Cost(start);  // the standard errors at `start`
  }
  out.standard_error.assign(free.size(), kNaN);
  if (!covariance) return out;

  // The sensitivities at the solution, which parameters they determine, and the
  // covariance of those (identification/identifiability.h).
  const double* at[1] = {x.data()};
  std::vector<double> residual(rows), jacobian(rows * free.size());
  double* jacobians[1] = {jacobian.data()};
  if (!cost->Evaluate(at, residual.data(), jacobians)) return out;
  const Eigen::MatrixXd j = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      jacobian.data(), static_cast<long>(rows), static_cast<long>(free.size()));
  std::vector<double> preference;
  for (int p : free) preference.push_back(HoldPreference(p));
  const Identifiability id = AnalyseIdentifiability(j, preference);
  out.collinearity = id.collinearity;
  for (const HeldParameter& h : id.held) {
    HeldBack held;
    held.param = free[static_cast<std::size_t>(h.column)];
    for (int c : h.partners) held.partners.push_back(free[static_cast<std::size_t>(c)]);
    held.collinearity = h.collinearity;
    out.held.push_back(held);
  }
  const Eigen::MatrixXd c = KeptInverseNormal(j, id.kept);
  if (c.size() == 0) return out;
  // The inverse normal matrix is for unit-variance residuals: scale by the residual's
  // variance, and by its correlation length (overlapping predictions are not
  // independent rows).
  double ss = 0;
  for (double v : residual) ss += v * v;
  const double dof = std::max(1.0, static_cast<double>(rows) - static_cast<double>(id.kept.size()));
  std::vector<double> forward;
  for (std::size_t k = 0; k < residual.size(); k += 3) forward.push_back(residual[k]);
  const double correlation = std::max(1, CorrelationLength(forward, 200));
  const double scale = ss / dof * correlation;
  Eigen::VectorXd slope(static_cast<long>(id.kept.size()));
  for (std::size_t k = 0; k < id.kept.size(); ++k) {
    const auto col = static_cast<std::size_t>(id.kept[k]);
    const double var = c(static_cast<long>(k), static_cast<long>(k)) * scale;
    const double v = out.values[static_cast<std::size_t>(free[col])];
    slope[static_cast<long>(k)] = CoordinateSlope(free[col], v, max_delay);  // the delta method
    out.standard_error[col] = std::sqrt(std::max(0.0, var)) * slope[static_cast<long>(k)];
    out.covariance_of.push_back(free[col]);
  }
  out.covariance = slope.asDiagonal() * (c * scale) * slope.asDiagonal();
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  return out;
}

// Gains and couplings as a linear least-squares fit of the measured body velocity (central
// differences of measured poses) on the command sent `delay` s earlier, over frames whose
// command had held for kSettleSeconds by then (near steady state), in the fit blocks
// (`in_fit`): a start for the fit, which sees the dynamics. Leaves *v as it is where too
// few frames qualify.
void LinearStart(const std::vector<OmniLog>& logs, double delay, const std::function<bool(const OmniLog&, std::size_t)>& in_fit,
                 const std::vector<int>& free, std::array<double, kNumParams>* v) {
  constexpr double kSettleSeconds = 0.3;
  std::vector<std::array<double, 3>> u, y;
  for (const OmniLog& log : logs) {
    std::size_t changed = 0;  // the last row whose command differs from the row before
    std::size_t j = 0;        // the row whose command acts at row i's time
    for (std::size_t i = 1; i + 1 < log.rows.size(); ++i) {
      while (j + 1 < log.rows.size() && log.rows[j + 1].t <= log.rows[i].t - delay + 1e-9) {
        ++j;
        const Twist2& a = log.rows[j].command;
        const Twist2& b = log.rows[j - 1].command;
        if (a.vx != b.vx || a.vy != b.vy || a.omega != b.omega) changed = j;
      }
      if (!in_fit(log, i - 1) || !in_fit(log, i) || !in_fit(log, i + 1)) continue;
      if (log.rows[i].t - delay < log.rows[0].t + kSettleSeconds) continue;
      if (log.rows[j].t - log.rows[changed].t < kSettleSeconds) continue;
      const OmniLogRow& a = log.rows[i - 1];
      const OmniLogRow& b = log.rows[i + 1];
      if (!a.measured || !b.measured) continue;
      const double dt = b.t - a.t;
      const Twist2 body = FieldToBody(
          Twist2{(b.pose.x - a.pose.x) / dt, (b.pose.y - a.pose.y) / dt, (b.pose.theta - a.pose.theta) / dt},
          log.rows[i].pose.theta);
      const Twist2& c = log.rows[j].command;
      u.push_back({c.vx, c.vy, c.omega});
      y.push_back({body.vx, body.vy, body.omega});
    }
  }
  if (u.size() < 30) return;
  // Per axis, its own command and the ones that couple into it.
  auto fit = [&](int out, std::vector<int> in) {
    Eigen::MatrixXd A(static_cast<long>(u.size()), static_cast<long>(in.size()));
    Eigen::VectorXd b(static_cast<long>(u.size()));
    for (std::size_t r = 0; r < u.size(); ++r) {
      for (std::size_t k = 0; k < in.size(); ++k) A(static_cast<long>(r), static_cast<long>(k)) = u[r][static_cast<std::size_t>(in[k])];
      b[static_cast<long>(r)] = y[r][static_cast<std::size_t>(out)];
    }
    return Eigen::VectorXd(A.colPivHouseholderQr().solve(b));
  };
  auto set = [&](int p, double value) {
    if (!IsFree(free, p)) return;  // held at the model's value
    if (std::isfinite(value)) (*v)[static_cast<std::size_t>(p)] = std::clamp(value, Specs()[p].lower, Specs()[p].upper);
  };
  const Eigen::VectorXd fx = fit(0, {0, 1}), fy = fit(1, {1, 0}), fw = fit(2, {2, 0, 1});
  set(kGainX, fx[0]);
  set(kCrossXY, fx[1]);
  set(kGainY, fy[0]);
  set(kCrossYX, fy[1]);
  set(kGainW, fw[0]);
  set(kTurnX, fw[1]);
  set(kTurnY, fw[2]);
}

// The delay (s) with the lowest fit cost on a grid, and the profile.
double ProfileDelay(const OmniIdentificationProblem& problem, std::array<double, kNumParams> v, double from,
                    double to, double step, std::vector<double>* grid, std::vector<double>* cost) {
  double best = from, best_cost = std::numeric_limits<double>::infinity();
  const int n = static_cast<int>(std::floor((to - from) / step + 1e-9)) + 1;
  for (int k = 0; k < n; ++k) {
    const double d = std::max(0.0, from + k * step);
    v[kDelay] = d;
    const double c = problem.Cost(v);
    if (grid) {
      grid->push_back(d);
      cost->push_back(c);
    }
    if (c < best_cost) {
      best_cost = c;
      best = d;
    }
  }
  return best;
}

// The held-out blocks' position RMSE (m) at the options' horizon, or with `pose` their
// pose's, sqrt(dx² + dy² + (r dθ)²) with r the chassis radius; predicted from every
// options.stride-th frame; infinity where the model diverges.
double HeldOutRmse(const OmniIdentificationProblem& problem, const std::vector<Segment>& segments,
                   const OmniIdentificationOptions& options, const std::array<double, kNumParams>& v,
                   bool pose = false) {
  try {
    const OmniModel model = problem.Build(v);
    const HorizonSum sum = ScoreHeldOut(segments, &model, false, options, model.chassis_radius, options.stride);
    return pose ? sum.PoseRms() : sum.PositionRmse();
  } catch (const CheckFailed&) {
    return std::numeric_limits<double>::infinity();
  }
}

// Tries the lag's structures on top of the fit `v`: the lag held in the field frame,
// then braking at its own time constants (the factor that predicts the fit blocks best
// at the lookahead, on a grid refined by a parabola in its logarithm). A 4-frame
// prediction hardly sees either (the observer corrects the velocity every frame), so
// both are judged at the lookahead: kept, and added to `chosen`, where they cut the
// held-out blocks' lookahead RMSE by kStructureGain without making their K-frame RMSE
// worse by more than kStructureTolerance. The verdict, with the numbers, goes into
// `notes`.
// A braking factor this close to 1 (either way) is no structure of its own.
constexpr double kBrakingSameAsSpeedingUp = 1.05;

void ChooseLagStructures(const OmniIdentificationProblem& lookahead, const std::vector<Segment>& segments,
                         const OmniIdentificationOptions& options, const OmniIdentificationOptions& ahead,
                         bool turned, const std::vector<int>& free, std::array<double, kNumParams>* v,
                         std::map<int, std::string>* notes, std::set<int>* chosen) {
  bool any_lag = false;
  for (int a = 0; a < 3; ++a) {
    const int p = kLagX + a;
    any_lag = any_lag || (IsFree(free, p) && (*v)[static_cast<std::size_t>(p)] > 1.05 * Specs()[p].lower);
  }
  if (!any_lag) {
    (*notes)[kFieldFrame] = (*notes)[kBraking] = "not tried: the fit found no lag";
    return;
  }
  double k_now = HeldOutRmse(lookahead, segments, options, *v);
  double l_now = HeldOutRmse(lookahead, segments, ahead, *v);
  auto decide = [&](int p, const std::array<double, kNumParams>& trial) {
    const double k_with = HeldOutRmse(lookahead, segments, options, trial);
    const double l_with = HeldOutRmse(lookahead, segments, ahead, trial);
    const bool keep = l_with < (1 - kStructureGain) * l_now && k_with < (1 + kStructureTolerance) * k_now;
    char numbers[200];
    std::snprintf(numbers, sizeof numbers, "%.3g mm at %d frames and %.3g mm at %d with it, %.3g and %.3g mm without",
                  1e3 * l_with, ahead.horizon, 1e3 * k_with, options.horizon, 1e3 * l_now, 1e3 * k_now);
    char value[48] = "";
    if (p == kBraking) std::snprintf(value, sizeof value, " (factor %.3g)", trial[kBraking]);
    (*notes)[p] = std::string(keep ? "chosen" : "not chosen") + value + " on the held-out blocks: " + numbers +
                  (keep ? "; held at this value in the final fit" : "");
    if (!keep) return;
    *v = trial;
    k_now = k_with;
    l_now = l_with;
    chosen->insert(p);
  };
  if (turned) {
    std::array<double, kNumParams> trial = *v;
    trial[kFieldFrame] = 1;
    decide(kFieldFrame, trial);
  } else {
    (*notes)[kFieldFrame] = "not tried: the fit blocks never command a turn, where the frames differ";
  }
  // Braking: log-spaced factors around 1, the best refined by a parabola through it and
  // its neighbours.
  const std::vector<double> grid = {0.25, 0.35, 0.5, 0.7, 1, 1.4, 2, 2.8};
  std::vector<double> cost;
  for (double b : grid) {
    std::array<double, kNumParams> trial = *v;
    trial[kBraking] = b;
    cost.push_back(lookahead.Cost(trial));
  }
  const std::size_t best = static_cast<std::size_t>(std::min_element(cost.begin(), cost.end()) - cost.begin());
  // Refined also where the grid's best is 1: the minimum may lie between 1 and a
  // neighbour (measured: 0.7 and 1 within 0.04 % of each other, the parabola's minimum
  // at 0.83).
  double b = grid[best];
  if (best > 0 && best + 1 < grid.size() && std::isfinite(cost[best - 1]) && std::isfinite(cost[best + 1])) {
    const double x0 = std::log(grid[best - 1]), x1 = std::log(grid[best]), x2 = std::log(grid[best + 1]);
    const double c0 = cost[best - 1], c1 = cost[best], c2 = cost[best + 1];
    const double denom = (x0 - x1) * (x0 - x2) * (x1 - x2);
    const double a = (x2 * (c1 - c0) + x1 * (c0 - c2) + x0 * (c2 - c1)) / denom;
    const double bb = (x2 * x2 * (c0 - c1) + x1 * x1 * (c2 - c0) + x0 * x0 * (c1 - c2)) / denom;
    if (a > 0) b = std::exp(std::clamp(-bb / (2 * a), x0, x2));
  }
  if (std::abs(std::log(b)) < std::log(kBrakingSameAsSpeedingUp)) {
    (*notes)[kBraking] = "not chosen: braking as fast as speeding up predicts the fit blocks best";
    return;
  }
  std::array<double, kNumParams> trial = *v;
  trial[kBraking] = b;
  decide(kBraking, trial);
}

// The robot's body velocity from measured poses (central differences over measured
// neighbours), the command sent `delay` (s) earlier, and the nominal and identified
// models' estimate of it after each frame (the observer's: what the model's filter
// makes of the camera; with the tracker's state, the velocity of its one-frame
// predictions of the neighbours), for the report's plots over the first stretch of the
// log (its fit and held-out blocks alike). Its one-frame prediction differenced against
// the measured pose a frame before, as until 2026-12-07, charged a filter that smooths
// the camera with the camera's noise: on the Robotino's axis runs the identified turn
// rate swung +-0.35 rad/s that way, the nominal model's, whose filter follows the
// camera, +-0.1.
OmniIdentificationSeries MakeSeries(const OmniLog& log, const OmniModel& nominal, const OmniModel& identified,
                                    const OmniIdentificationOptions& options, double delay) {
  OmniIdentificationSeries s;
  s.log = log.path;
  const std::size_t n = log.rows.size();
  if (n < 8) return s;
  OmniReplayOptions o;
  o.backend = options.backend;
  o.state = options.state;
  o.horizon = 1;
  o.features = options.state == OmniReplayState::kObserver;
  const OmniReplayResult rn = ReplayOmniLog(nominal, log, o);
  const OmniReplayResult ri = ReplayOmniLog(identified, log, o);
  auto body = [&](const Pose2& a, const Pose2& b, double dt, double theta) {
    const Twist2 v = FieldToBody(Twist2{(b.x - a.x) / dt, (b.y - a.y) / dt, (b.theta - a.theta) / dt}, theta);
    return std::array<double, 3>{v.vx, v.vy, v.omega};
  };
  // A model's velocity at row i, or nothing where it has none.
  auto model = [&](const OmniReplayResult& r, std::size_t i) -> std::optional<std::array<double, 3>> {
    if (o.features) {
      // After the warm-up (predicted), as the tracker's: not the filter settling.
      if (!r.predicted[i] || i >= r.input_feature.size() || r.input_feature[i].size() == 0) return std::nullopt;
      const Twist2& v = r.estimated_velocity[i];
      return std::array<double, 3>{v.vx, v.vy, v.omega};
    }
    if (!r.predicted[i - 1] || !r.predicted[i + 1]) return std::nullopt;
    return body(r.pose[i - 1], r.pose[i + 1], log.rows[i + 1].t - log.rows[i - 1].t, log.rows[i].pose.theta);
  };
  for (std::size_t i = 1; i + 1 < n; ++i) {
    if (!log.rows[i].measured || !log.rows[i - 1].measured || !log.rows[i + 1].measured) continue;
    const auto vn = model(rn, i), vi = model(ri, i);
    if (!vn || !vi) continue;
    const OmniLogRow& a = log.rows[i - 1];
    const OmniLogRow& b = log.rows[i + 1];
    s.t.push_back(log.rows[i].t);
    s.measured.push_back(body(a.pose, b.pose, b.t - a.t, log.rows[i].pose.theta));
    s.nominal.push_back(*vn);
    s.identified.push_back(*vi);
    std::size_t j = i;
    while (j > 0 && log.rows[j].t > log.rows[i].t - delay + 1e-9) --j;
    const Twist2& c = log.rows[j].command;
    s.command.push_back({c.vx, c.vy, c.omega});
  }
  return s;
}

}  // namespace

OmniGap OmniHeldOutGap(const OmniModel& model, const std::vector<OmniLog>& logs, const OmniIdentificationOptions& options,
                       const std::string& name, double radius) {
  double block = 0;
  return ToGap(ScoreHeldOut(MakeSegments(logs, {}, options, &block), &model, false, options, radius), name);
}

bool OmniIdentificationOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (horizon < 1 || horizon > 60) return fail("--horizon must be 1 to 60 frames, got " + std::to_string(horizon));
  if (!(held_out > 0 && held_out < 1)) return fail("--held-out must lie strictly between 0 and 1");
  if (!(block_seconds >= 0 && block_seconds <= 3600)) return fail("--block must be 0 (automatic) to 3600 s");
  if (stride < 1 || stride > 60) return fail("--stride must be 1 to 60 frames, got " + std::to_string(stride));
  if (max_iterations < 1 || max_iterations > 1000) return fail("--max-iterations must be 1 to 1000");
  if (!(max_delay > 0 && max_delay <= 2)) return fail("--max-delay must be above 0 and at most 2 s");
  if (threads < 0) return fail("--threads must be 0 (one per core) or more");
  if (backend == "learned") return fail("--backend: identification fits a physical model (analytic, ode or bullet)");
  return true;
}

const OmniGap* OmniIdentificationReport::Gap(const std::vector<OmniGap>& gaps, const std::string& name) const {
  for (const OmniGap& g : gaps)
    if (g.name == name) return &g;
  return nullptr;
}

namespace {

using InFit = std::function<bool(const OmniLog&, std::size_t)>;

// What the identification carries from step to step.
struct FitState {
  std::array<double, kNumParams> v{};        // the parameters now
  std::array<double, kNumParams> nominal{};  // the given model's
  std::vector<int> free;                     // estimated, in order
  std::map<int, std::string> pruned;         // left at a value, with why
  std::set<int> chosen;                      // lag structures the held-out blocks chose
  std::set<int> held;                        // held at the fit's value (collinear or flat)
  SolveResult solved;                        // the last solve, with its standard errors
  std::vector<double> speeds, turns;         // m/s, rad/s: the fit rows' commanded speed and turn rate, sorted
  std::string turn_harmonics_note;           // why the turn's third harmonic is free, where it is
};

void CheckFramePeriods(const std::vector<OmniLog>& logs, const std::vector<OmniLog>& validation) {
  const double period = logs.front().frame_period;
  for (const auto* set : {&logs, &validation}) {
    for (const OmniLog& log : *set) {
      if (std::abs(log.frame_period - period) > kSameCameraRate * period) {
        throw InputError(SourceLocation{log.path, 1},
                         "the log's frame period (" + std::to_string(log.frame_period) + " s) differs from the first "
                         "log's (" + std::to_string(period) + " s) by more than 5 %: identify logs of one camera rate "
                         "together");
      }
    }
  }
}

// The start: the model's values; a lag to move from (a given lag in series added to
// each axis's: one lag of the sum keeps the pair's mean delay); no limits (added below if
// reached); the lag's structures and a three-wheel robot's turn by direction off,
// whatever the given model has (the logs choose them, step 5).
std::array<double, kNumParams> StartValues(const OmniModel& nominal, double period) {
  std::array<double, kNumParams> v = ValuesOf(nominal, period);
  for (int a = 0; a < 3; ++a) {
    double& lag = v[static_cast<std::size_t>(kLagX + a)];
    lag += nominal.effects.lag_series;
    if (lag <= 0) lag = kStartLag;
  }
  for (int p : {kSlewX, kSlewY, kSlewW}) {
    if (v[static_cast<std::size_t>(p)] <= 0) v[static_cast<std::size_t>(p)] = Specs()[p].upper;
  }
  v[kBraking] = 1;
  v[kFieldFrame] = 0;
  if (nominal.num_wheels() == 3) v[kTurn3S] = v[kTurn3C] = 0;
  return v;
}

// Which axes the fit blocks command, and so which parameters are free. An axis the fit
// blocks never command (below 2 % of the largest command) leaves its parameters, and the
// couplings it drives, at the model's values: the logs say nothing of them. The
// observer's noise is fitted with the physical parameters from the start: fitted last,
// it let the filter absorb what a speed limit explains (w_max went unfound). Throws
// InputError when no axis is commanded.
std::array<bool, 3> ChooseFreeParameters(const std::vector<OmniLog>& logs, const InFit& in_fit,
                                         const OmniIdentificationOptions& options, FitState* fit) {
  double most[3] = {0, 0, 0};
  for (const OmniLog& log : logs) {
    for (std::size_t i = 0; i < log.rows.size(); ++i) {
      if (!in_fit(log, i)) continue;
      const Twist2& c = log.rows[i].command;
      most[0] = std::max(most[0], std::abs(c.vx));
      most[1] = std::max(most[1], std::abs(c.vy));
      most[2] = std::max(most[2], std::abs(c.omega));
    }
  }
  const double speed_scale = std::max({most[0], most[1], 1e-9});
  const std::array<bool, 3> excited = {most[0] > 0.02 * speed_scale && most[0] > 0.01,
                                       most[1] > 0.02 * speed_scale && most[1] > 0.01, most[2] > 0.02};
  if (!excited[0] && !excited[1] && !excited[2]) {
    throw InputError(SourceLocation{logs.front().path, 1},
                     "the robot is never commanded to move in the fit blocks (every command under 1 cm/s and "
                     "0.02 rad/s): a log of a robot that stood still says nothing of its response (is --robot the "
                     "one that drove?)");
  }
  for (int a = 0; a < 3; ++a) {
    if (excited[static_cast<std::size_t>(a)]) continue;
    std::vector<int> tied = {kGainX + a, kLagX + a, kLoopX + a, kSlewX + a};
    if (a == 0) tied.insert(tied.end(), {kTurnX, kCrossYX});
    if (a == 1) tied.insert(tied.end(), {kTurnY, kCrossXY});
    for (int p : tied) fit->pruned[p] = std::string("not excited: the fit blocks never command ") + kOmniAxisNames[a];
  }
  if (options.state != OmniReplayState::kObserver) {
    for (int p : {kNoiseX, kNoiseY, kNoiseW, kNoiseTime, kProcessScale})
      fit->pruned[p] = "the open-loop tracker (--state tracker) has no observer";
  }
  for (int p = 0; p < kNumParams; ++p)
    if (p != kVMax && p != kWMax && p != kBraking && p != kFieldFrame && p != kTurn3S && p != kTurn3C &&
        !fit->pruned.count(p))
      fit->free.push_back(p);
  for (const auto& [p, why] : fit->pruned) fit->v[static_cast<std::size_t>(p)] = fit->nominal[static_cast<std::size_t>(p)];
  return excited;
}

// Step 3b: an axis whose lag ended at the top of its range (1 s) has most often fallen
// into a valley beside the data's: on a 30 s log of a plant written apart (a 60 ms turn
// lag) the turn's lag went to 1 s with a loop gain of 15 and turn couplings of 0.8 rad/s
// per m/s standing in for the response, at a fit cost 15 % above the valley a restart
// finds. Each such axis is fitted again from a short lag, a loop gain of 1 and no
// couplings into it, the rest where the fit left it, and the lower cost kept (a note
// says so).
void RestartLagsAtTheirCeiling(const OmniIdentificationProblem& problem, const OmniIdentificationOptions& options,
                               const std::vector<int>& free, std::array<double, kNumParams>* v, double* cost,
                               std::vector<std::string>* notes, int* iterations) {
  static constexpr std::array<std::array<int, 2>, 3> kInto = {{{kCrossXY, -1}, {kCrossYX, -1}, {kTurnX, kTurnY}}};
  for (int a = 0; a < 3; ++a) {
    const int lag = kLagX + a;
    const double at = (*v)[static_cast<std::size_t>(lag)];
    if (!IsFree(free, lag) || at < 0.9 * Specs()[lag].upper) continue;
    std::array<double, kNumParams> trial = *v;
    trial[static_cast<std::size_t>(lag)] = kStartLag;
    trial[static_cast<std::size_t>(kLoopX + a)] = 1;
    for (int p : kInto[static_cast<std::size_t>(a)]) {
      if (p >= 0 && IsFree(free, p)) trial[static_cast<std::size_t>(p)] = 0;
    }
    try {
      const SolveResult other = Solve(problem, trial, free, options.max_delay, options.max_iterations, false);
      *iterations += other.iterations;
      char text[320];
      std::snprintf(text, sizeof text,
                    "the %s lag ended at the top of its range (%.3g s, loop gain %.3g); fitted again from %.3g s it "
                    "reached %.3g s at a fit cost of %.4g against %.4g: %s",
                    kOmniAxisNames[a], at, (*v)[static_cast<std::size_t>(kLoopX + a)], kStartLag,
                    other.values[static_cast<std::size_t>(lag)], other.cost, *cost,
                    other.cost < *cost ? "kept" : "the first fit kept");
      notes->push_back(text);
      if (other.cost < *cost) {
        *cost = other.cost;
        *v = other.values;
      }
    } catch (const CheckFailed&) {
      // The model diverges from there: the first valley stays.
    }
  }
}

// Steps 1 to 3. 1: the delay on a half-frame grid (the fit below is local, and the cost
// has a valley per frame of delay), with gains and couplings from a linear regression of
// the measured velocity on the delayed command as the start; the regression once more at
// the delay found. 2: everything but the speed limits, the delay included (a command
// falling due within a physics step acts for its rest, so the cost is smooth in the
// delay). 3: the neighbouring valleys: a longer delay trades against a faster response,
// so the fit is restarted a frame either side and the best kept; then a lag at its
// ceiling is restarted (RestartLagsAtTheirCeiling).
void FitDelayAndResponse(const OmniIdentificationProblem& problem, const std::vector<OmniLog>& logs, const InFit& in_fit,
                         const OmniIdentificationOptions& options, double period,
                         const std::function<void(int, const std::string&)>& say, FitState* fit,
                         OmniIdentificationReport* report) {
  say(0, "delay profile");
  std::array<double, kNumParams>& v = fit->v;
  v[kDelay] = ProfileDelay(problem, v, 0, options.max_delay, period / 2, nullptr, nullptr);
  LinearStart(logs, v[kDelay], in_fit, fit->free, &v);
  v[kDelay] = ProfileDelay(problem, v, 0, options.max_delay, period / 2, &report->delay_profile_s,
                           &report->delay_profile_rms);
  LinearStart(logs, v[kDelay], in_fit, fit->free, &v);
  say(1, "delay, response and couplings");
  const SolveResult solved = Solve(problem, v, fit->free, options.max_delay, options.max_iterations, false);
  v = solved.values;
  report->solver_iterations += solved.iterations;
  say(2, "neighbouring delays");
  double best = problem.Cost(v);
  const std::array<double, kNumParams> centre = v;
  for (double shift : {-period, period}) {
    std::array<double, kNumParams> trial = centre;
    trial[kDelay] = centre[kDelay] + shift;
    if (trial[kDelay] < 0 || trial[kDelay] > options.max_delay) continue;
    try {
      const SolveResult other = Solve(problem, trial, fit->free, options.max_delay, options.max_iterations / 2, false);
      report->solver_iterations += other.iterations;
      if (other.cost < best) {
        best = other.cost;
        v = other.values;
      }
    } catch (const CheckFailed&) {
      // The model diverges at that delay: not a valley to try.
    }
  }
  RestartLagsAtTheirCeiling(problem, options, fit->free, &v, &best, &report->notes, &report->solver_iterations);
}

// Step 4: speed limits, where the commands go beyond what the robot reached: each is kept
// when it lowers the fit blocks' lookahead error by more than 0.3 % (a limit touches few
// frames, and a K-frame prediction from the observer's velocity hardly sees it).
void FitSpeedLimits(const OmniIdentificationProblem& lookahead, const std::vector<OmniLog>& logs, const InFit& in_fit,
                    FitState* fit) {
  std::array<double, kNumParams>& v = fit->v;
  for (const OmniLog& log : logs) {
    for (std::size_t i = 0; i < log.rows.size(); ++i) {
      if (!in_fit(log, i)) continue;
      const Twist2& c = log.rows[i].command;
      fit->speeds.push_back(std::hypot(v[kGainX] * c.vx + v[kCrossXY] * c.vy, v[kGainY] * c.vy + v[kCrossYX] * c.vx));
      fit->turns.push_back(std::abs(v[kGainW] * c.omega + v[kTurnX] * c.vx + v[kTurnY] * c.vy));
    }
  }
  std::sort(fit->speeds.begin(), fit->speeds.end());
  std::sort(fit->turns.begin(), fit->turns.end());
  double base_cost = lookahead.Cost(v);
  for (int p : {kVMax, kWMax}) {
    const std::vector<double>& sorted = p == kVMax ? fit->speeds : fit->turns;
    double best_cost = base_cost, best_limit = 0;
    for (double q : {0.6, 0.75, 0.85, 0.92, 0.96, 0.98, 0.99, 0.995}) {
      const double limit = sorted[std::min(sorted.size() - 1, static_cast<std::size_t>(q * static_cast<double>(sorted.size())))];
      if (limit < Specs()[p].lower) continue;
      std::array<double, kNumParams> trial = v;
      trial[static_cast<std::size_t>(p)] = limit;
      const double c = lookahead.Cost(trial);
      if (c < best_cost) {
        best_cost = c;
        best_limit = limit;
      }
    }
    if (best_limit > 0 && best_cost < 0.997 * base_cost) {
      v[static_cast<std::size_t>(p)] = best_limit;
      fit->free.push_back(p);
      base_cost = best_cost;
    }
  }
}

// Step 5, after the lag's structures, three-wheel robots: a turn that varies with the
// direction the robot drives in, v (s sin 3φ + c cos 3φ) (turn_coupling's third_sin and
// third_cos; omni_effects.h). Three wheels 120° apart turn the robot by the sum of their
// own losses: where the wheels lose alike that sum repeats every 120° of direction (the
// third harmonic), where they differ it has a first harmonic too, which the axis
// couplings (v cos φ, v sin φ) hold. Tried where the fit rows' commands tell the four
// apart (TurnHarmonicsExcited: logs driving only along the robot's axes cannot, sin 3φ =
// −sin φ there), fitted alone from none, and kept free for the final fit where the
// held-out blocks ask for it as for the lag's structures; the verdict goes into the notes.
// The smallest share of the largest singular value the four unit columns vx, vy, v sin
// 3φ, v cos 3φ must keep: below, the directions driven alias the harmonic.
constexpr double kHarmonicsConditioning = 1.0 / 30;

bool TurnHarmonicsExcited(const std::vector<OmniLog>& logs, const InFit& in_fit) {
  // The effect's own harmonics: v sin 3φ and v cos 3φ are its turn at a unit coefficient.
  OmniEffects sin3, cos3;
  sin3.turn_third_sin = cos3.turn_third_cos = 1;
  std::vector<double> rows;  // vx, vy, v sin 3φ, v cos 3φ per fit row
  for (const OmniLog& log : logs) {
    for (std::size_t i = 0; i < log.rows.size(); ++i) {
      const Twist2& c = log.rows[i].command;
      if (!in_fit(log, i) || c.vx * c.vx + c.vy * c.vy < 1e-4) continue;  // under 1 cm/s: no direction
      rows.insert(rows.end(), {c.vx, c.vy, sin3.TurnByDirection(c.vx, c.vy), cos3.TurnByDirection(c.vx, c.vy)});
    }
  }
  const long n = static_cast<long>(rows.size() / 4);
  if (n < 8) return false;
  Eigen::MatrixXd x = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>>(rows.data(), n, 4);
  // A column nearly zero (an axis never driven, or directions 60° apart from an axis,
  // where sin 3φ vanishes) leaves the harmonic aliased; the rest scaled to unit length.
  const Eigen::VectorXd norms = x.colwise().norm();
  if (norms.minCoeff() < 1e-3 * norms.maxCoeff()) return false;
  for (int k = 0; k < 4; ++k) x.col(k) /= norms(k);
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(x).singularValues();
  return sv(3) > kHarmonicsConditioning * sv(0);
}

constexpr const char* kTooFewDirections =
    "not tried: the fit blocks drive in too few directions to tell it from the axis couplings";

void ChooseTurnByDirection(const OmniIdentificationProblem& problem, const OmniIdentificationProblem& lookahead,
                           const std::vector<Segment>& segments, const std::vector<OmniLog>& logs, const InFit& in_fit,
                           const OmniIdentificationOptions& options, const OmniIdentificationOptions& ahead,
                           FitState* fit, int* iterations) {
  std::map<int, std::string>& notes = fit->pruned;
  if (problem.nominal().num_wheels() != 3) return;  // not reported: a three-wheel robot's structure
  if (!options.turn_harmonics) {
    notes[kTurn3S] = notes[kTurn3C] = "not tried (--no-turn-harmonics)";
    return;
  }
  if (!TurnHarmonicsExcited(logs, in_fit)) {
    notes[kTurn3S] = notes[kTurn3C] = kTooFewDirections;
    return;
  }
  std::array<double, kNumParams> trial = fit->v;
  trial[kTurn3S] = trial[kTurn3C] = 0;
  try {
    const SolveResult solved =
        Solve(problem, trial, {kTurn3S, kTurn3C}, options.max_delay, options.max_iterations, false);
    *iterations += solved.iterations;
    trial = solved.values;
  } catch (const CheckFailed&) {
    notes[kTurn3S] = notes[kTurn3C] = "not chosen: the model diverges with it";
    return;
  }
  // Judged by the pose (the heading at the chassis' rim beside the position): a turn
  // rate shows in the heading a quarter second ahead long before in the position.
  const double k_now = HeldOutRmse(lookahead, segments, options, fit->v, true);
  const double l_now = HeldOutRmse(lookahead, segments, ahead, fit->v, true);
  const double k_with = HeldOutRmse(lookahead, segments, options, trial, true);
  const double l_with = HeldOutRmse(lookahead, segments, ahead, trial, true);
  const bool keep = l_with < (1 - kStructureGain) * l_now && k_with < (1 + kStructureTolerance) * k_now;
  char numbers[200];
  std::snprintf(numbers, sizeof numbers,
                "pose %.3g mm at %d frames and %.3g mm at %d with it, %.3g and %.3g mm without (s %.3g, c %.3g)",
                1e3 * l_with, ahead.horizon, 1e3 * k_with, options.horizon, 1e3 * l_now, 1e3 * k_now,
                trial[kTurn3S], trial[kTurn3C]);
  if (!keep) {
    notes[kTurn3S] = notes[kTurn3C] = std::string("not chosen on the held-out blocks: ") + numbers;
    return;
  }
  fit->v = trial;
  fit->free.push_back(kTurn3S);
  fit->free.push_back(kTurn3C);
  fit->turn_harmonics_note = std::string("chosen on the held-out blocks: ") + numbers;
}

// Step 6: all together, kept only where it does not predict the held-out blocks worse
// than before it (the fit blocks can pull a misfit structure away from what generalises:
// early stopping).
void FitTogether(const OmniIdentificationProblem& problem, const std::vector<Segment>& segments,
                 const OmniIdentificationOptions& options, FitState* fit, OmniIdentificationReport* report) {
  const double before = HeldOutRmse(problem, segments, options, fit->v);
  const SolveResult solved = Solve(problem, fit->v, fit->free, options.max_delay, options.max_iterations, false);
  report->solver_iterations += solved.iterations;
  const double after = HeldOutRmse(problem, segments, options, solved.values);
  if (after <= (1 + kStructureTolerance) * before) {
    fit->v = solved.values;
  } else {
    char numbers[160];
    std::snprintf(numbers, sizeof numbers, "%.3g mm against %.3g mm", 1e3 * after, 1e3 * before);
    report->notes.push_back(std::string("the final joint fit predicted the held-out blocks worse (") + numbers +
                            " at the fit's horizon): the estimate before it is kept");
  }
}

// After step 6: what ends at the edge of its range is what the data does not ask for (a
// lag at its floor is none, a ramp at its ceiling no limit); the standard errors are
// for the rest, parameters the logs cannot tell apart held at the fit's value; a limit
// the fit pushed beyond every command the robot got is no limit.
void StandardErrors(const OmniIdentificationProblem& problem, const OmniIdentificationOptions& options, FitState* fit,
                    OmniIdentificationReport* report) {
  for (int p : std::vector<int>(fit->free)) {
    const ParamSpec& s = Specs()[p];
    double& value = fit->v[static_cast<std::size_t>(p)];
    const double upper = p == kDelay ? options.max_delay : s.upper;
    const bool at_lower = s.log_scale ? value <= 1.05 * s.lower : value <= s.lower + 1e-3 * (upper - s.lower);
    const bool at_upper = s.log_scale ? value >= upper / 1.05 : value >= upper - 1e-3 * (upper - s.lower);
    if (!at_lower && !at_upper) continue;
    std::string& why = fit->pruned[p];
    if (p >= kLagX && p <= kLagW && at_lower) {
      value = 0;
      why = "no lag beyond the controller's";
    } else if (p >= kSlewX && p <= kSlewW && at_upper) {
      value = 0;
      why = "no ramp limit";
    } else if (p >= kNoiseX && p <= kNoiseW && at_lower) {
      why = "no driving noise found on this axis: the model's response explains its motion (the floor of the range is kept)";
    } else if (p == kProcessScale && at_lower) {
      why = "the observer trusts the model's velocity (the floor of the range is kept)";
    } else {
      why = "at the edge of its range (" + std::string(at_lower ? "lower" : "upper") + "): not determined";
    }
    fit->free.erase(std::find(fit->free.begin(), fit->free.end(), p));
  }
  fit->solved = Solve(problem, fit->v, fit->free, options.max_delay, 0, true);
  report->collinearity = fit->solved.collinearity;
  for (const HeldBack& h : fit->solved.held) {
    fit->held.insert(h.param);
    std::string partners;
    for (int q : h.partners) partners += (partners.empty() ? "" : ", ") + std::string(Specs()[q].name);
    char index[32];
    std::snprintf(index, sizeof index, "%.3g", h.collinearity);
    fit->pruned[h.param] = h.partners.empty()
                               ? std::string("held at the fit's value: the fit's error does not depend on it on these logs")
                               : "held at the fit's value: on these logs it trades with " + partners +
                                     " (collinearity index " + index + "); the others' standard errors take it as known";
  }
  for (int p : {kVMax, kWMax}) {
    const std::vector<double>& sorted = p == kVMax ? fit->speeds : fit->turns;
    double& limit = fit->v[static_cast<std::size_t>(p)];
    if (limit > 0 && limit >= sorted.back()) limit = 0;
  }
}

// The covariance of the response's parameters the fit determined, for the model file
// (observer.parameter_covariance): the driving noise and the filter's trust, which
// spread the predictions themselves, and a speed limit found off, left out.
OmniObserverModel::ParameterCovariance ParameterCovarianceOf(const FitState& fit) {
  std::vector<long> rows;
  OmniObserverModel::ParameterCovariance out;
  for (std::size_t k = 0; k < fit.solved.covariance_of.size(); ++k) {
    const int p = fit.solved.covariance_of[k];
    const double var = fit.solved.covariance(static_cast<long>(k), static_cast<long>(k));
    if ((p >= kNoiseX && p <= kProcessScale) || fit.v[static_cast<std::size_t>(p)] == 0 || !(var > 0)) continue;
    rows.push_back(static_cast<long>(k));
    out.parameters.push_back(Specs()[p].name);
  }
  out.matrix = fit.solved.covariance(rows, rows);
  return out;
}

// A note where the calibration (on the validation logs where `validated`, else the
// held-out blocks) had too few rows at a horizon to check the intervals:
// short runs (the Robotino's 10 s) leave no held-out block long enough for a prediction
// 2 s ahead, and a user would otherwise read the intervals there as checked (on the
// Robotino's validation runs the heading's 90 % intervals held 20 % at 63 frames).
void NoteUncheckedIntervals(bool validated, int fit_logs, OmniIdentificationReport* report) {
  std::string horizons;
  for (const OmniCalibration& c : report->calibration) {
    if (c.rows >= kSafeguardLeastRows) continue;
    char label[64];
    std::snprintf(label, sizeof label, "%d frames (%.2g s)", c.frames, c.seconds);
    horizons += (horizons.empty() ? "" : ", ") + std::string(label);
  }
  if (horizons.empty()) return;
  char where[160];
  std::snprintf(where, sizeof where, validated ? "the validation logs hold fewer than %d predictions that long"
                                               : "fewer than %d predictions that long lie within a held-out block (%.3g s)",
                kSafeguardLeastRows, report->block_seconds);
  const std::string check = validated ? "check them on longer logs not fitted (--validate LOG, or compare)"
                                       : "check them on a log not fitted (--validate LOG, or compare)";
  report->notes.push_back("the predictive intervals " + horizons + " ahead are not checked: " + where + "; " + check +
                          (fit_logs > 1 ? " or scale them on left-out logs (--safeguard logs)" : ""));
}

// The driving noise for predictions ahead and the simulation, then its calibration.
void IdentifyNoise(const std::vector<Segment>& segments, const OmniIdentificationOptions& options,
                   const std::function<void(int, const std::string&)>& say, OmniModel* model,
                   OmniIdentificationReport* report) {
  model->observer.interval_scale.clear();  // the given model's belong to its own fit; fitted anew below
  model->observer.seen_inputs = {};
  if (options.state != OmniReplayState::kObserver) return;
  std::vector<OmniBlockedStretch> views;
  for (const Segment& s : segments) views.push_back(BlockedStretchOf(s));
  OmniNoiseOptions noise_options;
  noise_options.backend = options.backend;
  noise_options.max_delay = options.max_delay;
  noise_options.threads = options.threads;
  if (options.noise) {
    say(6, "driving noise");
    report->noise = IdentifyDrivingNoise(*model, views, noise_options);
    report->noise_identified = true;
    if (report->noise.kept) *model = report->noise.model;
    // The better of the two on the held-out blocks is the robot's own wander: run and serve draw it.
    model->driving_noise.simulated = true;
  }
  model->driving_noise.drift = {};  // the given model's, if any: fitted anew below, or none
  if (options.noise && options.drift) {
    say(6, "the noise's drift");
    report->drift = IdentifyDrift(*model, views, noise_options);
    report->drift_identified = true;
    if (report->drift.kept) {
      model->driving_noise.drift = report->drift.drift;
      for (OmniCrossedNoise& c : report->noise.crossed) c.model.driving_noise.drift = report->drift.drift;
    }
  }
  // A noise fitted on the held-out blocks is calibrated there only across the halves; the
  // validation logs with the parameters' uncertainty too, as compare does.
  const std::array<OmniCrossedNoise, 2>* crossed = report->noise.kept ? &report->noise.crossed : nullptr;
  noise_options.parameter_shifts = ParameterShiftedModels(*model, segments.front().log.frame_period);
  report->calibration = CalibrateOnBlocks(*model, views, noise_options, crossed, &report->calibration_by_distance,
                                          &report->calibration_by_turn_rate, &report->spread_budget);
  if (!report->spread_budget.empty())
    report->spread_budget_on = crossed ? "held-out blocks, each half with the noise fitted on the other" : "held-out blocks";
  // (Under --safeguard logs the left-out logs check them.)
  if (options.safeguard != OmniSafeguard::kLogs) {
    std::set<int> fit_logs;  // a segment is a piece of one log: its blocks' numbers say which
    bool validated = false;
    for (const Segment& s : segments) {
      validated = validated || s.validation;
      if (!s.validation && !s.block.empty()) fit_logs.insert(s.block.front() / kBlocksPerLog);
    }
    NoteUncheckedIntervals(validated, static_cast<int>(fit_logs.size()), report);
  }
  // The scale within the fit's reach: the safeguard of "blocks", the base of "logs".
  if (options.safeguard != OmniSafeguard::kOff) {
    say(6, "intervals' safeguard");
    report->safeguard = FitIntervalSafeguard(*model, views, noise_options, crossed);
    model->observer.interval_scale = report->safeguard.Scales();
  }
  // The inputs of the fit, which a growth over left-out logs measures distances from
  // (taken last: the held-out blocks above lie within the fit's reach and read none).
  if (options.safeguard == OmniSafeguard::kLogs || options.keep_seen_inputs)
    model->observer.seen_inputs = SeenInputsOfFitBlocks(*model, views, noise_options);
}

// The intervals' safeguard on left-out logs (options.safeguard kLogs): each log predicted,
// at the safeguard's horizons, by the model identified on the others (its noise and its
// camera with it), and the safeguard fitted with each log a fold. A log that drives
// differently from the others (another direction, another floor) is then what the
// scale is checked on: the model's own error out of its fit's reach, not only the
// robot's wander.
// With options.drift, the noise's drift is fitted first on the left-out logs'
// predictions (the model's own error on a run it did not see, as that run's drift) into
// *drift, and each left-out log is predicted with it where kept. (The held-out blocks'
// scales, the growth's base, were fitted with the fit logs' drift.)
OmniIntervalSafeguard LeftOutLogsSafeguard(const OmniModel& nominal, const std::vector<OmniLog>& logs,
                                           const OmniIdentificationOptions& options, const OmniIntervalSafeguard& blocks,
                                           const std::function<void(int, const std::string&)>& say,
                                           OmniDriftIdentification* drift) {
  OmniNoiseOptions noise_options;
  noise_options.backend = options.backend;
  noise_options.threads = options.threads;
  const std::vector<int> horizons = SafeguardHorizons(noise_options.horizons);
  OmniIdentificationOptions fold = options;
  fold.safeguard = OmniSafeguard::kOff;
  fold.keep_seen_inputs = true;  // each left-out log's distances from the others' fit
  std::vector<OmniModel> models(logs.size());
  std::vector<const OmniLog*> left_out_logs;
  for (std::size_t i = 0; i < logs.size(); ++i) {
    say(6, "intervals' safeguard: " + std::to_string(i + 1) + " of " + std::to_string(logs.size()) + " logs left out");
    std::vector<OmniLog> others;
    for (std::size_t j = 0; j < logs.size(); ++j)
      if (j != i) others.push_back(logs[j]);
    IdentifyOmni(nominal, others, {}, fold, &models[i]);
    left_out_logs.push_back(&logs[i]);
  }
  if (options.noise && options.drift) {
    say(6, "the noise's drift on the left-out logs");
    *drift = IdentifyDriftOnLeftOutLogs(models, left_out_logs, noise_options);
    for (OmniModel& m : models) m.driving_noise.drift = drift->kept ? drift->drift : OmniDrivingNoise::Drift{};
  }
  std::vector<std::vector<std::vector<SafeguardRow>>> rows(horizons.size(),
                                                           std::vector<std::vector<SafeguardRow>>(logs.size()));
  for (std::size_t i = 0; i < logs.size(); ++i) {
    const std::vector<std::vector<PredictiveError>> left_out =
        OmniLogPredictiveErrors(models[i], logs[i], options.backend, horizons, noise_options.score_stride);
    for (std::size_t q = 0; q < horizons.size(); ++q)
      AppendSafeguardRows(left_out[q], MeasurementCovariance(models[i]), &rows[q][i]);
  }
  // The held-out blocks' scales (1 where they kept none) are the base the growth adds to;
  // where too few of their predictions reach a horizon to check it (short runs: the
  // Robotino's 10 s leave none 0.5 s long), the left-out logs fit the scale itself, which
  // may narrow the intervals as well as widen them.
  constexpr double kNoBase = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::array<double, 2>> base(horizons.size(), {kNoBase, kNoBase});
  for (std::size_t q = 0; q < horizons.size(); ++q) {
    for (const OmniSafeguardHorizon& h : blocks.horizons)
      if (h.frames == horizons[q] && h.position_check[0].rows > 0) base[q] = {h.position, h.heading};
  }
  OmniIntervalSafeguard out = SafeguardFromFolds(horizons, rows, noise_options.score_stride, kSafeguardLeastRows, &base);
  const bool own = std::any_of(base.begin(), base.end(), [](const auto& b) { return !std::isfinite(b[0]); });
  out.on = own ? "left-out logs, a growth over the held-out blocks' scale, or a scale of their own where too few "
                 "held-out predictions reach"
               : "left-out logs, a growth over the held-out blocks' scale";
  return out;
}

// With options.safeguard kLogs (and the observer's state), the safeguard on left-out
// logs into the report and the model. The fit's seen inputs stay in the model only where
// a scale grows with them (or options.keep_seen_inputs asks).
void SafeguardOnLeftOutLogs(const OmniModel& nominal, const std::vector<OmniLog>& logs,
                            const OmniIdentificationOptions& options,
                            const std::function<void(int, const std::string&)>& say, OmniModel* model,
                            OmniIdentificationReport* report) {
  if (options.safeguard == OmniSafeguard::kLogs && options.state == OmniReplayState::kObserver) {
    OmniDriftIdentification drift;
    report->safeguard = LeftOutLogsSafeguard(nominal, logs, options, report->safeguard, say, &drift);
    model->observer.interval_scale = report->safeguard.Scales();
    // A run unlike the fit's drifts as the left-out logs did: that drift where kept.
    if (drift.kept || (!report->drift.kept && !drift.on.empty())) {
      report->drift = drift;
      report->drift_identified = true;
      model->driving_noise.drift = drift.kept ? drift.drift : OmniDrivingNoise::Drift{};
    }
  }
  const auto& scales = model->observer.interval_scale;
  if (!options.keep_seen_inputs && std::none_of(scales.begin(), scales.end(), [](const auto& h) {
        return h.position_growth > 0 || h.heading_growth > 0;
      })) {
    model->observer.seen_inputs = {};  // no scale grows: the model file need not carry them
  }
}

// Refuses no logs, and one log to leave out.
void CheckLogCount(const std::vector<OmniLog>& logs, const OmniIdentificationOptions& options) {
  if (logs.empty()) throw InputError("identify needs at least one log");
  if (options.safeguard == OmniSafeguard::kLogs && logs.size() < 2)
    throw InputError("--safeguard logs needs at least two logs to fit on (each is predicted by the model of the others)");
}

// The report's parameter table, the delay first, each with its standard error or why it
// has none; the noise identified for predictions ahead replaces the fit's (the filter's
// tuning).
void ReportParameters(const FitState& fit, const OmniModel& model, OmniIdentificationReport* report) {
  std::vector<int> listed = {kDelay, kGainX, kGainY, kGainW, kLagX, kLagY, kLagW, kBraking, kFieldFrame,
                             kLoopX, kLoopY, kLoopW, kSlewX, kSlewY, kSlewW, kTurnX, kTurnY, kCrossYX, kCrossXY,
                             kVMax, kWMax, kNoiseX, kNoiseY, kNoiseW, kNoiseTime, kProcessScale};
  // The turn's third harmonic is a three-wheel robot's (ChooseTurnByDirection).
  if (model.num_wheels() == 3)
    listed.insert(std::find(listed.begin(), listed.end(), kCrossYX), {kTurn3S, kTurn3C});
  for (int p : listed) {
    IdentifiedParameter q;
    const ParamSpec& s = Specs()[p];
    q.name = s.name;
    q.key = s.key;
    q.unit = s.unit;
    q.meaning = s.meaning;
    q.nominal = fit.nominal[static_cast<std::size_t>(p)];
    q.value = fit.v[static_cast<std::size_t>(p)];
    const auto it = std::find(fit.free.begin(), fit.free.end(), p);
    q.estimated = it != fit.free.end();
    q.held = fit.held.count(p) > 0;
    if (fit.chosen.count(p)) q.estimated = q.held = true;  // a structure: chosen, then held
    if (fit.pruned.count(p)) q.note = fit.pruned.at(p);
    if (q.estimated && (p == kTurn3S || p == kTurn3C) && q.note.empty()) q.note = fit.turn_harmonics_note;
    if (q.estimated && !q.held) {
      q.standard_error = fit.solved.standard_error[static_cast<std::size_t>(it - fit.free.begin())];
      if (!std::isfinite(q.standard_error)) q.note = "not determined by these logs alone (the fit's covariance is singular)";
    }
    if ((p == kVMax || p == kWMax) && q.value == 0) {
      q.estimated = false;
      q.note = "none found: the robot reached what it was commanded";
    }
    if (p == kDelay) {
      q.note = "a log of commands and poses holds only the total; the model keeps its vision frames (" +
               std::to_string(model.vision_delay_frames) + ") and puts the rest on the command side";
    }
    report->parameters.push_back(q);
  }
  if (!report->noise.kept) return;
  const std::map<std::string, std::string> replaced = {{"driving_noise.forward", "forward"},
                                                       {"driving_noise.sideways", "sideways"},
                                                       {"driving_noise.turn", "turn"},
                                                       {"driving_noise.correlation_time", "correlation_time"},
                                                       {"process_noise.scale", "process_noise_scale"}};
  for (IdentifiedParameter& q : report->parameters) {
    auto it = replaced.find(q.name);
    if (it == replaced.end()) continue;
    for (const OmniNoiseParameter& n : report->noise.parameters) {
      if (n.name != it->second) continue;
      q.note = "identified for predictions ahead (the driving noise's likelihood at 4, 16 and 63 frames); the "
               "4-frame fit gave " + PrintfNumber("%.4g", q.value);
      q.value = n.name == "process_noise_scale" ? q.value * n.value : n.value;
      q.standard_error = n.name == "process_noise_scale" ? q.value / n.value * n.standard_error : n.standard_error;
      q.estimated = true;
      q.held = !std::isfinite(q.standard_error);
      if (q.held) q.note += "; held at this value: the likelihood is flat along it with others (no standard error)";
    }
  }
}

// What the table's held and undetermined parameters ask of the logs.
void NoteUndetermined(const FitState& fit, OmniIdentificationReport* report) {
  bool any_undetermined = false;
  for (const auto& q : report->parameters) {
    any_undetermined = any_undetermined || (q.estimated && !q.held && !std::isfinite(q.standard_error));
  }
  if (!fit.held.empty()) {
    report->notes.push_back(std::to_string(fit.held.size()) +
                            " parameter(s) held at the fit's value because these logs cannot tell them from others "
                            "(their notes say which): drive every axis, alone and together, at several speeds and "
                            "with steps as well as ramps to separate them");
  }
  if (any_undetermined) {
    report->notes.push_back("the fit's covariance is singular: some parameters trade off against each other on these logs "
                            "(drive every axis, alone and together, at several speeds to separate them)");
  }
  // Issue 64: where the intervals are reliable. Fitted on the Robotino's four axis runs,
  // the heading's 90 % intervals 2 s ahead held 37 % on the runs 30 degrees from them.
  const auto turn = fit.pruned.find(kTurn3S);
  if (turn != fit.pruned.end() && turn->second == kTooFewDirections) {
    report->notes.push_back("the fit blocks drive this three-wheel robot in too few directions to tell its turn by "
                            "direction (repeating every 120 degrees) from the axis couplings: in directions between "
                            "those driven its turn, and the heading's intervals beyond a few frames, are not checked; "
                            "drive it in twelve directions or at random to fit the turn there");
  }
}

// Step 7: gaps on the held-out blocks (validation_only false) or the validation logs,
// beside the nominal model and constant velocity, and with the observer the identified
// model from the open-loop tracker's state (what the observer adds).
std::vector<OmniGap> HeldOutGaps(const std::vector<Segment>& segments, const OmniModel& nominal, const OmniModel& model,
                                 bool validation_only, const OmniIdentificationOptions& options,
                                 OmniIdentificationReport* report) {
  std::vector<OmniGap> out;
  const double r = nominal.chassis_radius;
  const HorizonSum n = ScoreHeldOut(segments, &nominal, validation_only, options, r);
  const HorizonSum i = ScoreHeldOut(segments, &model, validation_only, options, r);
  const HorizonSum c = ScoreHeldOut(segments, nullptr, validation_only, options, r);
  if (i.rows == 0) return out;
  out.push_back(ToGap(n, "nominal model"));
  out.push_back(ToGap(i, "identified model"));
  out.push_back(ToGap(c, "constant velocity"));
  if (options.state == OmniReplayState::kObserver) {
    OmniIdentificationOptions tracker = options;
    tracker.state = OmniReplayState::kTracker;
    out.push_back(ToGap(ScoreHeldOut(segments, &model, validation_only, tracker, r), "identified model, open-loop tracker"));
  }
  if (!validation_only) report->held_out_rows = static_cast<int>(i.rows);
  return out;
}

// Every horizon a simulator needs, on the validation logs if there are any: rows in
// held-out blocks (or the validation logs), predicted from a start after the piece's
// lead-in and the longest warm-up, wherever it lies (analysis/omni_horizons.h); the
// seed's linear predictor beside the models where it was trained.
void ScoreHorizons(const std::vector<Segment>& segments, const OmniModel& nominal, const OmniModel& model,
                   std::shared_ptr<const OmniPredictor> linear, bool on_validation,
                   const OmniIdentificationOptions& options, double delay, double period,
                   OmniIdentificationReport* report) {
  std::vector<HorizonPredictor> predictors = {{"nominal model", &nominal},
                                              {"identified model", &model},
                                              {"constant velocity", nullptr, HorizonPredictor::kConstantVelocity},
                                              {"integrated command", nullptr, HorizonPredictor::kIntegratedCommand}};
  if (linear) predictors.push_back({"linear predictor", &model, HorizonPredictor::kNone, linear});
  std::vector<HorizonStretch> stretches;
  for (const Segment& s : segments) {
    if (s.validation != on_validation) continue;
    stretches.push_back({&s.log, s.held, s.score_from,
                         static_cast<int>(std::ceil(options.max_delay / s.log.frame_period)) + kWarmUpFrames});
  }
  HorizonOptions ho;
  ho.backend = options.backend;
  ho.state = options.state;
  ho.delay = delay;
  ho.radius = nominal.chassis_radius;
  ho.threads = options.threads;
  for (const auto& [label, frames] : ReportHorizons(options.horizon, period)) {
    OmniHorizonGaps h;
    h.label = label;
    h.frames = frames;
    h.seconds = frames * period;
    const std::vector<HorizonSum> sums = ScoreHorizonWithoutRunaway(stretches, &predictors, frames, ho, &report->notes);
    for (OmniHorizonGaps& done : report->horizons) done.gaps.resize(predictors.size());  // the same predictors
    for (std::size_t q = 0; q < predictors.size(); ++q) h.gaps.push_back(ToGap(sums[q], predictors[q].name));
    h.rows = static_cast<int>(sums.front().rows);
    report->horizons.push_back(h);
  }
  report->horizons_on = on_validation ? "validation logs" : "held-out blocks";
  if (!predictors.back().learned) return;
  std::vector<std::string> labels;
  std::vector<int> rows;
  std::vector<double> learned, identified;
  for (const OmniHorizonGaps& h : report->horizons) {
    labels.push_back(h.label);
    rows.push_back(h.rows);
    learned.push_back(h.gaps.back().rmse);
    identified.push_back(h.gaps[1].rmse);
  }
  const std::string wins = LinearPredictorWinsNote("the fit blocks", "the " + report->horizons_on,
                                                   "the identified model", labels, rows, learned, identified);
  if (!wins.empty()) report->notes.push_back(wins);
}

// The fit's own numbers: its rows and costs (RMS per row), the noise floor of the logs,
// the delay profile as RMS, a note where constant velocity predicts the held-out blocks
// as well, and the first fit log's series for the plots.
void SummariseFit(const OmniIdentificationProblem& problem, const std::vector<Segment>& segments,
                  const std::vector<OmniLog>& all_logs, const OmniModel& nominal, const OmniModel& model,
                  const OmniIdentificationOptions& options, const FitState& fit, double nominal_cost,
                  OmniIdentificationReport* report) {
  for (const OmniPoseErrors& e : problem.Errors(problem.Build(fit.v), false, options.stride)) {
    report->fit_rows += static_cast<int>(e.rows.size());
  }
  const double fit_n = std::max(1, report->fit_rows);
  report->fit_cost_nominal = std::sqrt(nominal_cost / fit_n);
  report->fit_cost_identified = std::sqrt(problem.Cost(fit.v) / fit_n);
  report->noise_floor = OmniNoiseFloor(all_logs, nominal.chassis_radius);
  for (double& rms : report->delay_profile_rms) rms = std::sqrt(rms / fit_n);
  const OmniGap* ident = report->Gap(report->held_out, "identified model");
  const OmniGap* cv = report->Gap(report->held_out, "constant velocity");
  if (ident && cv && ident->rmse >= cv->rmse) {
    report->notes.push_back("the identified model predicts no better than extrapolating the measured poses at constant "
                            "velocity on the held-out blocks: the robot does something the model's structure cannot "
                            "express (run diagnose on the identified model, and compare with a learned predictor)");
  }
  for (const Segment& s : segments) {
    if (!s.validation) {
      report->series.push_back(MakeSeries(s.log, nominal, model, options, fit.v[kDelay]));
      break;
    }
  }
}

// Where the identified model's predicted spread comes from (analysis/omni_spread_budget.h),
// at the calibration's horizons: on the validation logs, pooled, where there are any
// (the noise step left none); else the held-out blocks' that the noise step left, given
// the final model's safeguard scale (a left-out logs' safeguard replaces the blocks').
void SpreadBudgetOn(const OmniModel& model, const std::vector<OmniLog>& validation,
                    const OmniIdentificationOptions& options, OmniIdentificationReport* report) {
  if (validation.empty()) {
    for (OmniSpreadBudget& b : report->spread_budget) b.scale = model.observer.IntervalScaleAt(b.frames)[0];
    return;
  }
  if (report->calibration.empty()) return;
  constexpr int kBudgetStride = 4;  // as compare's calibration
  std::vector<int> horizons;
  for (const OmniCalibration& c : report->calibration) horizons.push_back(c.frames);
  std::vector<std::vector<OmniSpreadBudget>> per_log;
  for (const OmniLog& log : validation) {
    per_log.emplace_back();
    OmniLogPredictiveErrors(model, log, options.backend, horizons, kBudgetStride, &per_log.back(),
                            ParameterShiftedModels(model, log.frame_period));
    if (per_log.back().empty()) per_log.pop_back();  // too short for the longest horizon
  }
  report->spread_budget = PoolSpreadBudgets(per_log);
  report->spread_budget_on = report->spread_budget.empty() ? "" : "validation logs";
}

}  // namespace

std::vector<std::array<OmniModel, 2>> ParameterShiftedModels(const OmniModel& model, double frame_period) {
  const OmniObserverModel::ParameterCovariance& pc = model.observer.parameter_covariance;
  if (pc.empty()) return {};
  const std::array<double, kNumParams> v = ValuesOf(model, frame_period);
  std::vector<int> param;
  std::vector<long> rows;  // of pc.matrix, the parameters the model has within their range
  std::vector<double> slopes;
  for (std::size_t k = 0; k < pc.parameters.size(); ++k) {
    const std::string& name = pc.parameters[k];
    int p = 0;
    while (p < kNumParams && Specs()[p].name != name) ++p;
    if (p == kNumParams || (p >= kNoiseX && p <= kProcessScale) || p == kFieldFrame) {
      throw InputError(SourceLocation{model.source_path, 0},
                       "observer.parameter_covariance names '" + name +
                           "', which is not one of the response's parameters identify fits (delay, forward.gain, ...)");
    }
    // A limit the model has off (0: no speed limit, no ramp) has no spread to move.
    const double value = v[static_cast<std::size_t>(p)];
    if (value < Specs()[p].lower || value > Specs()[p].upper) continue;
    param.push_back(p);
    rows.push_back(static_cast<long>(k));
    const double s = CoordinateSlope(p, value, Specs()[p].upper);
    slopes.push_back(std::abs(s) > 1e-12 ? s : 1e-12);
  }
  if (param.empty()) return {};
  // In coordinates (the delta method backwards), then its principal directions.
  Eigen::MatrixXd c = pc.matrix(rows, rows);
  for (long i = 0; i < c.rows(); ++i)
    for (long j = 0; j < c.cols(); ++j) c(i, j) /= slopes[static_cast<std::size_t>(i)] * slopes[static_cast<std::size_t>(j)];
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (c + c.transpose()));
  std::vector<std::array<OmniModel, 2>> out;
  const long k = c.rows();
  for (long l = k - 1; l >= 0; --l) {  // eigenvalues ascend
    const double lambda = eig.eigenvalues()[l];
    if (!(lambda > 1e-9 * eig.eigenvalues()[k - 1])) break;
    const Eigen::VectorXd step = std::sqrt(lambda) * eig.eigenvectors().col(l);
    std::array<OmniModel, 2> pair;
    for (int side = 0; side < 2; ++side) {
      std::array<double, kNumParams> w = v;
      for (std::size_t i = 0; i < param.size(); ++i) {
        const auto p = static_cast<std::size_t>(param[i]);
        const double x = ToCoordinate(param[i], v[p], Specs()[p].upper);
        w[p] = FromCoordinate(param[i], x + (side == 0 ? 1 : -1) * step[static_cast<long>(i)], Specs()[p].upper);
      }
      pair[static_cast<std::size_t>(side)] = WithValues(model, w, frame_period, false);
      pair[static_cast<std::size_t>(side)].observer.parameter_covariance = {};
    }
    out.push_back(std::move(pair));
  }
  return out;
}

OmniIdentificationReport IdentifyOmni(const OmniModel& nominal, const std::vector<OmniLog>& logs,
                                      const std::vector<OmniLog>& validation, const OmniIdentificationOptions& options,
                                      OmniModel* identified,
                                      const std::function<void(int, int, const std::string&)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  CheckLogCount(logs, options);
  auto say = [&](int step, const std::string& what) {
    if (progress) progress(step, 8, what);
  };
  CheckFramePeriods(logs, validation);
  const double period = logs.front().frame_period;

  double block = 0;
  const std::vector<Segment> segments = MakeSegments(logs, validation, options, &block);
  OmniIdentificationProblem problem(nominal, segments, options);
  OmniIdentificationOptions ahead = options;
  ahead.horizon = std::max(options.horizon + 1, static_cast<int>(std::lround(kLookaheadSeconds / period)));
  ahead.stride = std::max(options.stride, ahead.horizon / 2);
  const OmniIdentificationProblem lookahead(nominal, segments, ahead);
  OmniIdentificationReport report;
  report.model_name = nominal.name;
  for (const OmniLog& log : logs) report.logs.push_back(log.path);
  for (const OmniLog& log : validation) report.validation_logs.push_back(log.path);
  report.backend = options.backend;
  report.horizon = options.horizon;
  report.frame_period = period;
  report.block_seconds = block;
  report.held_out_share = options.held_out;

  FitState fit;
  fit.nominal = ValuesOf(nominal, period);
  fit.v = StartValues(nominal, period);
  const double nominal_cost = problem.Cost(fit.nominal);
  if (!std::isfinite(nominal_cost)) throw CheckFailed("the model as given diverges on the logs");
  // Nothing of the held-out blocks reaches the fit, its start or its limits.
  const InFit in_fit = [&](const OmniLog& log, std::size_t i) {
    return !InHeldOutBlock(log.rows[i].t - log.rows.front().t, block, options.held_out);
  };
  const std::array<bool, 3> excited = ChooseFreeParameters(logs, in_fit, options, &fit);
  FitDelayAndResponse(problem, logs, in_fit, options, period, say, &fit, &report);       // steps 1-3
  say(3, "speed limits");
  FitSpeedLimits(lookahead, logs, in_fit, &fit);                                          // step 4
  // 5. Structures the held-out blocks choose, each kept where it predicts them at least
  // kStructureGain better: the lag held in the field frame rather than the robot's,
  // braking at its own time constants, and a three-wheel robot's turn by direction.
  say(4, "lag structures");
  ChooseLagStructures(lookahead, segments, options, ahead, excited[2], fit.free, &fit.v, &fit.pruned, &fit.chosen);
  ChooseTurnByDirection(problem, lookahead, segments, logs, in_fit, options, ahead, &fit, &report.solver_iterations);
  say(5, "final fit and standard errors");
  FitTogether(problem, segments, options, &fit, &report);                                 // step 6
  StandardErrors(problem, options, &fit, &report);
  OmniModel model = problem.Build(fit.v, false);
  model.observer.parameter_covariance = ParameterCovarianceOf(fit);
  IdentifyNoise(segments, options, say, &model, &report);
  SafeguardOnLeftOutLogs(nominal, logs, options, say, &model, &report);
  model.fitted_on = options.backend;  // the engines part near the wheels' grip: replay on this one
  if (identified) *identified = model;
  ReportParameters(fit, model, &report);
  NoteUndetermined(fit, &report);
  say(7, "held-out gaps");                                                                // step 7
  report.held_out = HeldOutGaps(segments, nominal, model, false, options, &report);
  if (!validation.empty()) report.validation = HeldOutGaps(segments, nominal, model, true, options, &report);
  SpreadBudgetOn(model, validation, options, &report);
  std::vector<std::vector<char>> fit_rows;
  for (const OmniLog& log : logs) {
    fit_rows.emplace_back(log.rows.size());
    for (std::size_t i = 0; i < log.rows.size(); ++i) fit_rows.back()[i] = in_fit(log, i);
  }
  ScoreHorizons(segments, nominal, model, TrainLinearBaseline(model, logs, std::move(fit_rows), &report.notes),
                !validation.empty(), options, fit.v[kDelay], period, &report);
  std::vector<OmniLog> all = logs;
  all.insert(all.end(), validation.begin(), validation.end());
  SummariseFit(problem, segments, all, nominal, model, options, fit, nominal_cost, &report);
  report.evaluations = problem.evaluations();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  say(8, "done");
  return report;
}

}  // namespace twinsim

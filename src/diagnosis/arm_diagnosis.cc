#include "diagnosis/arm_diagnosis.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <set>
#include <stdexcept>

#include "analysis/arm_replay.h"
#include "analysis/arm_simulation_score.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "diagnosis/forward_selection.h"
#include "diagnosis/learned_residual.h"
#include "identification/wls_identification.h"
#include "robots/arm/arm_dynamics.h"
#include "robots/arm/arm_effects.h"
#include "robots/arm/arm_regressor.h"
#include "signal/butterworth.h"

namespace twinsim {
namespace {

constexpr double kReversalWindow = 0.1;   // s either side of a velocity reversal
// A joint stands below 2 % of its largest speed: its q̇ is filtered and smooth.
constexpr double kStandFraction = 0.02;
// Samples of the residual spectra's Welch segments at most: arm logs run at hundreds of
// Hz to kHz for tens of seconds.
constexpr int kWelchSegmentCap = 4096;
constexpr double kMaxLag = 0.1;           // s, the cross-correlation's reach
constexpr int kMaxFitRows = 20000;        // residual rows per joint a Ceres fit uses at most
constexpr int kPlotPoints = 4000;
constexpr double kMaxDeflection = 0.5;     // rad: the most a flexible joint's spring deflects
constexpr double kMinStiffness = 1e-3;     // N·m/rad: joint_flexibility's search bounds
constexpr double kMinMotorInertia = 1e-9;  // kg m^2
// A saturation limit clips only commands beyond it by this many times the joint's
// torque noise (ArmProblem::SaturationReach).
constexpr double kSaturationMargin = 3;
constexpr double kPayloadReach = 2;      // m: a payload's position is searched within this of the last link's frame
// stribeck_friction's bristles (sigma0, N·m/rad or N/m): the search's bounds, and the
// share of the joint's fit-row squared residual the bristles must remove beyond the
// plain Stribeck curve's to be kept. They nest it (sigma0 -> infinity is the plain
// curve), so an information criterion's one parameter is no margin on thousands of
// rows: the derivative filter's error at every reversal would buy them.
constexpr double kMinBristleStiffness = 1e-3, kMaxBristleStiffness = 1e12;
constexpr double kBristleMargin = 0.1;
// rad or m: the most bristles deflect at the break-away level. A drive's contacts
// deflect micrometres to a milliradian or so before they slide; softer "bristles" stand
// for something else (a flexible joint's spring, on the plants that have one).
constexpr double kMaxBristleDeflection = 0.01;
// position_friction and position_torque: the knots a candidate gets, evenly over the
// positions the logs visit, and the share of its joint's fit-row squared residual it must
// remove beyond the best constant level (for friction one Coulomb level, for a torque a
// torque offset) to be kept: it nests that level, so a criterion's parameter count is no
// margin on thousands of rows.
constexpr int kPositionFrictionKnots = 5;
constexpr double kPositionFrictionMargin = 0.1;
// rad or m: a joint that moves less than this gets no candidate along its travel.
constexpr double kPositionFrictionSpan = 1e-3;
// The shortest bandwidth of the long-run variance (statistics.h): a quarter second holds
// a motion's stop or reversal (the events where friction and delays show).
constexpr double kChunkSeconds = 0.25;

// One log with what every evaluation reuses.
struct ArmLogData {
  const ArmLog* log = nullptr;
  int first = 0, last = 0;                  // rows used, [first, last)
  Eigen::MatrixXd rigid;                    // rows x n, N·m: inverse dynamics of the bodies, no friction
  std::array<Eigen::MatrixXd, 10> payload;  // rows x n each: the last link's regressor columns
  std::vector<RowKind> kind;                // per row: fit, selection, test or guard
  std::vector<int> block;                   // per row: its block, numbered over every log
};

// How an effect's parameters map to the optimiser's variables.
struct ParameterMap {
  std::vector<double> x;      // initial values
  std::vector<double> lower;  // bounds (-inf/inf: none)
  std::vector<double> upper;
};

// The guard between blocks (s): a zero-phase derivative filter spreads a sample over
// about half a period of its cut-off each way (its impulse response's main lobe);
// logged velocities need only a few samples.
double ArmGuardSeconds(const std::vector<ArmLog>& logs) {
  double guard = 0;
  for (const ArmLog& log : logs) {
    guard = std::max(guard, log.derive_cutoff_hz > 0 ? 0.5 / log.derive_cutoff_hz : 10 * log.sample_period);
  }
  return guard;
}

// Rows a learned residual trains on at most, and its random features.
constexpr int kMaxLearnedRows = 8000;
constexpr int kLearnedFeatures = 300;

// The effect's parameter `key`, or `fallback` where it has none.
double ParameterOr(const TrialEffect& e, const char* key, double fallback = 0) {
  auto it = e.parameters.find(key);
  return it == e.parameters.end() ? fallback : it->second;
}

// The letter of a profile along the travel's levels (position_friction's c1.., a
// position_torque's p1..), or '\0' for any other effect.
char ProfileLetter(const std::string& name) {
  return name == "position_friction" ? 'c' : name == "position_torque" ? 'p' : '\0';
}

// An effect's parameters as variables (log scale where a parameter spans decades).
// `floor`: the least a position_friction level may be (minus the joint's nominal Coulomb
// friction, which it may take away from).
ParameterMap FitVariablesOf(const TrialEffect& e, double floor) {
  ParameterMap m;
  auto add = [&](double x, double lo, double hi) {
    m.x.push_back(std::clamp(x, lo, hi));
    m.lower.push_back(lo);
    m.upper.push_back(hi);
  };
  if (e.name == "viscous_friction") {
    add(ParameterOr(e, "b"), 0, kInf);
  } else if (e.name == "coulomb_friction") {
    add(ParameterOr(e, "c_pos"), 0, kInf);
    add(ParameterOr(e, "c_neg"), 0, kInf);
  } else if (e.name == "stribeck_friction") {
    add(ParameterOr(e, "c"), 0, kInf);
    add(std::max(ParameterOr(e, "s") - ParameterOr(e, "c"), 1e-6), 1e-6, kInf);
    add(std::log(std::max(ParameterOr(e, "vs"), 1e-4)), std::log(1e-4), std::log(100.0));
    if (e.parameters.count("sigma0")) {
      add(std::log(ParameterOr(e, "sigma0")), std::log(kMinBristleStiffness), std::log(kMaxBristleStiffness));
    }
  } else if (const char letter = ProfileLetter(e.name)) {
    // A torque's levels are free; friction's no lower than `floor`.
    const double lowest = letter == 'p' ? -kInf : floor;
    for (int k = 0; k < ProfileLevelCount(letter, e.parameters); ++k)
      add(e.parameters.at(ProfileLevelKey(letter, k)), lowest, kInf);
  } else if (e.name == "torque_offset") {
    add(ParameterOr(e, "tau0"), -kInf, kInf);
  } else if (e.name == "torque_saturation") {
    add(ParameterOr(e, "limit"), 1e-6, kInf);
  } else if (e.name == "time_delay") {
    add(ParameterOr(e, "delay"), 0, 1.0);
  } else if (e.name == "joint_flexibility") {
    add(std::log(std::max(ParameterOr(e, "k"), kMinStiffness)), std::log(kMinStiffness), std::log(1e9));
    add(ParameterOr(e, "damping"), 0, kInf);
    add(std::log(std::max(ParameterOr(e, "motor_inertia"), kMinMotorInertia)), std::log(kMinMotorInertia), std::log(1e3));
  } else if (e.name == "payload") {
    add(std::max(ParameterOr(e, "mass"), 1e-6), 1e-6, kInf);
    add(ParameterOr(e, "x"), -kPayloadReach, kPayloadReach);
    add(ParameterOr(e, "y"), -kPayloadReach, kPayloadReach);
    add(ParameterOr(e, "z"), -kPayloadReach, kPayloadReach);
  }
  return m;
}

// A pre-sliding joint's bristles (stribeck_friction's sigma0, a Maxwell-slip element)
// damped critically against the joint's inertia `inertia` (kg m^2 or kg), as identify's
// --presliding damps them: sigma1 follows sigma0 and is not a variable of its own.
void SetBristles(double sigma0, double inertia, std::map<std::string, double>* p) {
  (*p)["sigma0"] = sigma0;
  (*p)["sigma1"] = 2 * std::sqrt(sigma0 * inertia);
  (*p)["maxwell"] = 1;
}

// The fit variables x into the effect's parameters, each projected onto its valid range:
// Ceres keeps its iterates within the bounds, but its numeric derivatives step across them
// (a friction level starting at 0 is tried at -1e-4), and an evaluation the effect's
// checks refuse would end the fit at its start. `inertia`: the effect's joint's, for
// bristles; `floor`: FitVariablesOf's, for position_friction's levels.
void SetFromFitVariables(const double* x, double inertia, double floor, TrialEffect* e) {
  auto& p = e->parameters;
  auto positive = [](double v, double least) { return std::max(v, least); };
  const bool bristles = p.count("sigma0") > 0;
  if (const char letter = ProfileLetter(e->name)) {
    // The knots stay where the guess put them; only their levels are variables.
    for (int k = 0; k < ProfileLevelCount(letter, p); ++k)
      p[ProfileLevelKey(letter, k)] = letter == 'p' ? x[k] : positive(x[k], floor);
    return;
  }
  p.clear();
  if (e->name == "viscous_friction") {
    p["b"] = positive(x[0], 0);
  } else if (e->name == "coulomb_friction") {
    p["c_pos"] = positive(x[0], 0);
    p["c_neg"] = positive(x[1], 0);
  } else if (e->name == "stribeck_friction") {
    p["c"] = positive(x[0], 0);
    p["s"] = p["c"] + positive(x[1], 1e-6);
    p["vs"] = std::exp(x[2]);
    if (bristles) SetBristles(std::exp(std::clamp(x[3], std::log(kMinBristleStiffness), std::log(kMaxBristleStiffness))), inertia, &p);
  } else if (e->name == "torque_offset") {
    p["tau0"] = x[0];
  } else if (e->name == "torque_saturation") {
    p["limit"] = positive(x[0], 1e-6);
  } else if (e->name == "time_delay") {
    p["delay"] = std::clamp(x[0], 0.0, 1.0);
  } else if (e->name == "joint_flexibility") {
    p["k"] = std::exp(x[0]);
    p["damping"] = positive(x[1], 0);
    p["motor_inertia"] = std::exp(x[2]);
  } else if (e->name == "payload") {
    p["mass"] = positive(x[0], 1e-6);
    p["x"] = x[1];
    p["y"] = x[2];
    p["z"] = x[3];
  }
}

double SignOf(double v) { return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0); }

// Least squares x = argmin |A x - b| with columns of A given as vectors (small systems).
Eigen::VectorXd SolveLeastSquares(const Eigen::MatrixXd& a, const Eigen::VectorXd& b) {
  return a.colPivHouseholderQr().solve(b);
}

// The fit rows of the residual the other effects leave, with the per-row features the starting guesses need.
struct GuessRows {
  std::vector<double> r, q, qd, qdd, needed_dd;
  std::vector<std::array<double, 4>> payload_rows;  // per joint row: m, mcx, mcy, mcz columns
  std::vector<double> payload_r;
};

class ArmProblem : public DiagnosisProblem {
 public:
  ArmProblem(const ArmModel& nominal, const std::vector<ArmLog>& logs, double block_seconds, double held_out,
             double standstill)
      : nominal_(nominal), n_(nominal.dof()), standstill_(standstill) {
    guard_seconds_ = ArmGuardSeconds(logs);
    const ArmModel bodies = ArmPlantModel(nominal);
    payload_candidate_ = nominal.effects.payload_mass <= 0;
    int blocks = 0;  // of the logs before
    for (const ArmLog& log : logs) {
      ArmLogData d;
      d.log = &log;
      d.first = log.edge_samples;
      d.last = log.rows() - log.edge_samples;
      const int rows = log.rows();
      d.rigid.resize(rows, n_);
      if (payload_candidate_) {
        for (auto& b : d.payload) b.resize(rows, n_);
      }
      for (int r = 0; r < rows; ++r) {
        const Eigen::VectorXd q = log.q.row(r).transpose(), qd = log.qd.row(r).transpose(),
                              qdd = log.qdd.row(r).transpose();
        d.rigid.row(r) = InverseDynamics(bodies, q, qd, qdd, false).transpose();
        if (payload_candidate_) {
          const Eigen::MatrixXd y = Regressor(bodies, q, qd, qdd);
          for (int k = 0; k < 10; ++k) d.payload[static_cast<std::size_t>(k)].row(r) = y.col(kParametersPerLink * (n_ - 1) + k).transpose();
        }
      }
      d.kind.resize(static_cast<std::size_t>(rows));
      d.block.resize(static_cast<std::size_t>(rows));
      for (int r = 0; r < rows; ++r) {
        d.kind[static_cast<std::size_t>(r)] = HeldOutRowKind(log.t[r] - log.t[0], block_seconds, held_out, guard_seconds_);
        d.block[static_cast<std::size_t>(r)] = blocks + TimeBlockIndex(log.t[r] - log.t[0], block_seconds);
      }
      blocks = d.block.back() + 1;
      data_.push_back(std::move(d));
    }
    noise_ = NoiseFloor();
    joint_inertia_ = MassMatrix(bodies, logs.front().q.row(0).transpose()).diagonal();
    q_lo_ = Eigen::VectorXd::Constant(n_, kInf);
    q_hi_ = Eigen::VectorXd::Constant(n_, -kInf);
    for (const ArmLog& log : logs) {
      q_lo_ = q_lo_.cwiseMin(log.q.colwise().minCoeff().transpose());
      q_hi_ = q_hi_.cwiseMax(log.q.colwise().maxCoeff().transpose());
    }
    chunk_rows_ = std::max(1, static_cast<int>(std::lround(kChunkSeconds / logs.front().sample_period)));
    sample_period_ = logs.front().sample_period;
    bandwidth_ = kInf;
    for (const ArmLog& log : logs) {
      bandwidth_ = std::min(bandwidth_, log.derive_cutoff_hz > 0 ? log.derive_cutoff_hz : 0.25 / log.sample_period);
    }
  }

  int dof() const { return n_; }
  const std::vector<ArmLogData>& data() const { return data_; }
  double Gap(double mean_squared) const override { return std::sqrt(mean_squared / n_); }
  int ChunkRows() const override { return chunk_rows_; }

  // The nominal model with `effects` added. Throws InputError for invalid parameters.
  ArmModel Build(const std::vector<TrialEffect>& effects) const {
    ArmModel m = nominal_;
    for (const TrialEffect& e : effects) AddArmEffect({e.name, e.joint, e.parameters}, n_, &m.effects);
    return m;
  }

  // Torque of the trial model's payload effect on log d (rows x n), or empty.
  Eigen::MatrixXd PayloadTorque(const ArmModel& trial, const ArmLogData& d) const {
    if (!payload_candidate_ || trial.effects.payload_mass <= 0) return {};
    const auto pi = PointMassParameters(trial.effects.payload_mass, trial.effects.payload_position);
    Eigen::MatrixXd tau = Eigen::MatrixXd::Zero(d.log->rows(), n_);
    for (int k = 0; k < 10; ++k) tau += pi[k] * d.payload[static_cast<std::size_t>(k)];
    return tau;
  }

  // What the links of joint j need: rigid bodies, payload and all friction (rows; a
  // pre-sliding joint's bristles followed along the log, ArmFrictionAlong). A joint at a
  // standstill gets no friction here: it sticks, and its friction is then whatever holds
  // it (Residual() allows for that).
  Eigen::VectorXd Needed(const ArmModel& trial, const ArmLogData& d, int j, const Eigen::MatrixXd& payload) const {
    Eigen::VectorXd needed = d.rigid.col(j);
    if (payload.size()) needed += payload.col(j);
    const auto& qd = d.log->qd;
    const Eigen::VectorXd friction = ArmFrictionAlong(trial, j, d.log->t, d.log->q.col(j), qd.col(j));
    const JointEffects e = trial.effects.joint(j);
    for (int r = 0; r < d.log->rows(); ++r) {
      if (std::abs(qd(r, j)) >= standstill_) needed[r] += friction[r];
      // position_torque acts on the link: the drive needs that much less.
      if (e.torque_profile.on()) needed[r] -= e.PositionTorque(d.log->q(r, j));
    }
    return needed;
  }

  // The model's command for joint j (rows).
  Eigen::VectorXd Command(const ArmModel& trial, const ArmLogData& d, int j, const Eigen::MatrixXd& payload) const {
    return JointCommandFromNeeded(trial, j, d.log->t, d.log->qdd.col(j), Needed(trial, d, j, payload));
  }

  // How far beyond a saturation `limit` of joint j a logged command must reach to count
  // as clipped: the joint's torque noise, kSaturationMargin times. A command within it
  // may be the limit plus noise; clipping it would fit the noise's peaks (on a joint
  // carried by gravity near its peak, with 2 % torque noise, a limit just below the peak
  // cut 11 % of the fit rows' error and made the test rows' 2.2 times worse).
  double SaturationReach(double limit, int j) const {
    return limit + kSaturationMargin * noise_[static_cast<std::size_t>(j)];
  }

  // Measured minus model for joint j (rows). With a torque_saturation limit a joint whose
  // command reaches beyond it (SaturationReach) received the limit: that is compared with
  // what the motion needs; the other rows keep the command as logged.
  // At a standstill the joint's friction takes any value up to its static level, so
  // only what exceeds that level counts: on the rows whose command the joint receives
  // at a standstill, its delay later (a delay's fit judged at the unshifted rows is
  // pulled short: a 21 ms delay on a joint with Coulomb friction came out at 16 ms).
  Eigen::VectorXd Residual(const ArmModel& trial, const ArmLogData& d, int j, const Eigen::MatrixXd& payload) const {
    const Eigen::VectorXd cmd = Command(trial, d, j, payload);
    const JointEffects e = trial.effects.joint(j);
    const Eigen::VectorXd u = d.log->tau.col(j);
    Eigen::VectorXd r = u - cmd;
    if (e.saturation > 0) {
      const double reach = SaturationReach(e.saturation, j);
      for (int row = 0; row < d.log->rows(); ++row) {
        if (std::abs(u[row]) > reach) r[row] = std::copysign(e.saturation, u[row]) - cmd[row];
      }
    }
    const double coulomb = trial.joints[static_cast<std::size_t>(j)].coulomb + (e.stribeck() ? e.stribeck_static : 0.0);
    const Eigen::VectorXd received_qd = ShiftEarlier(d.log->t, d.log->qd.col(j), JointCommandLead(trial, j));
    for (int row = 0; row < d.log->rows(); ++row) {
      if (std::abs(received_qd[row]) >= standstill_) continue;
      const double level = coulomb + (r[row] > 0 ? e.coulomb_positive : e.coulomb_negative) +
                           e.PositionFrictionLevel(d.log->q(row, j));
      r[row] = r[row] > 0 ? std::max(0.0, r[row] - level) : std::min(0.0, r[row] + level);
    }
    return r;
  }

  SquaredResiduals Evaluate(const std::vector<TrialEffect>& effects) const override {
    const ArmModel trial = Build(effects);
    SquaredResiduals out;
    out.selection_by_channel.resize(static_cast<std::size_t>(n_));
    out.fit_by_channel.resize(static_cast<std::size_t>(n_));
    for (const ArmLogData& d : data_) {
      const Eigen::MatrixXd payload = PayloadTorque(trial, d);
      Eigen::MatrixXd squared(d.log->rows(), n_);
      for (int j = 0; j < n_; ++j) squared.col(j) = Residual(trial, d, j, payload).cwiseAbs2();
      const Eigen::VectorXd sum = squared.rowwise().sum();
      for (int r = d.first; r < d.last; ++r) {
        switch (d.kind[static_cast<std::size_t>(r)]) {
          case RowKind::kFit:
            out.fit.push_back(sum[r]);
            for (int j = 0; j < n_; ++j) out.fit_by_channel[static_cast<std::size_t>(j)].push_back(squared(r, j));
            break;
          case RowKind::kSelection:
            out.selection.push_back(sum[r]);
            out.selection_block.push_back(d.block[static_cast<std::size_t>(r)]);
            for (int j = 0; j < n_; ++j) out.selection_by_channel[static_cast<std::size_t>(j)].push_back(squared(r, j));
            break;
          case RowKind::kTest: out.test.push_back(sum[r]); break;
          case RowKind::kGuard: break;
        }
      }
    }
    return out;
  }

  std::vector<TrialEffect> Candidates(const std::vector<TrialEffect>& current) const override {
    std::set<std::pair<std::string, int>> fitted;
    for (const TrialEffect& e : current) fitted.insert({e.name, e.joint});
    std::set<std::pair<std::string, int>> taken = fitted;
    for (const ArmEffect& e : ListArmEffects(nominal_.effects)) taken.insert({e.name, e.joint});
    // A torque along the travel holds a torque offset (all its levels equal): both fitted
    // on one joint would trade against each other and neither's standard error would be
    // defined, so a joint whose trial effects hold one is not offered the other.
    std::vector<TrialEffect> out;
    for (int j = 0; j < n_; ++j) {
      for (const std::string& name : ArmEffectNames()) {
        if (name == "payload" || taken.count({name, j})) continue;
        if (name == "position_torque" && fitted.count({"torque_offset", j})) continue;
        if (name == "torque_offset" && fitted.count({"position_torque", j})) continue;
        // Friction or a torque along the travel needs a travel to map.
        if (ProfileLetter(name) && !(q_hi_[j] - q_lo_[j] >= kPositionFrictionSpan)) continue;
        out.push_back({name, j, {}});
      }
    }
    if (payload_candidate_ && !taken.count({"payload", -1})) out.push_back({"payload", -1, {}});
    return out;
  }

  std::vector<TrialEffect> Fit(std::vector<TrialEffect> effects, const std::vector<int>& free) const override {
    std::vector<int> fresh_stribeck, fresh_position;
    for (int i : free) {
      TrialEffect& e = effects[static_cast<std::size_t>(i)];
      if (!e.parameters.empty()) continue;
      if (e.name == "stribeck_friction") fresh_stribeck.push_back(i);
      if (ProfileLetter(e.name)) fresh_position.push_back(i);
      InitialGuess(&effects, i);
    }
    Refine(&effects, free);
    for (int i : fresh_stribeck) TryBristles(&effects, free, i);
    for (int i : fresh_position) CheckLevelsVary(effects, i);
    for (int i : free) CheckResolved(effects[static_cast<std::size_t>(i)]);  // a joint refit too
    return effects;
  }

  // How far the bristles of a stribeck_friction effect `e` deflect before its joint
  // slides: the joint's whole dry friction level at rest (the nominal's Coulomb friction
  // acts through them too; at the first log's first posture) over sigma0.
  double BristleDeflection(const TrialEffect& e) const {
    const double q = data_.front().log->q(0, e.joint);
    const ArmSlipLevels levels = ArmMaxwellSlipLevels(Build({e}), e.joint, q, 0);
    return std::max(levels.positive, levels.negative) / e.parameters.at("sigma0");
  }

  // The joint's inertia on itself (M_jj at the first log's first posture; 0 for j < 0):
  // what the bristles' damping is critical against.
  double JointInertia(int j) const { return j >= 0 ? joint_inertia_[j] : 0.0; }
  // The least a position_friction level of joint j may be: minus the nominal's Coulomb
  // friction there, so that the joint's dry friction never turns negative (0 for j < 0).
  double LevelFloor(int j) const { return j >= 0 ? -nominal_.joints[static_cast<std::size_t>(j)].coulomb : 0.0; }

  std::string Signature(const TrialEffect& e) const override;
  std::vector<double> FitResiduals(const std::vector<TrialEffect>& effects) const override {
    std::vector<int> joints(static_cast<std::size_t>(n_));
    for (int j = 0; j < n_; ++j) joints[static_cast<std::size_t>(j)] = j;
    const Eigen::VectorXd r = FitResidual(effects, joints);
    return {r.data(), r.data() + r.size()};
  }
  TestResiduals TestRowResiduals(const std::vector<TrialEffect>& effects, bool learn) const override;
  // The arm's floor (the residual above twice the derivative filter's cut-off, scaled
  // to the band) is a lower bound: plants with nothing missing reach up to 3.4 times it
  // (flexible joints with logged velocities; 2 for delays under a 4 Hz controller;
  // 1.5 clean; measured, docs/diagnose-study).
  double FloorRatio() const override { return 4; }
  // The torque is logged unfiltered beside zero-phase filtered derivatives: the filter's
  // error is a function of the motion, predictable but not physics. On 20 clean plants
  // the learned residual lowered a joint's test RMS by up to 0.19 of its noise (0.15 on
  // every plant of seed 1); a spring or a cogging torque by 0.43 to 3.0
  // (docs/diagnose-study).
  double LearnedFloor() const override { return 0.25; }
  double guard_seconds() const { return guard_seconds_; }

  // A joint flexibility keeps its fit while candidates are scored: its replay is a
  // numerical approximation (the spring's deflection integrated by implicit Euler and
  // differentiated twice, near a resonance of 100 Hz and more; the true plant replays
  // worse than the fitted model), and refitted beside another effect it lets that one
  // patch the approximation (measured: a 3.7 N·m saturation "found" at t = 6 beside a
  // flexible elbow that has none).
  bool HeldWhileScoring(const TrialEffect& e) const override { return e.name == "joint_flexibility"; }
  std::vector<std::string> MustBeDetermined(const TrialEffect& e) const override {
    if (e.name == "torque_saturation") return {"limit"};
    return {};
  }
  // The bristles' damping follows their stiffness (SetBristles); `maxwell` names the element.
  bool Derived(const TrialEffect& e, const std::string& key) const override {
    return (e.name == "stribeck_friction" && (key == "sigma1" || key == "maxwell")) ||
           (ProfileLetter(e.name) && (key == "from" || key == "to"));  // the knots: the logs' travel
  }
  // A joint's effect changes that joint's command alone (Residual): scored on it.
  int ChannelOf(const TrialEffect& e) const override { return e.joint; }

  // Throws CheckFailed when a fitted effect lies where the logs cannot see it:
  // what it then explains is something else (the derivative filter's error, noise).
  void CheckResolved(const TrialEffect& e) const {
    char msg[200];
    if (e.name == "joint_flexibility") {
      // A spring or motor at the search's bound is no spring: a damper, or nothing.
      if (e.parameters.at("k") < 1.01 * kMinStiffness || e.parameters.at("motor_inertia") < 1.01 * kMinMotorInertia) {
        throw CheckFailed("its stiffness or motor inertia ends at the search bound: no spring the logs determine");
      }
      // The spring carries the joint's torque: a spring that would deflect by more than
      // kMaxDeflection under it is a filter fitted to something else, not a joint.
      double peak = 0;
      for (const ArmLogData& d : data_) peak = std::max(peak, d.rigid.col(e.joint).segment(d.first, d.last - d.first).cwiseAbs().maxCoeff());
      if (peak / e.parameters.at("k") > kMaxDeflection) {
        std::snprintf(msg, sizeof msg, "its spring would deflect %.3g rad under the joint's %.3g N·m: no joint is that soft",
                      peak / e.parameters.at("k"), peak);
        throw CheckFailed(msg);
      }
      const double f = std::sqrt(e.parameters.at("k") / e.parameters.at("motor_inertia")) / (2 * kPi);
      if (f > bandwidth_) {
        std::snprintf(msg, sizeof msg, "its resonance (%.3g Hz) lies above the %.3g Hz the logs' motion resolves", f, bandwidth_);
        throw CheckFailed(msg);
      }
    } else if (e.name == "position_friction") {
      // A level on its floor takes the joint's whole Coulomb friction away there: the
      // map stands in for something that holds the joint less (a flexible joint's
      // spring, on the plant that has one), not for friction the logs measure.
      const double floor = LevelFloor(e.joint);
      for (int k = 0; k < ProfileLevelCount('c', e.parameters); ++k) {
        if (e.parameters.at(ProfileLevelKey('c', k)) > floor + 1e-9 * std::max(1.0, std::abs(floor))) continue;
        std::snprintf(msg, sizeof msg,
                      "its level at knot %d ends at %.3g, leaving the joint no dry friction there: friction taken away "
                      "is no map of it",
                      k + 1, floor);
        throw CheckFailed(msg);
      }
    } else if (e.name == "time_delay") {
      if (e.parameters.at("delay") < 0.5 * sample_period_) {
        std::snprintf(msg, sizeof msg, "%.3g ms is below half a sample", 1000 * e.parameters.at("delay"));
        throw CheckFailed(msg);
      }
    } else if (e.name == "stribeck_friction") {
      if (e.parameters.at("vs") < standstill_) {
        std::snprintf(msg, sizeof msg, "vs = %.3g rad/s is below the standstill speed %.3g: Coulomb friction by another name",
                      e.parameters.at("vs"), standstill_);
        throw CheckFailed(msg);
      }
      if (e.parameters.count("sigma0") && BristleDeflection(e) > kMaxBristleDeflection) {
        std::snprintf(msg, sizeof msg, "its bristles would deflect %.3g rad before the joint slides: no contact is that soft",
                      BristleDeflection(e));
        throw CheckFailed(msg);
      }
    } else if (e.name == "torque_saturation") {
      long beyond = 0, total = 0;
      const double reach = SaturationReach(e.parameters.at("limit"), e.joint);
      for (const ArmLogData& d : data_) {
        for (int r = d.first; r < d.last; ++r) {
          beyond += std::abs(d.log->tau(r, e.joint)) > reach;
          ++total;
        }
      }
      if (beyond < std::max(10L, total / 200)) throw CheckFailed("fewer than 0.5 % of the commands reach the limit");
    } else if (e.name == "payload") {
      for (const char* key : {"x", "y", "z"}) {
        if (std::abs(e.parameters.at(key)) > 0.99 * kPayloadReach) {
          throw CheckFailed(std::string("its position's ") + key + " ends at the search bound: not determined by the logs");
        }
      }
    }
  }

  // The fit rows' residual of the joints `joints` under `effects`, concatenated.
  Eigen::VectorXd FitResidual(const std::vector<TrialEffect>& effects, const std::vector<int>& joints) const {
    const ArmModel trial = Build(effects);
    std::vector<double> out;
    for (const ArmLogData& d : data_) {
      const Eigen::MatrixXd payload = PayloadTorque(trial, d);
      for (int j : joints) {
        const Eigen::VectorXd r = Residual(trial, d, j, payload);
        for (int row = d.first; row < d.last; row += stride_) {
          if (d.kind[static_cast<std::size_t>(row)] == RowKind::kFit) out.push_back(r[row]);
        }
      }
    }
    return Eigen::Map<Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size()));
  }

  void SetStride() {
    int rows = 0;
    for (const ArmLogData& d : data_) rows += d.last - d.first;
    stride_ = std::max(1, rows / kMaxFitRows);
  }

 private:
  std::vector<int> TouchedJoints(const std::vector<TrialEffect>& effects, const std::vector<int>& free) const {
    std::set<int> joints;
    for (int i : free) {
      const TrialEffect& e = effects[static_cast<std::size_t>(i)];
      if (e.joint < 0) {
        for (int j = 0; j < n_; ++j) joints.insert(j);
      } else {
        joints.insert(e.joint);
      }
    }
    return {joints.begin(), joints.end()};
  }

  double Cost(const std::vector<TrialEffect>& effects, const std::vector<int>& joints) const {
    try {
      return FitResidual(effects, joints).squaredNorm();
    } catch (const InputError&) {
      return kInf;
    }
  }

  // Per joint, the logged torque's noise: its part above twice the derivative filter's
  // cut-off, scaled to the whole band (HighFrequencySigma), averaged in variance over
  // the logs. From the log alone: the model's command holds nothing there (it is made
  // of the filtered derivatives), and no model, nominal or repaired, can move it.
  std::vector<double> NoiseFloor() const;
  // Starting parameters for effects[i] from the residual the others leave.
  void InitialGuess(std::vector<TrialEffect>* effects, int i) const;
  // The fit rows of the residual `base` leaves on effect e's joint (every joint's for a payload), with their features.
  GuessRows GuessRowsFor(const ArmModel& base, const TrialEffect& e) const;
  // A torque limit or a delay for effects[i]: the best of a grid on the model's cost, a delay then sample by sample.
  void GuessOnGrid(const ArmModel& base, std::vector<TrialEffect>* effects, int i) const;
  // A spring's stiffness and motor inertia for effects[i]: the best on the model of a grid over k, each with its
  // linear motor inertia.
  void GuessFlexibility(const GuessRows& fit, std::vector<TrialEffect>* effects, int i) const;
  // Ceres over every free effect's variables.
  void Refine(std::vector<TrialEffect>* effects, const std::vector<int>& free) const;
  // Gives the plain Stribeck curve effects[i], just fitted, pre-sliding bristles where
  // they remove kBristleMargin of its joint's fit-row squared residual beyond it and do
  // no worse on its selection rows.
  void TryBristles(std::vector<TrialEffect>* effects, const std::vector<int>& free, int i) const;
  // Throws CheckFailed unless the position_friction or position_torque effects[i], just
  // fitted, removes kPositionFrictionMargin of its joint's fit-row squared residual beyond
  // its best single level (every knot at the constant the other effects' residual asks
  // for: one Coulomb level, or a torque offset).
  void CheckLevelsVary(const std::vector<TrialEffect>& effects, int i) const;

  ArmModel nominal_;
  int n_;
  double standstill_;  // rad/s or m/s: slower counts as standing still
  double bandwidth_ = 0;       // Hz: the motion the logs resolve (derivative cut-off, or a quarter of the rate)
  double sample_period_ = 0;   // s, the logs' median
  bool payload_candidate_ = true;
  std::vector<ArmLogData> data_;
  Eigen::VectorXd joint_inertia_;  // per joint, M_jj at the first log's first row (JointInertia)
  Eigen::VectorXd q_lo_, q_hi_;    // per joint, the least and greatest position over the logs
  // Per joint, the logs' torque noise (NoiseFloor): fixed, so an effect that fits the
  // noise cannot lower the floor it is judged against.
  std::vector<double> noise_;
  int chunk_rows_ = 1;
  int stride_ = 1;
  double guard_seconds_ = 0;
};

// Coulomb friction's c_pos and c_neg: least squares on the signs of the joint's speed.
void GuessCoulombFriction(const std::vector<double>& qd, const Eigen::Map<const Eigen::VectorXd>& rv,
                          std::map<std::string, double>* p) {
  const auto rows = static_cast<Eigen::Index>(qd.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(rows, 2);
  for (Eigen::Index k = 0; k < rows; ++k) {
    a(k, 0) = qd[static_cast<std::size_t>(k)] > 0 ? 1 : 0;
    a(k, 1) = qd[static_cast<std::size_t>(k)] < 0 ? -1 : 0;
  }
  const Eigen::VectorXd c = SolveLeastSquares(a, rv);
  (*p)["c_pos"] = std::max(0.0, c[0]);
  (*p)["c_neg"] = std::max(0.0, c[1]);
}

// How a profile along the travel moves joint j's command on a fit row: friction's levels
// by sign(qd) (the command rises by c(q) sign(qd)); a torque's by -1 (the joint receives
// p(q), the command falls by it) on the rows where the joint moves, 0 at a standstill,
// whose residual the friction band has already clipped.
double ProfileFactor(bool torque, double qd, double standstill) {
  if (!torque) return SignOf(qd);
  return std::abs(qd) >= standstill ? -1.0 : 0.0;
}

// Friction (or with `torque` a torque) along the travel: kPositionFrictionKnots knots
// from `from` to `to`, their levels by least squares on ProfileFactor times each knot's
// weight (friction's at least `floor`).
void GuessPositionProfile(const GuessRows& fit, double from, double to, double floor, bool torque, double standstill,
                          const Eigen::Map<const Eigen::VectorXd>& rv, std::map<std::string, double>* p) {
  const auto rows = static_cast<Eigen::Index>(fit.qd.size());
  Eigen::MatrixXd a(rows, kPositionFrictionKnots);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const double factor = ProfileFactor(torque, fit.qd[static_cast<std::size_t>(r)], standstill);
    for (int k = 0; k < kPositionFrictionKnots; ++k)
      a(r, k) = factor * KnotWeight(from, to, kPositionFrictionKnots, k, fit.q[static_cast<std::size_t>(r)]);
  }
  const Eigen::VectorXd c = SolveLeastSquares(a, rv);
  (*p)["from"] = from;
  (*p)["to"] = to;
  for (int k = 0; k < kPositionFrictionKnots; ++k)
    (*p)[ProfileLevelKey(torque ? 'p' : 'c', k)] = torque ? c[k] : std::max(floor, c[k]);
}

// Stribeck friction's c, s and vs: least squares for each of a grid of Stribeck speeds, the best kept.
void GuessStribeckFriction(const std::vector<double>& qd, const Eigen::Map<const Eigen::VectorXd>& rv,
                           std::map<std::string, double>* p) {
  const auto rows = static_cast<Eigen::Index>(qd.size());
  double best = kInf;
  for (double vs : {0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0}) {
    Eigen::MatrixXd a(rows, 2);
    for (Eigen::Index k = 0; k < rows; ++k) {
      const double v = qd[static_cast<std::size_t>(k)], s = SignOf(v);
      a(k, 0) = s;
      a(k, 1) = s * std::exp(-(v / vs) * (v / vs));
    }
    Eigen::VectorXd c = SolveLeastSquares(a, rv);
    c[0] = std::max(0.0, c[0]);
    c[1] = std::max(1e-6, c[1]);
    const double sse = (rv - a * c).squaredNorm();
    if (sse < best) {
      best = sse;
      *p = {{"c", c[0]}, {"s", c[0] + c[1]}, {"vs", vs}};
    }
  }
}

// A payload's mass and position from least squares on its first moments (the second moments of a point mass follow
// from them).
void GuessPayload(const GuessRows& fit, std::map<std::string, double>* p) {
  const auto m = static_cast<Eigen::Index>(fit.payload_r.size());
  Eigen::MatrixXd a(m, 4);
  for (Eigen::Index k = 0; k < m; ++k) {
    for (int c = 0; c < 4; ++c) a(k, c) = fit.payload_rows[static_cast<std::size_t>(k)][static_cast<std::size_t>(c)];
  }
  const Eigen::VectorXd c = SolveLeastSquares(a, Eigen::Map<const Eigen::VectorXd>(fit.payload_r.data(), m));
  const double mass = std::max(c[0], 1e-3);
  Eigen::Vector3d pos = c.tail<3>() / mass;
  pos = pos.cwiseMax(-kPayloadReach).cwiseMin(kPayloadReach);
  *p = {{"mass", mass}, {"x", pos.x()}, {"y", pos.y()}, {"z", pos.z()}};
}

GuessRows ArmProblem::GuessRowsFor(const ArmModel& base, const TrialEffect& e) const {
  const int j = e.joint;
  GuessRows fit;
  for (const ArmLogData& d : data_) {
    const Eigen::MatrixXd payload = PayloadTorque(base, d);
    if (j >= 0) {
      const Eigen::VectorXd res = Residual(base, d, j, payload);
      Eigen::VectorXd ndd;
      if (e.name == "joint_flexibility") {
        const Eigen::VectorXd needed = Needed(base, d, j, payload);
        ndd = ThreePointDerivatives(d.log->t, needed).second;
      }
      for (int row = d.first; row < d.last; row += stride_) {
        if (d.kind[static_cast<std::size_t>(row)] != RowKind::kFit) continue;
        fit.r.push_back(res[row]);
        fit.q.push_back(d.log->q(row, j));
        fit.qd.push_back(d.log->qd(row, j));
        fit.qdd.push_back(d.log->qdd(row, j));
        if (ndd.size()) fit.needed_dd.push_back(ndd[row]);
      }
    } else {
      for (int jj = 0; jj < n_; ++jj) {
        const Eigen::VectorXd res = Residual(base, d, jj, payload);
        for (int row = d.first; row < d.last; row += stride_) {
          if (d.kind[static_cast<std::size_t>(row)] != RowKind::kFit) continue;
          fit.payload_r.push_back(res[row]);
          fit.payload_rows.push_back(
              {d.payload[0](row, jj), d.payload[1](row, jj), d.payload[2](row, jj), d.payload[3](row, jj)});
        }
      }
    }
  }
  return fit;
}

void ArmProblem::GuessOnGrid(const ArmModel& base, std::vector<TrialEffect>* effects, int i) const {
  TrialEffect& e = (*effects)[static_cast<std::size_t>(i)];
  const int j = e.joint;
  auto& p = e.parameters;
  // A grid on the residual's cost: quantiles of the commands, or delays.
  std::vector<double> grid;
  const char* key = e.name == "time_delay" ? "delay" : "limit";
  if (e.name == "time_delay") {
    grid = {0.0005, 0.001, 0.002, 0.003, 0.005, 0.007, 0.01, 0.015, 0.02, 0.03, 0.05, 0.07, 0.1, 0.15};
  } else {
    // Quantiles of the logged commands and of what the motion needs: a joint held at
    // its limit needs the limit while its controller's command winds up beyond it
    // (to the effort limit, where every command may be the same number).
    std::vector<double> u, needed;
    for (const ArmLogData& d : data_) {
      const Eigen::VectorXd cmd = Command(base, d, j, PayloadTorque(base, d));
      for (int row = d.first; row < d.last; ++row) {
        u.push_back(std::abs(d.log->tau(row, j)));
        needed.push_back(std::abs(cmd[row]));
      }
    }
    for (std::vector<double>* v : {&u, &needed}) {
      std::sort(v->begin(), v->end());
      for (double q : {0.5, 0.7, 0.8, 0.9, 0.95, 0.98, 0.99, 0.995}) {
        grid.push_back((*v)[std::min(v->size() - 1, static_cast<std::size_t>(q * static_cast<double>(v->size())))]);
      }
    }
  }
  double best = kInf;
  auto try_value = [&](double g) {
    if (!(g > 0)) return;
    std::vector<TrialEffect> trial = *effects;
    trial[static_cast<std::size_t>(i)].parameters = {{key, g}};
    const double c = Cost(trial, {j});
    if (c < best) {
      best = c;
      p = {{key, g}};
    }
  };
  for (double g : grid) try_value(g);
  if (p.empty()) throw CheckFailed("no usable starting value");
  if (e.name == "time_delay") {
    // Then every whole sample between the best's neighbours on the grid (at most 100
    // steps): the cost is
    // piecewise in the delay (the command interpolated between samples; a Coulomb
    // step moves by rows), and the refinement does not cross a sample from a grid
    // point (a 21 ms delay stayed at the grid's 20 ms).
    const auto at = std::find(grid.begin(), grid.end(), p.at(key)) - grid.begin();
    const double low = at > 0 ? grid[static_cast<std::size_t>(at - 1)] : 0.0;
    const double high = at + 1 < static_cast<long>(grid.size()) ? grid[static_cast<std::size_t>(at + 1)] : grid.back();
    const double step = std::max(sample_period_, (high - low) / 100);  // at most 100 evaluations
    for (double g = step * std::ceil(low / step); g < high; g += step) try_value(g);
  }
}

void ArmProblem::GuessFlexibility(const GuessRows& fit, std::vector<TrialEffect>* effects, int i) const {
  TrialEffect& e = (*effects)[static_cast<std::size_t>(i)];
  const int j = e.joint;
  auto& p = e.parameters;
  // Without damping the spring's deflection is needed / k, so the command rises by
  // J_m (qdd + needed'' / k): linear in J_m for each k. A grid over k picks the best.
  const auto rows = static_cast<Eigen::Index>(fit.r.size());
  const Eigen::Map<const Eigen::VectorXd> rv(fit.r.data(), rows);
  const Eigen::Map<const Eigen::VectorXd> a(fit.qdd.data(), rows), ndd(fit.needed_dd.data(), rows);
  double best = kInf;
  for (double k = 10; k < 2e6; k *= 2) {
    const Eigen::VectorXd x = a + ndd / k;
    const double jm = x.squaredNorm() > 0 ? -rv.dot(x) / x.squaredNorm() : 0.0;
    if (!(jm > 0)) continue;
    // Scored on the model itself: the linearisation misleads where the spring is soft.
    std::vector<TrialEffect> trial = *effects;
    trial[static_cast<std::size_t>(i)].parameters = {{"k", k}, {"damping", 0.0}, {"motor_inertia", jm}};
    const double cost = Cost(trial, {j});
    if (cost < best) {
      best = cost;
      p = trial[static_cast<std::size_t>(i)].parameters;
    }
  }
  if (p.empty()) throw CheckFailed("no motor inertia explains the residual");
}

void ArmProblem::InitialGuess(std::vector<TrialEffect>* effects, int i) const {
  TrialEffect& e = (*effects)[static_cast<std::size_t>(i)];
  std::vector<TrialEffect> others = *effects;
  others.erase(others.begin() + i);
  const ArmModel base = Build(others);
  const GuessRows fit = GuessRowsFor(base, e);
  const auto rows = static_cast<Eigen::Index>(fit.r.size());
  const Eigen::Map<const Eigen::VectorXd> rv(fit.r.data(), rows);
  auto& p = e.parameters;
  if (e.name == "viscous_friction") {
    // The command rises by b qd: the residual falls by it.
    const Eigen::Map<const Eigen::VectorXd> v(fit.qd.data(), rows);
    p["b"] = std::max(0.0, v.squaredNorm() > 0 ? rv.dot(v) / v.squaredNorm() : 0.0);
  } else if (e.name == "coulomb_friction") {
    GuessCoulombFriction(fit.qd, rv, &p);
  } else if (e.name == "stribeck_friction") {
    GuessStribeckFriction(fit.qd, rv, &p);
  } else if (ProfileLetter(e.name)) {
    GuessPositionProfile(fit, q_lo_[e.joint], q_hi_[e.joint], LevelFloor(e.joint), e.name == "position_torque",
                         standstill_, rv, &p);
  } else if (e.name == "torque_offset") {
    // The joint receives the command plus tau0: the residual rises by it.
    p["tau0"] = rows ? -rv.mean() : 0.0;
  } else if (e.name == "torque_saturation" || e.name == "time_delay") {
    GuessOnGrid(base, effects, i);
  } else if (e.name == "joint_flexibility") {
    GuessFlexibility(fit, effects, i);
  } else if (e.name == "payload") {
    GuessPayload(fit, &p);
  }
}

// The residual of the free effects' joints as a function of their variables.
class FitFunctor {
 public:
  FitFunctor(const ArmProblem* problem, std::vector<TrialEffect> effects, std::vector<int> free,
             std::vector<int> joints)
      : problem_(problem), effects_(std::move(effects)), free_(std::move(free)), joints_(std::move(joints)) {}

  bool operator()(double const* const* x, double* residual) const {
    std::vector<TrialEffect> trial = effects_;
    for (std::size_t k = 0; k < free_.size(); ++k) {
      TrialEffect& e = trial[static_cast<std::size_t>(free_[k])];
      SetFromFitVariables(x[k], problem_->JointInertia(e.joint), problem_->LevelFloor(e.joint), &e);
    }
    Eigen::VectorXd r;
    try {
      r = problem_->FitResidual(trial, joints_);
    } catch (const InputError&) {
      return false;  // outside the effect's valid range: Ceres steps back
    }
    std::copy(r.data(), r.data() + r.size(), residual);
    return true;
  }

 private:
  const ArmProblem* problem_;
  std::vector<TrialEffect> effects_;
  std::vector<int> free_;
  std::vector<int> joints_;
};

void ArmProblem::Refine(std::vector<TrialEffect>* effects, const std::vector<int>& free) const {
  const std::vector<int> joints = TouchedJoints(*effects, free);
  const Eigen::Index rows = FitResidual(*effects, joints).size();
  if (rows == 0) throw CheckFailed("no fit rows");
  std::vector<ParameterMap> maps;
  std::vector<int> sizes;
  for (int i : free) {
    const TrialEffect& e = (*effects)[static_cast<std::size_t>(i)];
    maps.push_back(FitVariablesOf(e, LevelFloor(e.joint)));
    sizes.push_back(static_cast<int>(maps.back().x.size()));
  }
  ceres::NumericDiffOptions diff;
  diff.relative_step_size = 1e-4;
  auto* cost = new ceres::DynamicNumericDiffCostFunction<FitFunctor, ceres::CENTRAL>(
      new FitFunctor(this, *effects, free, joints), ceres::TAKE_OWNERSHIP, diff);
  for (int s : sizes) cost->AddParameterBlock(s);
  cost->SetNumResiduals(static_cast<int>(rows));
  ceres::Problem problem;
  std::vector<double*> blocks;
  for (auto& m : maps) blocks.push_back(m.x.data());
  problem.AddResidualBlock(cost, nullptr, blocks);
  for (std::size_t b = 0; b < maps.size(); ++b) {
    for (std::size_t k = 0; k < maps[b].x.size(); ++k) {
      if (std::isfinite(maps[b].lower[k])) problem.SetParameterLowerBound(blocks[b], static_cast<int>(k), maps[b].lower[k]);
      if (std::isfinite(maps[b].upper[k])) problem.SetParameterUpperBound(blocks[b], static_cast<int>(k), maps[b].upper[k]);
    }
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 30;
  options.function_tolerance = 1e-8;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  for (std::size_t k = 0; k < free.size(); ++k) {
    TrialEffect& e = (*effects)[static_cast<std::size_t>(free[k])];
    SetFromFitVariables(maps[k].x.data(), JointInertia(e.joint), LevelFloor(e.joint), &e);
  }
  Build(*effects);  // throws InputError when Ceres left the valid range
}

void ArmProblem::CheckLevelsVary(const std::vector<TrialEffect>& effects, int i) const {
  const TrialEffect& e = effects[static_cast<std::size_t>(i)];
  std::vector<TrialEffect> others = effects;
  others.erase(others.begin() + i);
  const GuessRows fit = GuessRowsFor(Build(others), e);
  const char letter = ProfileLetter(e.name);
  const bool torque = letter == 'p';
  double along = 0, across = 0;
  for (std::size_t r = 0; r < fit.r.size(); ++r) {
    const double factor = ProfileFactor(torque, fit.qd[r], standstill_);
    along += factor * fit.r[r];
    across += factor * factor;
  }
  const double best = across > 0 ? along / across : 0.0;
  const double level = torque ? best : std::max(LevelFloor(e.joint), best);
  std::vector<TrialEffect> one = effects;
  auto& levels = one[static_cast<std::size_t>(i)].parameters;
  for (int k = 0; k < ProfileLevelCount(letter, levels); ++k) levels[ProfileLevelKey(letter, k)] = level;
  const double varied = Cost(effects, {e.joint}), flat = Cost(one, {e.joint});
  if (varied <= (1 - kPositionFrictionMargin) * flat) return;
  char msg[240];
  std::snprintf(msg, sizeof msg,
                "its levels remove %.3g %% of the joint's fit-row cost beyond one level of %.3g, under the %g %% a "
                "map of the travel must: %s by another name",
                flat > 0 ? 100 * (1 - varied / flat) : 0.0, level, 100 * kPositionFrictionMargin,
                torque ? "a torque offset" : "Coulomb friction");
  throw CheckFailed(msg);
}

void ArmProblem::TryBristles(std::vector<TrialEffect>* effects, const std::vector<int>& free, int i) const {
  const int j = (*effects)[static_cast<std::size_t>(i)].joint;
  const double plain_cost = Cost(*effects, {j});
  // Start from the best of a grid of deflections at the break-away level, a micro-radian
  // (or micrometre) to the most there is.
  std::vector<TrialEffect> best = *effects;
  double best_cost = kInf;
  for (double deflection = 1e-6; deflection < 1.01 * kMaxBristleDeflection; deflection *= std::sqrt(10.0)) {
    std::vector<TrialEffect> trial = *effects;
    auto& p = trial[static_cast<std::size_t>(i)].parameters;
    SetBristles(std::clamp(p.at("s") / deflection, kMinBristleStiffness, kMaxBristleStiffness), JointInertia(j), &p);
    const double cost = Cost(trial, {j});
    if (cost < best_cost) best_cost = cost, best = std::move(trial);
  }
  // The refinement moves the grid's best by a point or so of the plain cost (17.5 to
  // 18.6 % on the EMPS-like drive with bristles): a grid far from the margin is left there.
  if (!(best_cost < (1 - kBristleMargin / 2) * plain_cost)) return;
  try {
    Refine(&best, free);
    CheckResolved(best[static_cast<std::size_t>(i)]);  // too soft, or Coulomb friction by another name: the plain curve stays
  } catch (const InputError&) {
    return;
  } catch (const CheckFailed&) {
    return;
  }
  if (Cost(best, {j}) > (1 - kBristleMargin) * plain_cost) return;
  // And on the joint's selection rows, unseen by either fit: no worse than the plain curve.
  const auto selection = [&](const std::vector<TrialEffect>& e) {
    const std::vector<double> squared = Evaluate(e).selection_by_channel[static_cast<std::size_t>(j)];
    return std::accumulate(squared.begin(), squared.end(), 0.0);
  };
  if (selection(best) < selection(*effects)) *effects = std::move(best);
}

// The residual's lag (s) against the model: the shift of the model's command that best
// matches the measured one (positive: the measured command leads the model's).
double CommandLag(const Eigen::VectorXd& t, const Eigen::VectorXd& measured, const Eigen::VectorXd& model, int first, int last) {
  const double dt = (t[last - 1] - t[first]) / std::max(1, last - first - 1);
  const int max_shift = std::min(200, static_cast<int>(kMaxLag / dt));
  const std::vector<double> a(measured.data() + first, measured.data() + last), b(model.data() + first, model.data() + last);
  return BestAlignment(a, b, -max_shift, max_shift).shift * dt;
}

std::string ArmProblem::Signature(const TrialEffect& e) const {
  char buf[256];
  const auto& p = e.parameters;
  if (e.name == "viscous_friction") {
    std::snprintf(buf, sizeof buf, "the torque it adds grows with the joint's speed, b = %s N·m·s/rad",
                  FormatParameter(p.at("b")).c_str());
  } else if (e.name == "coulomb_friction") {
    std::snprintf(buf, sizeof buf, "the residual steps where the joint reverses, by %s N·m moving up and %s N·m down, whatever the speed",
                  FormatParameter(p.at("c_pos")).c_str(), FormatParameter(p.at("c_neg")).c_str());
  } else if (e.name == "stribeck_friction") {
    std::snprintf(buf, sizeof buf, "friction breaks away at %s N·m and falls to %s N·m within %s rad/s of standstill",
                  FormatParameter(p.at("s")).c_str(), FormatParameter(p.at("c")).c_str(), FormatParameter(p.at("vs")).c_str());
    if (p.count("sigma0")) {
      const std::string plain = buf;
      std::snprintf(buf, sizeof buf,
                    "%s; before it slides the joint deflects on bristles of %s N·m/rad (%s mrad at the break-away), "
                    "so the friction turns round over a stretch of motion at each reversal, not at once",
                    plain.c_str(), FormatParameter(p.at("sigma0")).c_str(), FormatParameter(1e3 * BristleDeflection(e)).c_str());
    }
  } else if (const char letter = ProfileLetter(e.name)) {
    const bool torque = letter == 'p';
    double lo = kInf, hi = -kInf;
    for (int k = 0; k < ProfileLevelCount(letter, p); ++k) {
      lo = std::min(lo, p.at(ProfileLevelKey(letter, k)));
      hi = std::max(hi, p.at(ProfileLevelKey(letter, k)));
    }
    std::snprintf(buf, sizeof buf,
                  torque ? "a torque that follows the joint's position whether or not it moves, %s to %s N·m over "
                           "%s to %s"
                         : "the friction level changes along the joint's travel, by %s to %s N·m over %s to %s",
                  FormatParameter(lo).c_str(), FormatParameter(hi).c_str(), FormatParameter(p.at("from")).c_str(),
                  FormatParameter(p.at("to")).c_str());
  } else if (e.name == "torque_offset") {
    std::snprintf(buf, sizeof buf, "a constant %s N·m at every posture, speed and acceleration, where a payload's torque would follow gravity",
                  FormatParameter(p.at("tau0")).c_str());
  } else if (e.name == "torque_saturation") {
    int beyond = 0, total = 0;
    for (const ArmLogData& d : data_) {
      for (int r = d.first; r < d.last; ++r) {
        beyond += std::abs(d.log->tau(r, e.joint)) > p.at("limit");
        ++total;
      }
    }
    std::snprintf(buf, sizeof buf, "%.1f %% of the commands exceed %s N·m and move the joint no more than the limit would",
                  100.0 * beyond / std::max(total, 1), FormatParameter(p.at("limit")).c_str());
  } else if (e.name == "time_delay") {
    std::snprintf(buf, sizeof buf, "the logged commands lead the torques the motion needs by %s ms",
                  FormatParameter(1000 * p.at("delay")).c_str());
  } else if (e.name == "joint_flexibility") {
    std::snprintf(buf, sizeof buf, "a motor inertia of %s kg·m² on a spring of %s N·m/rad, a resonance near %s Hz",
                  FormatParameter(p.at("motor_inertia")).c_str(), FormatParameter(p.at("k")).c_str(),
                  FormatParameter(std::sqrt(p.at("k") / p.at("motor_inertia")) / (2 * kPi)).c_str());
  } else if (e.name == "payload") {
    // How much of the payload's torque a constant offset per joint could carry.
    const ArmModel trial = Build({e});
    double total = 0, constant = 0;
    for (const ArmLogData& d : data_) {
      const Eigen::MatrixXd tau = PayloadTorque(trial, d).middleRows(d.first, d.last - d.first);
      for (int j = 0; j < n_; ++j) {
        const double mean = tau.col(j).mean();
        total += tau.col(j).squaredNorm();
        constant += mean * mean * static_cast<double>(tau.rows());
      }
    }
    std::snprintf(buf, sizeof buf,
                  "%s kg at (%s, %s, %s) m in the last link's frame; its torque follows gravity and acceleration on every "
                  "joint, and constant offsets could carry only %.0f %% of it",
                  FormatParameter(p.at("mass")).c_str(), FormatParameter(p.at("x")).c_str(),
                  FormatParameter(p.at("y")).c_str(), FormatParameter(p.at("z")).c_str(),
                  100 * (total > 0 ? constant / total : 0.0));
  } else {
    return "";
  }
  return buf;
}

// Per-joint noise: the residual's part above `cutoff_hz`, scaled to the whole band (white).
double HighFrequencySigma(const Eigen::VectorXd& residual, double rate, double cutoff_hz) {
  const double nyquist = rate / 2;
  if (cutoff_hz >= 0.8 * nyquist || residual.size() < 64) return 0;
  const ButterworthFilter low = DesignButterworthLowPass(4, cutoff_hz, rate);
  const Eigen::VectorXd high = residual - FiltFilt(low, residual);
  const Eigen::Index skip = std::min<Eigen::Index>(high.size() / 4, static_cast<Eigen::Index>(rate * 0.2));
  const Eigen::VectorXd mid = high.segment(skip, high.size() - 2 * skip);
  const double var = (mid.array() - mid.mean()).square().mean();
  return std::sqrt(var * nyquist / (nyquist - cutoff_hz));
}

// The learned residual's inputs at row r of log d: per joint q, qd, qdd and a smooth
// sign of qd. No past motion: with qdd 20 ms earlier the learner modelled the
// derivative filter's own error (jerk) and flagged a correctly repaired joint as
// unexplained (measured: joint 3 beside a payload named and closed 100 %).
void LearnedInputs(const ArmLogData& d, int r, std::vector<double>* x) {
  const ArmLog& log = *d.log;
  x->clear();
  for (int j = 0; j < log.dof; ++j) {
    x->insert(x->end(), {log.q(r, j), log.qd(r, j), log.qdd(r, j), std::tanh(log.qd(r, j) / 0.05)});
  }
}

// The derivative filter's cut-off of log d (Hz): the motion the log resolves.
double FilterCutoff(const ArmLog& log) {
  return log.derive_cutoff_hz > 0 ? log.derive_cutoff_hz : 1.0 / (8 * log.sample_period);
}

std::vector<double> ArmProblem::NoiseFloor() const {
  std::vector<double> variance(static_cast<std::size_t>(n_), 0.0);
  for (const ArmLogData& d : data_) {
    for (int j = 0; j < n_; ++j) {
      const double sigma = HighFrequencySigma(d.log->tau.col(j).segment(d.first, d.last - d.first),
                                              1.0 / d.log->sample_period, 2 * FilterCutoff(*d.log));
      variance[static_cast<std::size_t>(j)] += sigma * sigma / static_cast<double>(data_.size());
    }
  }
  for (double& v : variance) v = std::sqrt(v);
  return variance;
}

TestResiduals ArmProblem::TestRowResiduals(const std::vector<TrialEffect>& effects, bool learn) const {
  const ArmModel trial = Build(effects);
  TestResiduals out;
  const auto n = static_cast<std::size_t>(n_);
  out.residual.resize(n);
  out.noise.assign(n, 0.0);
  for (int j = 0; j < n_; ++j) out.channels.push_back("joint " + std::to_string(j + 1));
  for (int j = 0; j < n_; ++j) {
    // Not the logged command: the residual is that command minus the model's, so they
    // correlate by construction (measured on the KUKA: r = 1.00 on joint 5).
    for (const char* what : {"q", "qd", "qdd"}) out.input_names.push_back(std::string(what) + std::to_string(j + 1));
  }
  out.inputs.resize(out.input_names.size());
  std::vector<std::vector<double>> fit_x, fit_y, test_x;
  std::vector<double> x;
  double cutoff = 0;
  for (const ArmLogData& d : data_) {
    const ArmLog& log = *d.log;
    const Eigen::MatrixXd payload = PayloadTorque(trial, d);
    std::vector<Eigen::VectorXd> res(n);
    cutoff = std::max(cutoff, FilterCutoff(log));
    for (int j = 0; j < n_; ++j) res[static_cast<std::size_t>(j)] = Residual(trial, d, j, payload);
    int fit_count = 0;
    for (int r = d.first; r < d.last; ++r) {
      const RowKind kind = d.kind[static_cast<std::size_t>(r)];
      if (kind == RowKind::kTest) {
        for (std::size_t j = 0; j < n; ++j) {
          const int jj = static_cast<int>(j);
          out.residual[j].push_back(res[j][r]);
          out.inputs[3 * j].push_back(log.q(r, jj));
          out.inputs[3 * j + 1].push_back(log.qd(r, jj));
          out.inputs[3 * j + 2].push_back(log.qdd(r, jj));
        }
        if (learn) {
          LearnedInputs(d, r, &x);
          test_x.push_back(x);
        }
      } else if (learn && kind == RowKind::kFit && fit_count++ % stride_ == 0) {
        LearnedInputs(d, r, &x);
        fit_x.push_back(x);
        std::vector<double> y(n);
        for (std::size_t j = 0; j < n; ++j) y[j] = res[j][r];
        fit_y.push_back(y);
      }
    }
  }
  out.noise = noise_;
  out.rate = 1.0 / sample_period_;
  out.step = std::max(1, static_cast<int>(std::ceil(out.rate / (2 * cutoff))));
  if (learn && !fit_x.empty() && !test_x.empty()) {
    // At most kMaxLearnedRows training rows, spread evenly.
    const std::size_t every = std::max<std::size_t>(1, fit_x.size() / kMaxLearnedRows);
    const auto rows = static_cast<Eigen::Index>((fit_x.size() + every - 1) / every);
    const auto inputs = static_cast<Eigen::Index>(fit_x.front().size());
    Eigen::MatrixXd ax(rows, inputs), ay(rows, n_);
    for (Eigen::Index k = 0; k < rows; ++k) {
      const std::size_t i = static_cast<std::size_t>(k) * every;
      ax.row(k) = Eigen::Map<const Eigen::RowVectorXd>(fit_x[i].data(), inputs);
      ay.row(k) = Eigen::Map<const Eigen::RowVectorXd>(fit_y[i].data(), n_);
    }
    const RandomFeatureRidge learner = RandomFeatureRidge::Fit(ax, ay, kLearnedFeatures, 1);
    Eigen::MatrixXd tx(static_cast<Eigen::Index>(test_x.size()), inputs);
    for (std::size_t i = 0; i < test_x.size(); ++i) tx.row(static_cast<Eigen::Index>(i)) = Eigen::Map<const Eigen::RowVectorXd>(test_x[i].data(), inputs);
    const Eigen::MatrixXd correction = learner.Predict(tx);
    out.learned = out.residual;
    for (std::size_t j = 0; j < n; ++j) {
      for (std::size_t i = 0; i < out.learned[j].size(); ++i) out.learned[j][i] -= correction(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    }
    out.learner = "kernel ridge regression (random Fourier features) of the torque residual on every joint's q, qd, qdd, "
                  "a smooth sign of qd, trained on " + std::to_string(rows) + " fit rows";
  }
  return out;
}

}  // namespace

Eigen::Matrix<double, 10, 1> PointMassParameters(double mass, const Eigen::Vector3d& p) {
  const Eigen::Matrix3d io = mass * (p.squaredNorm() * Eigen::Matrix3d::Identity() - p * p.transpose());
  Eigen::Matrix<double, 10, 1> pi;
  pi << mass, mass * p.x(), mass * p.y(), mass * p.z(), io(0, 0), io(0, 1), io(0, 2), io(1, 1), io(1, 2), io(2, 2);
  return pi;
}

namespace {

// `model` with its base parameters and friction identified on the fit blocks.
ArmModel RefitOnFitBlocks(const ArmModel& model, const std::vector<ArmLog>& logs, double block, double held_out) {
  WlsIdentificationOptions wls;
  wls.skip_filter_edges = false;  // ArmFitBlockLogs left the edges out
  try {
    ArmModel refitted = IdentifyArmByLeastSquares(model, ArmFitBlockLogs(logs, block, held_out), wls);
    refitted.name = model.name, refitted.source_path = model.source_path;
    return refitted;
  } catch (const InputError& e) {
    throw InputError(std::string("--refit-model: ") + e.what());
  }
}

// s: the windows the test rows are simulated in. A 20 s log's 1 s test blocks hold one
// 0.5 s window each between their guards; logs under 10 s (0.5 s blocks) only 0.1 s ones.
constexpr double kSimulationHorizons[] = {0.1, 0.5};

// `given` and `repaired` simulated from the logs' torques in windows wholly in test rows,
// per horizon that at least one window fits, pooled over the logs (RMSE weighted by rows).
std::vector<DiagnosisSimulation> SimulateTestRows(const ArmModel& given, const ArmModel& repaired,
                                                  const std::vector<ArmLogData>& data) {
  std::vector<DiagnosisSimulation> out;
  for (double horizon : kSimulationHorizons) {
    DiagnosisSimulation sim;
    sim.seconds = horizon;
    const int n = given.dof();
    Eigen::ArrayXd nominal = Eigen::ArrayXd::Zero(n), fixed = nominal, velocity = nominal;
    for (const ArmLogData& d : data) {
      ArmSimulationScoreOptions options;
      options.horizons = {horizon};
      options.drop_long_horizons = true;
      options.scored_rows = [&d](int row) {
        return row >= d.first && row < d.last && d.kind[static_cast<std::size_t>(row)] == RowKind::kTest;
      };
      const ArmSimulationScore a = ScoreArmSimulation(given, *d.log, options);
      const ArmSimulationScore b = ScoreArmSimulation(repaired, *d.log, options);
      if (a.horizons.empty() || b.horizons.empty()) continue;
      const ArmHorizonScore& ha = a.horizons.front();
      const ArmHorizonScore& hb = b.horizons.front();
      sim.windows += ha.windows;
      sim.rows += ha.rows;
      nominal += ha.rows * ha.rmse.array().square();
      fixed += hb.rows * hb.rmse.array().square();
      velocity += ha.rows * ha.constant_velocity.array().square();
    }
    if (sim.rows == 0) continue;
    for (int j = 0; j < n; ++j) {
      sim.nominal.push_back(std::sqrt(nominal[j] / sim.rows));
      sim.repaired.push_back(std::sqrt(fixed[j] / sim.rows));
      sim.constant_velocity.push_back(std::sqrt(velocity[j] / sim.rows));
    }
    out.push_back(std::move(sim));
  }
  return out;
}

}  // namespace

namespace {

// Checks what diagnose is given before any work: joints, logs that match the model and
// hold finite numbers, logs long enough to hold out blocks. Returns the block length (s).
// Throws InputError naming the file and line.
double CheckArmInputs(const ArmModel& model, const std::vector<ArmLog>& logs, const DiagnosisOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  if (model.dof() == 0) throw InputError(SourceLocation{model.source_path}, "the model has no joints: nothing to diagnose");
  if (logs.empty()) throw InputError("diagnose needs at least one --log");
  std::vector<double> durations;
  for (const ArmLog& log : logs) {
    CheckArmLogMatchesModel(log, model);
    for (Eigen::Index r = 0; r < log.rows(); ++r) {
      for (int j = 0; j < log.dof; ++j) {
        if (!std::isfinite(log.q(r, j)) || !std::isfinite(log.qd(r, j)) || !std::isfinite(log.qdd(r, j)) ||
            !std::isfinite(log.tau(r, j))) {
          throw InputError(SourceLocation{log.path, log.line_of[static_cast<std::size_t>(r)]},
                           "joint " + std::to_string(j + 1) + " holds a value that is not a finite number");
        }
      }
    }
    durations.push_back(log.t[log.rows() - 1] - log.t[0]);
  }
  const double block = HeldOutBlockSeconds(options.block_seconds, durations);
  for (const ArmLog& log : logs) {
    std::vector<double> t(log.t.data(), log.t.data() + log.rows() - log.edge_samples);
    CheckLogHoldsOut(t, static_cast<std::size_t>(log.edge_samples), block, options.held_out, log.path);
  }
  return block;
}

// Find, for joint j: the nominal and the repaired model's residuals over every log, what
// they correlate with, the command's lag, the residual's noise (the repaired model's fast
// content: what an added effect explains, a resonance, is not noise) and, from the first
// log, the series and spectra the report plots.
void FindJoint(const ArmProblem& problem, const ArmModel& model, const ArmModel& nominal_model,
               const ArmModel& repaired_model, const std::vector<Eigen::MatrixXd>& nominal_payload,
               const std::vector<Eigen::MatrixXd>& repaired_payload, int j, DiagnosisReport* report) {
  const auto& data = problem.data();
  ChannelFinding f;
  ChannelSeries s;
  f.channel = "joint " + std::to_string(j + 1);
  f.unit = model.joints[static_cast<std::size_t>(j)].type == JointType::kPrismatic ? "N" : "N·m";
  ChannelSamples x;
  double lag_sum = 0, noise_joint = 0;
  for (std::size_t k = 0; k < data.size(); ++k) {
    const ArmLogData& d = data[k];
    const ArmLog& log = *d.log;
    const Eigen::VectorXd rb = problem.Residual(nominal_model, d, j, nominal_payload[k]);
    const Eigen::VectorXd ra = problem.Residual(repaired_model, d, j, repaired_payload[k]);
    const Eigen::VectorXd cmd = problem.Command(nominal_model, d, j, nominal_payload[k]);
    lag_sum += CommandLag(log.t, log.tau.col(j), cmd, d.first, d.last);
    const double rate = 1.0 / log.sample_period;
    const double cutoff = log.derive_cutoff_hz > 0 ? 2 * log.derive_cutoff_hz : rate / 8;
    const double sigma = HighFrequencySigma(ra.segment(d.first, d.last - d.first), rate, cutoff);
    noise_joint += sigma * sigma;
    // Reversals: where the velocity changes sign or the joint stands.
    ReversalWindows reversals(std::vector<double>(log.t.data() + d.first, log.t.data() + d.last),
                              std::vector<double>(log.qd.col(j).data() + d.first, log.qd.col(j).data() + d.last),
                              kStandFraction, kReversalWindow);
    for (int r = d.first; r < d.last; ++r) {
      x.before.push_back(rb[r]);
      x.after.push_back(ra[r]);
      x.velocity.push_back(log.qd(r, j));
      x.acceleration.push_back(log.qdd(r, j));
      (reversals.Near(log.t[r]) ? x.near_reversal : x.moving).push_back(rb[r]);
    }
    if (k == 0) {
      // Plots: the first log, subsampled.
      const int step = std::max(1, (d.last - d.first) / kPlotPoints);
      for (int r = d.first; r < d.last; r += step) {
        s.t.push_back(log.t[r]);
        s.before.push_back(rb[r]);
        s.after.push_back(ra[r]);
        s.velocity.push_back(log.qd(r, j));
      }
      ResidualSpectra(std::vector<double>(rb.data() + d.first, rb.data() + d.last),
                      std::vector<double>(ra.data() + d.first, ra.data() + d.last), rate, kWelchSegmentCap, &s);
    }
  }
  DescribeChannel(x, s, &f);
  f.lag = lag_sum / static_cast<double>(data.size());
  f.noise = std::sqrt(noise_joint / static_cast<double>(data.size()));
  report->findings.push_back(f);
  report->series.push_back(std::move(s));
}

// The notes on the model's own effects, and on what a simulator is for: the motion from
// the torques on the test rows, where the repaired model follows them worse.
void NoteTrustAndSimulation(const ArmModel& model, const ArmModel& repaired_model, const ArmProblem& problem,
                            bool any_added, DiagnosisReport* report) {
  if (model.effects.payload_mass > 0) report->notes.push_back("the model already has a payload: no payload candidate was tried");
  for (const ArmEffect& e : ListArmEffects(model.effects)) {
    report->notes.push_back("the model's own " + EffectLabel(e.name, e.joint) + " was trusted, not refitted");
  }
  report->simulation = SimulateTestRows(model, repaired_model, problem.data());
  for (const DiagnosisSimulation& sim : report->simulation) {
    std::string worse;
    for (std::size_t j = 0; j < sim.nominal.size(); ++j)
      if (sim.repaired[j] > sim.nominal[j]) worse += (worse.empty() ? "" : ", ") + std::to_string(j + 1);
    if (!worse.empty() && any_added) {
      report->notes.push_back("simulated from the torques over " + FormatParameter(sim.seconds) +
                              " s, the repaired model follows the test rows worse than the given one on joint(s) " + worse);
    }
  }
}

}  // namespace

DiagnosisReport DiagnoseArm(const ArmModel& model, const std::vector<ArmLog>& logs, const DiagnosisOptions& options,
                            ArmModel* repaired, const std::function<void(const std::string&)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  const double block = CheckArmInputs(model, logs, options);
  // With --refit-model the effects are sought on top of the model re-identified on the
  // fit blocks alone (the held-out blocks stay unseen); the gap before is still the
  // given model's.
  const ArmModel start_model = options.refit_model ? RefitOnFitBlocks(model, logs, block, options.held_out) : model;
  ArmProblem problem(start_model, logs, block, options.held_out, options.standstill);
  problem.SetStride();
  const SelectionResult selection = SelectEffects(problem, options, progress);

  DiagnosisReport report;
  DiagnosisReportHeader header{"arm", model.name,
                               "RMS over joints and held-out samples of the measured command minus the model's (N·m or N)",
                               block, problem.guard_seconds(), {}};
  for (const ArmLog& log : logs) header.logs.push_back(log.path);
  ReportSelection(header, problem, selection, options, &report);
  if (options.refit_model) {
    ReportRefit(ArmProblem(model, logs, block, options.held_out, options.standstill),
                "The model's own inertial parameters and friction were refitted on the fit blocks (twinsim identify's "
                "weighted least squares)",
                &report);
  }

  // Find: per joint, the nominal and the repaired model's residuals.
  const ArmModel nominal_model = problem.Build({});
  const ArmModel repaired_model = problem.Build(selection.effects);
  std::vector<Eigen::MatrixXd> nominal_payload, repaired_payload;  // per log
  for (const ArmLogData& d : problem.data()) {
    nominal_payload.push_back(problem.PayloadTorque(nominal_model, d));
    repaired_payload.push_back(problem.PayloadTorque(repaired_model, d));
  }
  double noise_sq = 0;
  for (int j = 0; j < model.dof(); ++j) {
    FindJoint(problem, model, nominal_model, repaired_model, nominal_payload, repaired_payload, j, &report);
    noise_sq += report.findings.back().noise * report.findings.back().noise;
  }
  report.noise_floor = std::sqrt(noise_sq / model.dof());
  NoteTrustAndSimulation(model, repaired_model, problem, !selection.effects.empty(), &report);
  if (repaired) *repaired = repaired_model;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace twinsim

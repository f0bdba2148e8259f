#include "learning/arm_predictor.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "io/yaml_reader.h"
#include "learning/predictor_file.h"
#include "robots/arm/arm_regressor.h"

namespace twinsim {

ArmPredictor MakeLinearArmPredictor(ArmPredictorInfo info, Eigen::VectorXd mean, Eigen::VectorXd scale,
                                    Eigen::MatrixXd weights, Eigen::VectorXd bias) {
  ArmPredictor p;
  p.info_ = std::move(info);
  p.input_mean_ = std::move(mean);
  p.input_scale_ = std::move(scale);
  p.weights_ = std::move(weights);
  p.bias_ = std::move(bias);
  return p;
}

ArmPredictor MakeMlpArmPredictor(ArmPredictorInfo info, Mlp mlp) {
  ArmPredictor p;
  p.info_ = std::move(info);
  p.mlp_ = std::move(mlp);
  return p;
}

ArmPredictor::NominalSlot& ArmPredictor::NominalSlot::operator=(const NominalSlot& other) {
  if (this == &other) return *this;
  std::unique_ptr<ArmNominalStep> fresh;
  {
    const std::lock_guard<std::mutex> lock(other.mutex);
    if (other.step) fresh = std::make_unique<ArmNominalStep>(other.step->model());
  }
  const std::lock_guard<std::mutex> lock(mutex);
  step = std::move(fresh);
  return *this;
}

void ArmPredictor::PredictOutputs(const double* inputs, double* outputs) const {
  const long in = info_.layout.num_inputs(), out = info_.layout.num_outputs();
  const Eigen::Map<const Eigen::VectorXd> x(inputs, in);
  Eigen::Map<Eigen::VectorXd> y(outputs, out);
  if (info_.kind == "mlp") {
    y = mlp_.Predict(x);
  } else {
    y = weights_ * (x - input_mean_).cwiseQuotient(input_scale_) + bias_;
  }
}

void ArmPredictor::Predict(const double* q, const double* qd, const double* tau, double* q_next,
                           double* qd_next) const {
  const ArmFeatureLayout& l = info_.layout;
  double x_small[512], y_small[128];
  std::vector<double> x_big, y_big;
  double* x = x_small;
  double* y = y_small;
  if (l.num_inputs() > 512) x_big.resize(static_cast<std::size_t>(l.num_inputs())), x = x_big.data();
  if (l.num_outputs() > 128) y_big.resize(static_cast<std::size_t>(l.num_outputs())), y = y_big.data();
  EncodeArmInputs(l, q, qd, tau, x);
  const std::size_t newest = static_cast<std::size_t>((l.history - 1) * l.dof());
  if (!info_.residual) {
    PredictOutputs(x, y);
    DecodeArmOutputs(l, y, q + newest, qd + newest, q_next, qd_next);
    return;
  }
  {
    // The nominal model's recent errors (inputs) and its step from the newest state under
    // the torques acting from it on (rows history-1 .. history+H-2).
    const std::lock_guard<std::mutex> lock(nominal_.mutex);
    if (!nominal_.step)
      throw std::logic_error("residual arm predictor" + (path_.empty() ? std::string() : " " + path_) +
                             ": no nominal model attached (ArmPredictor::AttachModel)");
    if (l.nominal_errors) EncodeNominalErrors(l, *nominal_.step, q, qd, tau, x + l.num_base_inputs());
    nominal_.step->Step(q + newest, qd + newest, tau + newest, l.horizon, q_next, qd_next);
  }
  // The learned correction on top.
  PredictOutputs(x, y);
  const int n = l.dof();
  for (int i = 0; i < n; ++i) {
    q_next[i] += y[i];
    qd_next[i] += y[n + i];
  }
}

void ArmPredictor::AttachModel(const ArmModel& model, const std::string& use) {
  CheckUse(model, info_.layout.horizon, use);
  if (info_.residual) nominal_.Set(model);
}

void ArmPredictor::CheckUse(const ArmModel& model, int horizon, const std::string& use) const {
  const SourceLocation where{path_};
  const ArmFeatureLayout& l = info_.layout;
  if (info_.model_name != model.name)
    throw InputError(where, "predictor was trained for arm model '" + info_.model_name + "', not '" + model.name +
                                "' (" + use + ")");
  const ArmFeatureLayout wanted = ArmLayoutFor(model, l.history, l.horizon);
  if (wanted.joints != l.joints)
    throw InputError(where, "predictor was trained for " + std::to_string(l.dof()) + " joints (" + l.joints +
                                "), model '" + model.name + "' has " + std::to_string(model.dof()) + " (" +
                                wanted.joints + ") (" + use + ")");
  if (std::abs(l.sample_time - model.sample_time) > 1e-3 * model.sample_time) {
    std::ostringstream msg;
    msg << "predictor was trained at a sample time of " << l.sample_time << " s, model '" << model.name << "' has "
        << model.sample_time << " s (" << use << ")";
    throw InputError(where, msg.str());
  }
  if (l.command_lag != model.delay_samples)
    throw InputError(where, "predictor assumes a delay of " + std::to_string(l.command_lag) + " samples, model '" +
                                model.name + "' has " + std::to_string(model.delay_samples) + " (" + use + ")");
  if (l.horizon != horizon)
    throw InputError(where, "predictor predicts " + std::to_string(l.horizon) + " sample(s) ahead, " + use +
                                " needs " + std::to_string(horizon));
  if (info_.residual) {
    // The correction was learned on top of these parameters' nominal step.
    const Eigen::VectorXd pi = StandardParameters(model);
    const std::vector<std::string> names = StandardParameterNames(model);
    if (pi.size() != info_.nominal_parameters.size())
      throw InputError(where, "residual predictor holds " + std::to_string(info_.nominal_parameters.size()) +
                                  " nominal parameters, model '" + model.name + "' has " + std::to_string(pi.size()) +
                                  " (" + use + ")");
    for (Eigen::Index k = 0; k < pi.size(); ++k) {
      const double a = info_.nominal_parameters[k], b = pi[k];
      if (std::abs(a - b) > 1e-9 * std::max({1.0, std::abs(a), std::abs(b)})) {
        std::ostringstream msg;
        msg << std::setprecision(17) << "residual predictor corrects model '" << info_.model_name
            << "' with parameter " << names[static_cast<std::size_t>(k)] << " = " << a << ", this model file has "
            << b << "; retrain it for this model (" << use << ")";
        throw InputError(where, msg.str());
      }
    }
  }
}

void ArmPredictor::Save(const std::string& path) const {
  const ArmFeatureLayout& l = info_.layout;
  YAML::Emitter out;
  BeginPredictorFile(out, kArmPredictorFormatVersion);
  out << YAML::Key << "robot" << YAML::Value << "arm";
  out << YAML::Key << "kind" << YAML::Value << info_.kind;
  out << YAML::Key << "residual" << YAML::Value << info_.residual;
  out << YAML::Key << "model" << YAML::Value << info_.model_name;
  if (info_.residual) {
    // What the nominal step was: this model's standard parameters (12 per joint).
    out << YAML::Key << "nominal" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "step" << YAML::Value << "analytic";
    EmitVector(out, "parameters", info_.nominal_parameters.data(), info_.nominal_parameters.size());
    out << YAML::EndMap;
  }
  out << YAML::Key << "dof" << YAML::Value << l.dof();
  out << YAML::Key << "sample_time" << YAML::Value << l.sample_time;
  out << YAML::Key << "layout" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "joints" << YAML::Value << l.joints;
  out << YAML::Key << "history" << YAML::Value << l.history;
  out << YAML::Key << "horizon" << YAML::Value << l.horizon;
  out << YAML::Key << "command_lag" << YAML::Value << l.command_lag;
  if (info_.residual) out << YAML::Key << "nominal_errors" << YAML::Value << l.nominal_errors;
  out << YAML::Key << "inputs" << YAML::Value << l.num_inputs();
  out << YAML::Key << "outputs" << YAML::Value << l.num_outputs();
  out << YAML::EndMap;
  EmitTrainedOn(out, info_.logs, info_.samples,
                {{"train_rmse", info_.train_rmse},
                 {"validation_rmse", info_.validation_rmse},
                 {"validation_qd_rmse", info_.validation_qd_rmse},
                 {"validation_rollout_rmse", info_.validation_rollout_rmse}});
  EmitPredictorModel(out, info_.kind, input_mean_, input_scale_, weights_, bias_, mlp_);
  WritePredictorFile(out, path);
}

ArmPredictor ArmPredictor::Load(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  CheckPredictorRobot(root, path, RobotKind::kArm);
  ErrorList errors;
  YamlMap top(root, path, "", &errors);
  const int version = ReadPredictorVersion(top, "arm predictor", 1, kArmPredictorFormatVersion);
  ArmPredictorInfo info;
  ArmFeatureLayout& l = info.layout;
  top.Require("kind", &info.kind, std::vector<std::string>{"linear", "mlp"});
  if (version >= 2) top.Require("residual", &info.residual);  // version 1 knew no residual predictors
  top.Require("model", &info.model_name);
  int dof = 0;
  top.Require("dof", &dof, InRange(1, 64));
  if (info.residual) {
    if (top.Has("nominal")) {
      YamlMap m(top.Child("nominal"), path, "nominal", &errors);
      std::string step;
      m.Require("step", &step, std::vector<std::string>{"analytic"});
      if (dof > 0) info.nominal_parameters = ReadVector(m, "parameters", 12 * dof);
      m.Finish();
    } else {
      top.Missing("nominal");
    }
  } else if (top.Has("nominal")) {
    top.Error("nominal", "only a residual predictor (residual: true) has a nominal model");
  }
  top.Require("sample_time", &l.sample_time, Positive());
  if (top.Has("layout")) {
    YamlMap m(top.Child("layout"), path, "layout", &errors);
    if (m.Require("joints", &l.joints)) {
      if (l.joints.find_first_not_of("RP") != std::string::npos)
        m.Error("joints", "must be one letter per joint, R (revolute) or P (prismatic), got '" + l.joints + "'");
      else if (dof > 0 && l.dof() != dof)
        m.Error("joints", "names " + std::to_string(l.dof()) + " joints but dof is " + std::to_string(dof));
    }
    m.Require("history", &l.history, InRange(1, 100));
    m.Require("horizon", &l.horizon, InRange(1, 100));
    m.Require("command_lag", &l.command_lag, InRange(0, 1000));
    if (info.residual)
      m.Require("nominal_errors", &l.nominal_errors);
    else if (m.Has("nominal_errors"))
      m.Error("nominal_errors", "only a residual predictor (residual: true) has the nominal model's errors as inputs");
    errors.ThrowIfAny();
    int inputs = 0, outputs = 0;
    if (m.Require("inputs", &inputs) && inputs != l.num_inputs())
      m.Error("inputs", "does not match the joints, history and horizon (expected " + std::to_string(l.num_inputs()) + ")");
    if (m.Require("outputs", &outputs) && outputs != l.num_outputs())
      m.Error("outputs", "expected " + std::to_string(l.num_outputs()) + " (2 per joint)");
    m.Finish();
  } else {
    top.Missing("layout");
  }
  ReadTrainedOn(top, &info.logs, &info.samples,
                {{"train_rmse", &info.train_rmse},
                 {"validation_rmse", &info.validation_rmse},
                 {"validation_qd_rmse", &info.validation_qd_rmse},
                 {"validation_rollout_rmse", &info.validation_rollout_rmse}});
  errors.ThrowIfAny();

  const int in = l.num_inputs(), out = l.num_outputs();
  LinearPredictorParameters linear;
  Mlp mlp;
  ReadPredictorModel(top, info.kind, in, out, path, &errors, &linear, &mlp);
  ArmPredictor p = info.kind == "linear" ? MakeLinearArmPredictor(info, linear.input_mean, linear.input_scale,
                                                                  linear.weights, linear.bias)
                                         : MakeMlpArmPredictor(info, std::move(mlp));
  p.path_ = path;
  return p;
}

bool ArmTrainOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (kind != "linear" && kind != "mlp") return fail("--kind must be linear or mlp, got '" + kind + "'");
  if (history < 1 || history > 50) return fail("--history must be 1 to 50 samples, got " + std::to_string(history));
  if (horizon < 1 || horizon > 100) return fail("--horizon must be 1 to 100 samples, got " + std::to_string(horizon));
  if (!(ridge >= 0) || !(residual_ridge >= 0)) return fail("ridge must not be negative");
  if (!(validation_fraction > 0 && validation_fraction < 0.9)) return fail("validation fraction must be in (0, 0.9)");
  if (!(rollout_seconds >= 0)) return fail("rollout seconds must not be negative");
  if (kind == "mlp") return mlp.IsValid(why);
  return true;
}

std::string ArmTrainSummary::BriefReport() const {
  std::ostringstream s;
  s << samples << " samples (" << train_samples << " for training), one-step q RMSE " << train_rmse * 1e6
    << " urad on training, " << validation_rmse * 1e6 << " urad held out (qd " << validation_qd_rmse * 1e3
    << " mrad/s), " << seconds << " s";
  if (validation_rollout_rmse > 0) s << "; on its own: " << validation_rollout_rmse * 1e3 << " mrad held out";
  if (!mlp_report.empty()) s << "; " << mlp_report;
  return s.str();
}

Eigen::MatrixXd ArmRolloutError(const ArmPredictor& predictor, const ArmSequence& seq, int start, int steps) {
  const ArmFeatureLayout& l = predictor.layout();
  const int n = l.dof(), h = l.history;
  if (l.horizon != 1) throw std::invalid_argument("ArmRolloutError: needs a 1-sample predictor");
  if (seq.dof != n || start - h + 1 < seq.first_known_torque || start + steps >= seq.rows() || steps < 0)
    throw std::invalid_argument("ArmRolloutError: the window does not fit the sequence");
  std::vector<double> q(seq.q.begin() + (start - h + 1) * n, seq.q.begin() + (start + 1) * n);
  std::vector<double> qd(seq.qd.begin() + (start - h + 1) * n, seq.qd.begin() + (start + 1) * n);
  std::vector<double> q_next(static_cast<std::size_t>(n)), qd_next(static_cast<std::size_t>(n));
  Eigen::MatrixXd error(steps, n);
  for (int t = 0; t < steps; ++t) {
    const int i = start + t;
    predictor.Predict(q.data(), qd.data(), &seq.acting[static_cast<std::size_t>((i - h + 1) * n)], q_next.data(),
                      qd_next.data());
    q.erase(q.begin(), q.begin() + n);
    qd.erase(qd.begin(), qd.begin() + n);
    q.insert(q.end(), q_next.begin(), q_next.end());
    qd.insert(qd.end(), qd_next.begin(), qd_next.end());
    for (int j = 0; j < n; ++j) error(t, j) = q_next[static_cast<std::size_t>(j)] - seq.q[static_cast<std::size_t>((i + 1) * n + j)];
  }
  return error;
}

namespace {

double QRmse(const Eigen::MatrixXd& predicted, const Eigen::MatrixXd& truth, int dof, int offset) {
  if (truth.rows() == 0) return 0;
  return std::sqrt((predicted.middleCols(offset, dof) - truth.middleCols(offset, dof)).squaredNorm() /
                   static_cast<double>(truth.rows() * dof));
}

}  // namespace

namespace {

// A log's windows in time order, and the first held-out row.
using SplitArmLog = std::pair<ArmSequence, int>;

// Per log: the first part trains, the last part validates (time order kept); a residual
// predictor's windows hold what remains after `nominal`'s step. Throws InputError for a
// log of another sample time or too short to give windows to both.
std::vector<SplitArmLog> SplitArmLogs(const ArmModel& model, const std::vector<ArmLog>& logs,
                                      const ArmTrainOptions& options, ArmNominalStep* nominal, ArmPredictorInfo* info,
                                      ArmDataset* train, ArmDataset* validation) {
  const ArmFeatureLayout& l = info->layout;
  std::vector<SplitArmLog> split;
  for (const ArmLog& log : logs) {
    CheckArmLogMatchesModel(log, model);
    if (std::abs(log.sample_period - model.sample_time) > 0.01 * model.sample_time) {
      std::ostringstream msg;
      msg << "sample period " << log.sample_period << " s differs from model '" << model.name << "''s sample time "
          << model.sample_time << " s (the predictor steps one model sample at a time)";
      throw InputError(SourceLocation{log.path, log.line_of.empty() ? 0 : log.line_of.front()}, msg.str());
    }
    ArmSequence seq = ToArmSequence(log, l);
    const int cut = static_cast<int>(std::round(seq.rows() * (1 - options.validation_fraction)));
    const int n_train = AppendArmSamples(seq, l, 0, cut - 1 - l.horizon, train, nominal);
    const int n_val = AppendArmSamples(seq, l, cut, seq.rows() - 1, validation, nominal);
    if (n_train < 10 || n_val < 1) {
      const int needed = l.command_lag + l.history + l.horizon;
      throw InputError(SourceLocation{log.path}, "log too short: " + std::to_string(log.rows()) + " rows give " +
                                                     std::to_string(n_train + n_val) + " windows (history " +
                                                     std::to_string(l.history) + " + delay " +
                                                     std::to_string(l.command_lag) + " + horizon " +
                                                     std::to_string(l.horizon) + " = " + std::to_string(needed) +
                                                     " consecutive rows each; at least 10 to train on and 1 held "
                                                     "out, after the last " +
                                                     std::to_string(static_cast<int>(options.validation_fraction * 100)) +
                                                     " % is held out, are needed)");
    }
    info->logs.push_back(log.path);
    split.emplace_back(std::move(seq), cut);
  }
  return split;
}

// The predictor's outputs for every window of `d` (rows x outputs).
Eigen::MatrixXd PredictArmAll(const ArmPredictor& predictor, const ArmDataset& d, const ArmFeatureLayout& l) {
  Eigen::MatrixXd out(d.rows(), l.num_outputs());
  Eigen::VectorXd row(l.num_inputs()), y(l.num_outputs());
  for (int i = 0; i < d.rows(); ++i) {
    row = d.x.row(i).transpose();
    predictor.PredictOutputs(row.data(), y.data());
    out.row(i) = y.transpose();
  }
  return out;
}

// The model on its own over the held-out part: free runs of `rollout_seconds`, started
// every tenth of that; the RMS joint error (infinite where a run diverged).
double ArmRolloutRmse(const ArmPredictor& predictor, const std::vector<SplitArmLog>& split, const ArmFeatureLayout& l,
                      double rollout_seconds) {
  const int steps = std::max(1, static_cast<int>(std::lround(rollout_seconds / l.sample_time)));
  const int every = std::max(1, steps / 10 * 10);
  double sum = 0;
  long count = 0;
  for (const auto& [seq, cut] : split) {
    for (int s = std::max(cut, seq.first_known_torque + l.history - 1); s + steps < seq.rows(); s += every) {
      const Eigen::MatrixXd e = ArmRolloutError(predictor, seq, s, steps);
      if (!e.allFinite()) {
        sum = INFINITY;
        continue;
      }
      sum += e.squaredNorm();
      count += e.size();
    }
  }
  return count ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

}  // namespace

ArmPredictor TrainArmPredictor(const ArmModel& model, const std::vector<ArmLog>& logs, const ArmTrainOptions& options,
                               ArmTrainSummary* summary, const std::function<void(int, int, double)>& progress) {
  if (std::string problem; !options.IsValid(&problem)) throw InputError(problem);
  if (logs.empty()) throw InputError("no logs to train on");

  ArmPredictorInfo info;
  info.kind = options.kind;
  info.residual = options.residual;
  info.model_name = model.name;
  info.layout = ArmLayoutFor(model, options.history, options.horizon);
  info.layout.nominal_errors = options.residual && options.nominal_errors.value_or(options.kind == "linear");
  const ArmFeatureLayout& l = info.layout;
  const int n = l.dof();
  // A residual predictor learns what remains after the nominal model's step.
  std::unique_ptr<ArmNominalStep> nominal;
  if (options.residual) {
    info.nominal_parameters = StandardParameters(model);
    nominal = std::make_unique<ArmNominalStep>(model);
  }
  ArmDataset train, validation;
  const std::vector<SplitArmLog> split = SplitArmLogs(model, logs, options, nominal.get(), &info, &train, &validation);
  info.samples = train.rows() + validation.rows();

  const auto start = std::chrono::steady_clock::now();
  std::string mlp_report;
  ArmPredictor predictor;
  if (options.kind == "linear") {
    // Ridge regression on centred, scaled inputs, closed form; the bias is the mean
    // output (gravity and torque offsets make a constant part).
    const Eigen::RowVectorXd x_mean = train.x.colwise().mean(), y_mean = train.y.colwise().mean();
    Eigen::VectorXd scale;
    const double ridge = options.residual ? options.residual_ridge : options.ridge;
    const Eigen::MatrixXd w = FitRidge(train.x.rowwise() - x_mean, train.y.rowwise() - y_mean, ridge, &scale);  // in x out
    predictor = MakeLinearArmPredictor(info, x_mean.transpose(), scale, w.transpose(), y_mean.transpose());
  } else {
    // The network early-stops on the held-out windows, placed last.
    predictor = MakeMlpArmPredictor(
        info, TrainMlpHoldingOut(train.x, train.y, validation.x, validation.y, options.mlp, progress, &mlp_report));
  }
  if (options.residual) predictor.nominal_.Set(model);

  info.train_rmse = QRmse(PredictArmAll(predictor, train, l), train.y, n, 0);
  const Eigen::MatrixXd val_pred = PredictArmAll(predictor, validation, l);
  info.validation_rmse = QRmse(val_pred, validation.y, n, 0);
  info.validation_qd_rmse = QRmse(val_pred, validation.y, n, n);
  if (l.horizon == 1 && options.rollout_seconds > 0)
    info.validation_rollout_rmse = ArmRolloutRmse(predictor, split, l, options.rollout_seconds);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  predictor.info_ = info;
  predictor.path_.clear();
  if (summary) {
    summary->samples = info.samples;
    summary->train_samples = train.rows();
    summary->train_rmse = info.train_rmse;
    summary->validation_rmse = info.validation_rmse;
    summary->validation_qd_rmse = info.validation_qd_rmse;
    summary->validation_rollout_rmse = info.validation_rollout_rmse;
    summary->seconds = seconds;
    summary->mlp_report = mlp_report;
  }
  return predictor;
}

}  // namespace twinsim

// The predictor file of an omni robot's predictor: OmniPredictor::Save and Load
// (docs/learning.md, "Predictor files"; the shared parts in predictor_file.h).
#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/engine_names.h"
#include "io/yaml_reader.h"
#include "learning/omni_predictor.h"
#include "learning/predictor_file.h"
#include "robots/omni/omni_effects.h"

namespace twinsim {

namespace {

// What a predictor knows of its own uncertainty: a linear one's weights' directions, a
// network's further members (the network under mlp: is member 0).
void EmitUncertainty(YAML::Emitter& out, const RidgeWeightUncertainty& u, const std::vector<Mlp>& ensemble) {
  if (!u.directions.empty()) {
    out << YAML::Key << "weight_uncertainty" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "blocks" << YAML::Value << u.blocks;
    out << YAML::Key << "share" << YAML::Value << u.share;
    out << YAML::Key << "count" << YAML::Value << static_cast<int>(u.directions.size());
    // Direction l is row l: its outputs' rows one after another (3 x inputs numbers).
    Eigen::MatrixXd rows(static_cast<long>(u.directions.size()), u.directions.front().size());
    for (std::size_t l = 0; l < u.directions.size(); ++l) {
      const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> d = u.directions[l];
      rows.row(static_cast<long>(l)) = Eigen::Map<const Eigen::RowVectorXd>(d.data(), d.size());
    }
    EmitMatrix(out, "directions", rows);
    out << YAML::EndMap;
  }
  if (!ensemble.empty()) {  // members 1..; the network below is member 0
    out << YAML::Key << "ensemble" << YAML::Value << YAML::BeginSeq;
    for (const Mlp& member : ensemble) {
      out << YAML::BeginMap;
      EmitMlp(out, member);
      out << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
}

}  // namespace

void OmniPredictor::Save(const std::string& path) const {
  YAML::Emitter out;
  BeginPredictorFile(out, residual() ? kResidualPredictorFormatVersion : kPredictorFormatVersion);
  out << YAML::Key << "kind" << YAML::Value << info_.kind;
  out << YAML::Key << "model" << YAML::Value << info_.model_name;
  out << YAML::Key << "frame_rate" << YAML::Value << info_.frame_rate;
  out << YAML::Key << "layout" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "history" << YAML::Value << info_.layout.history;
  out << YAML::Key << "horizon" << YAML::Value << info_.layout.horizon;
  out << YAML::Key << "command_lag" << YAML::Value << info_.layout.command_lag;
  out << YAML::Key << "inputs" << YAML::Value << info_.layout.num_inputs();
  out << YAML::Key << "outputs" << YAML::Value << FeatureLayout::kNumOutputs;
  if (residual()) {
    out << YAML::Key << "residual" << YAML::Value << true;
    out << YAML::Key << "nominal_errors" << YAML::Value << info_.layout.nominal_errors;
  }
  out << YAML::EndMap;
  if (residual()) {
    out << YAML::Key << "nominal" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "engine" << YAML::Value << info_.nominal_engine;
    out << YAML::Key << "substeps" << YAML::Value << info_.nominal_substeps;
    out << YAML::Key << "model_fingerprint" << YAML::Value << info_.nominal_fingerprint;
    if (info_.nominal_state != OmniReplayState::kTracker)
      out << YAML::Key << "state" << YAML::Value << OmniReplayStateName(info_.nominal_state);
    out << YAML::EndMap;
  }
  EmitTrainedOn(out, info_.logs, info_.samples,
                {{"train_rmse", info_.train_rmse},
                 {"validation_rmse", info_.validation_rmse},
                 {"validation_rollout_rmse", info_.validation_rollout_rmse}});
  if (info_.max_step > 0 || info_.max_turn > 0) {
    out << YAML::Key << "bounds" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "max_step" << YAML::Value << info_.max_step;
    out << YAML::Key << "max_turn" << YAML::Value << info_.max_turn;
    if (!info_.input_low.empty()) {
      out << YAML::Key << "input_low" << YAML::Value << YAML::Flow << info_.input_low;
      out << YAML::Key << "input_high" << YAML::Value << YAML::Flow << info_.input_high;
    }
    out << YAML::EndMap;
  }
  if (info_.has_driving_noise) {
    const OmniDrivingNoise& n = info_.driving_noise;
    out << YAML::Key << "driving_noise" << YAML::Value << YAML::Flow << YAML::BeginMap;
    for (int a = 0; a < 3; ++a) out << YAML::Key << kOmniAxisNames[a] << YAML::Value << n.sd[static_cast<std::size_t>(a)];
    out << YAML::Key << "correlation_time" << YAML::Value << n.correlation_time;
    if (n.per_speed != 0) out << YAML::Key << "per_speed" << YAML::Value << n.per_speed;
    if (n.per_acceleration != 0) out << YAML::Key << "per_acceleration" << YAML::Value << n.per_acceleration;
    if (n.per_turn_rate != 0) out << YAML::Key << "per_turn_rate" << YAML::Value << n.per_turn_rate;
    out << YAML::Key << "simulated" << YAML::Value << n.simulated;
    out << YAML::EndMap;
  }
  if (info_.has_driving_noise && !info_.interval_scale.empty()) {  // it scales the noise's intervals
    out << YAML::Key << "interval_scale" << YAML::Value << YAML::BeginSeq;
    for (const OmniObserverModel::IntervalScale& h : info_.interval_scale) {
      out << YAML::Flow << YAML::BeginMap << YAML::Key << "frames" << YAML::Value << h.frames;
      out << YAML::Key << "position" << YAML::Value << h.position;
      out << YAML::Key << "heading" << YAML::Value << h.heading << YAML::EndMap;
    }
    out << YAML::EndSeq;
  }
  EmitUncertainty(out, weight_uncertainty_, ensemble_);
  EmitPredictorModel(out, info_.kind, input_mean_, input_scale_, weights_, bias_, mlp_);
  WritePredictorFile(out, path);
}

namespace {

// The predictor's own driving noise, where the file has one (files from before issue 42
// and predictors of more than a frame ahead have none).
void ReadDrivingNoise(YamlMap* top, const std::string& path, ErrorList* errors, OmniPredictorInfo* info) {
  if (!top->Has("driving_noise")) return;
  YamlMap d(top->Child("driving_noise"), path, "driving_noise", errors);
  OmniDrivingNoise& n = info->driving_noise;
  for (int a = 0; a < 3; ++a) d.Require(kOmniAxisNames[a], &n.sd[static_cast<std::size_t>(a)], NonNegative(100));
  d.Require("correlation_time", &n.correlation_time, InRange(1e-3, 100));
  d.Get("per_speed", &n.per_speed, NonNegative(100));
  d.Get("per_acceleration", &n.per_acceleration, NonNegative(100));
  d.Get("per_turn_rate", &n.per_turn_rate, NonNegative(100));
  d.Require("simulated", &n.simulated);
  d.Finish();
  info->has_driving_noise = true;
  if (info->layout.horizon != 1) top->Error("driving_noise", "only a predictor of one frame ahead (layout.horizon 1) drives the learned backend");
}

// The safeguard on the driving noise's intervals, where the file has one (train's; files
// from before have none).
void ReadIntervalScale(YamlMap* top, OmniPredictorInfo* info) {
  if (!top->Has("interval_scale")) return;
  ReadIntervalScales(*top, "interval_scale", false, &info->interval_scale);
  if (!info->has_driving_noise) top->Error("interval_scale", "scales the driving noise's intervals: give driving_noise too");
}

// A linear one-frame predictor's weights' own uncertainty, where the file has it (train's;
// files from before, networks and weights fitted elsewhere have none).
RidgeWeightUncertainty ReadWeightUncertainty(YamlMap* top, const std::string& path, ErrorList* errors,
                                             const OmniPredictorInfo& info) {
  RidgeWeightUncertainty u;
  if (!top->Has("weight_uncertainty")) return u;
  if (info.kind != "linear" || info.layout.horizon != 1) {
    top->Child("weight_uncertainty");  // asked for: the error below is the one to report
    top->Error("weight_uncertainty", "only a linear predictor of one frame ahead carries its weights' uncertainty");
    return u;
  }
  YamlMap m(top->Child("weight_uncertainty"), path, "weight_uncertainty", errors);
  m.Require("blocks", &u.blocks, InRange(2, 100000000));
  m.Require("share", &u.share, InRange(1e-6, 1));
  int count = 0;
  m.Require("count", &count, InRange(1, 1000));
  const int in = info.layout.num_inputs(), out = FeatureLayout::kNumOutputs;
  const Eigen::MatrixXd rows = count > 0 ? ReadMatrix(m, "directions", count, out * in) : Eigen::MatrixXd();
  for (long l = 0; l < rows.rows(); ++l) {
    const Eigen::RowVectorXd r = rows.row(l);
    u.directions.push_back(Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        r.data(), out, in));
  }
  m.Finish();
  return u;
}

// A network's further members (`train --members`), where the file has them.
std::vector<Mlp> ReadEnsemble(YamlMap* top, const std::string& path, ErrorList* errors, const OmniPredictorInfo& info) {
  std::vector<Mlp> members;
  if (!top->Has("ensemble")) return members;
  const YAML::Node list = top->Child("ensemble");
  if (info.kind != "mlp" || info.layout.horizon != 1) {
    top->Error("ensemble", "only a network (kind mlp) of one frame ahead has an ensemble");
    return members;
  }
  if (!list.IsSequence() || list.size() < 1 || list.size() >= static_cast<std::size_t>(kMostEnsembleMembers)) {
    top->Error("ensemble", "must be a list of 1 to " + std::to_string(kMostEnsembleMembers - 1) + " networks");
    return members;
  }
  for (std::size_t i = 0; i < list.size(); ++i) {
    YamlMap m(list[i], path, "ensemble member " + std::to_string(i + 1), errors);
    members.push_back(ReadMlp(m, info.layout.num_inputs(), FeatureLayout::kNumOutputs, path, errors));
  }
  return members;
}

}  // namespace

OmniPredictor OmniPredictor::Load(const std::string& path) {
  const YAML::Node root = LoadYamlFile(path);
  CheckPredictorRobot(root, path, RobotKind::kOmni);
  ErrorList errors;
  YamlMap top(root, path, "", &errors);
  const int version = ReadPredictorVersion(top, "predictor", kPredictorFormatVersion, kResidualPredictorFormatVersion);
  OmniPredictorInfo info;
  top.Require("kind", &info.kind, std::vector<std::string>{"linear", "mlp"});
  top.Require("model", &info.model_name);
  top.Require("frame_rate", &info.frame_rate, Positive());
  if (top.Has("layout")) {
    YamlMap l(top.Child("layout"), path, "layout", &errors);
    l.Require("history", &info.layout.history, InRange(1, 100));
    l.Require("horizon", &info.layout.horizon, InRange(1, 100));
    l.Require("command_lag", &info.layout.command_lag, InRange(0, 100));
    if (version >= 3) {
      l.Get("residual", &info.layout.residual);
      if (info.layout.residual) l.Require("nominal_errors", &info.layout.nominal_errors, InRange(0, 100));
    }
    int inputs = 0, outputs = 0;
    if (l.Require("inputs", &inputs) && inputs != info.layout.num_inputs())
      l.Error("inputs", "does not match history and horizon (expected " + std::to_string(info.layout.num_inputs()) + ")");
    if (l.Require("outputs", &outputs) && outputs != FeatureLayout::kNumOutputs)
      l.Error("outputs", "expected 3");
    l.Finish();
  } else {
    top.Missing("layout");
  }
  if (info.layout.residual) {
    if (top.Has("nominal")) {
      YamlMap n(top.Child("nominal"), path, "nominal", &errors);
      n.Require("engine", &info.nominal_engine, KnownEngines());
      n.Require("substeps", &info.nominal_substeps, InRange(1, 1000));
      n.Require("model_fingerprint", &info.nominal_fingerprint);
      std::string state = OmniReplayStateName(OmniReplayState::kTracker);
      if (n.Get("state", &state, {kOmniReplayStateWords[0], kOmniReplayStateWords[1]}))
        ParseOmniReplayState(state, &info.nominal_state, nullptr);
      n.Finish();
    } else {
      top.Missing("nominal");
    }
  }
  ReadTrainedOn(top, &info.logs, &info.samples,
                {{"train_rmse", &info.train_rmse},
                 {"validation_rmse", &info.validation_rmse},
                 {"validation_rollout_rmse", &info.validation_rollout_rmse}});
  if (top.Has("bounds")) {  // optional: files from before issue 40 have none
    YamlMap b(top.Child("bounds"), path, "bounds", &errors);
    b.Require("max_step", &info.max_step, Positive());
    b.Require("max_turn", &info.max_turn, NonNegative());
    const int n = info.layout.num_inputs();
    if (b.Has("input_low") || b.Has("input_high")) {  // optional: files from before have none
      b.Get("input_low", &info.input_low, n);
      b.Get("input_high", &info.input_high, n);
      if (info.input_low.size() != info.input_high.size()) b.Missing(info.input_low.empty() ? "input_low" : "input_high");
    }
    b.Finish();
  }
  ReadDrivingNoise(&top, path, &errors, &info);
  ReadIntervalScale(&top, &info);
  RidgeWeightUncertainty uncertainty = ReadWeightUncertainty(&top, path, &errors, info);
  errors.ThrowIfAny();
  std::vector<Mlp> ensemble = ReadEnsemble(&top, path, &errors, info);
  errors.ThrowIfAny();

  const int in = info.layout.num_inputs();
  LinearPredictorParameters linear;
  Mlp mlp;
  ReadPredictorModel(top, info.kind, in, FeatureLayout::kNumOutputs, path, &errors, &linear, &mlp);
  OmniPredictor p = info.kind == "linear"
                        ? MakeLinearPredictor(info, linear.input_mean, linear.input_scale, linear.weights,
                                              Eigen::Vector3d(linear.bias))
                        : MakeMlpPredictor(info, std::move(mlp));
  p.weight_uncertainty_ = std::move(uncertainty);
  p.SetEnsemble(std::move(ensemble));
  p.path_ = path;
  return p;
}

}  // namespace twinsim

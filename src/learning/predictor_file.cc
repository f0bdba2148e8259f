#include "learning/predictor_file.h"

#include <cmath>
#include <cstdint>

#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <algorithm>
#include <stdexcept>
#include <vector>

#include "core/error.h"
#include "io/atomic_file.h"

namespace twinsim {

std::string PredictorFileRobot(const YAML::Node& root) {
  if (root.IsMap() && root["robot"] && root["robot"].IsScalar()) return root["robot"].Scalar();
  return "omni";
}

void CheckPredictorRobot(const YAML::Node& root, const std::string& path, RobotKind expected) {
  const std::string robot = PredictorFileRobot(root);
  if (robot == RobotKindName(expected)) return;
  SourceLocation where{path};
  if (root.IsMap() && root["robot"]) where.line = root["robot"].Mark().line + 1;
  else if (root.IsMap() && root["twinsim_predictor"]) where.line = root["twinsim_predictor"].Mark().line + 1;
  const bool arm = expected == RobotKind::kArm;
  const std::string hint = arm
                               ? "train one for the arm with 'twinsim train --model ARM_MODEL --log ARM_LOG ...'"
                               : "train one for the omni robot with 'twinsim train --model OMNI_MODEL --log OMNI_LOG ...'";
  const std::string what = robot == "arm" ? "an arm" : robot == "omni" ? "an omni robot" : "a robot of kind '" + robot + "'";
  throw InputError(where, "this is a predictor for " + what +
                              ", not for " + (arm ? "an arm" : "an omni robot") + "; " + hint);
}

int ReadPredictorVersion(YamlMap& top, const std::string& what, int oldest, int newest) {
  top.Child("robot");
  int version = 0;
  if (!top.Require("twinsim_predictor", &version)) top.errors()->ThrowIfAny();
  if (version < oldest || version > newest) {
    const std::string reads = oldest == newest
                                  ? "version " + std::to_string(newest)
                                  : "versions " + std::to_string(oldest) + " to " + std::to_string(newest);
    top.Error("twinsim_predictor", what + " format version " + std::to_string(version) +
                                       " is not supported (this build reads " + reads + ")");
    top.errors()->ThrowIfAny();
  }
  return version;
}

void ReadTrainedOn(YamlMap& top, std::vector<std::string>* logs, int* samples,
                   std::initializer_list<std::pair<const char*, double*>> fields) {
  if (!top.Has("trained_on")) return;
  YamlMap t(top.Child("trained_on"), top.path(), "trained_on", top.errors());
  const YAML::Node list = t.Child("logs");
  if (list.IsSequence())
    for (const auto& log : list) logs->push_back(log.Scalar());
  t.Get("samples", samples);
  for (const auto& [key, value] : fields) t.Get(key, value);
  t.Finish();
}

void BeginPredictorFile(YAML::Emitter& out, int version) {
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  out << YAML::Key << "twinsim_predictor" << YAML::Value << version;
}

void EmitTrainedOn(YAML::Emitter& out, const std::vector<std::string>& logs, int samples,
                   std::initializer_list<std::pair<const char*, double>> fields) {
  out << YAML::Key << "trained_on" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "logs" << YAML::Value << YAML::BeginSeq;
  for (const auto& log : logs) out << log;
  out << YAML::EndSeq;
  out << YAML::Key << "samples" << YAML::Value << samples;
  for (const auto& [key, value] : fields) out << YAML::Key << key << YAML::Value << value;
  out << YAML::EndMap;
}

void WritePredictorFile(YAML::Emitter& out, const std::string& path) {
  out << YAML::EndMap;
  WriteFileAtomically(path, std::string(out.c_str()) + "\n");
}

Eigen::VectorXd ReadVector(YamlMap& m, const std::string& key, int size) {
  std::vector<double> v;
  if (!m.Require(key, &v, size)) return Eigen::VectorXd::Zero(std::max(size, 0));
  return Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<long>(v.size()));
}

Eigen::MatrixXd ReadMatrix(YamlMap& m, const std::string& key, int rows, int cols) {
  // More numbers than a file of a predictor holds (a network's layer sizes multiply): a
  // corrupt file, refused before the product overflows an int or asks for gigabytes.
  const std::int64_t size = static_cast<std::int64_t>(rows) * cols;
  if (rows < 0 || cols < 0 || size > kMostMatrixNumbers) {
    m.Has(key);  // known: said once, as too large, not again as unknown
    m.Error(key, "a matrix of " + std::to_string(rows) + " x " + std::to_string(cols) + " is more than " +
                     std::to_string(kMostMatrixNumbers) + " numbers");
    return Eigen::MatrixXd();
  }
  std::vector<double> v;
  if (!m.Require(key, &v, static_cast<int>(size))) return Eigen::MatrixXd::Zero(rows, cols);
  // Stored row by row.
  return Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(v.data(), rows, cols);
}

void EmitVector(YAML::Emitter& out, const std::string& key, const double* data, long size) {
  // A fit that produced NaN or infinity has failed; a file holding them would be refused
  // by every reader, so none is written.
  for (long i = 0; i < size; ++i) {
    if (!std::isfinite(data[i])) {
      throw CheckFailed("the fit produced a non-finite value in '" + key +
                        "' (the data are too poor or ill-conditioned for it); no predictor was written");
    }
  }
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (long i = 0; i < size; ++i) out << data[i];
  out << YAML::EndSeq;
}

void EmitMatrix(YAML::Emitter& out, const std::string& key, const Eigen::MatrixXd& m) {
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows = m;
  EmitVector(out, key, rows.data(), rows.size());
}

void EmitMlp(YAML::Emitter& out, const Mlp& net) {
  const Mlp::Parameters& p = net.parameters();
  out << YAML::Key << "layers" << YAML::Value << YAML::Flow << p.layer_sizes;
  EmitVector(out, "input_mean", p.input_mean.data(), p.input_mean.size());
  EmitVector(out, "input_scale", p.input_scale.data(), p.input_scale.size());
  EmitVector(out, "output_mean", p.output_mean.data(), p.output_mean.size());
  EmitVector(out, "output_scale", p.output_scale.data(), p.output_scale.size());
  for (std::size_t l = 0; l < p.weights.size(); ++l) {
    EmitMatrix(out, "weights" + std::to_string(l), p.weights[l]);
    EmitVector(out, "biases" + std::to_string(l), p.biases[l].data(), p.biases[l].size());
  }
}

Mlp ReadMlp(YamlMap& m, int inputs, int outputs, const std::string& path, ErrorList* errors) {
  Mlp::Parameters params;
  std::vector<double> layers;
  if (m.Require("layers", &layers)) {
    for (double s : layers) params.layer_sizes.push_back(static_cast<int>(s));
    if (params.layer_sizes.size() < 2 || params.layer_sizes.front() != inputs || params.layer_sizes.back() != outputs)
      m.Error("layers", "must run from " + std::to_string(inputs) + " inputs to " + std::to_string(outputs) +
                            " outputs");
    for (int s : params.layer_sizes)
      if (s < 1 || s > 100000) m.Error("layers", "layer sizes must be 1 to 100000");
  }
  errors->ThrowIfAny();
  const auto& sizes = params.layer_sizes;
  params.input_mean = ReadVector(m, "input_mean", inputs);
  params.input_scale = ReadVector(m, "input_scale", inputs);
  params.output_mean = ReadVector(m, "output_mean", outputs);
  params.output_scale = ReadVector(m, "output_scale", outputs);
  for (std::size_t l = 0; l + 1 < sizes.size(); ++l) {
    params.weights.push_back(ReadMatrix(m, "weights" + std::to_string(l), sizes[l + 1], sizes[l]));
    params.biases.push_back(ReadVector(m, "biases" + std::to_string(l), sizes[l + 1]));
  }
  m.Finish();
  errors->ThrowIfAny();
  try {
    return Mlp::FromParameters(std::move(params));
  } catch (const InputError& e) {  // add the file to the message
    throw InputError(SourceLocation{path}, std::string("corrupt neural network: ") + e.what());
  }
}

void EmitPredictorModel(YAML::Emitter& out, const std::string& kind, const Eigen::VectorXd& input_mean,
                        const Eigen::VectorXd& input_scale, const Eigen::MatrixXd& weights, const Eigen::VectorXd& bias,
                        const Mlp& mlp) {
  if (kind == "linear") {
    out << YAML::Key << "linear" << YAML::Value << YAML::BeginMap;
    EmitVector(out, "input_mean", input_mean.data(), input_mean.size());
    EmitVector(out, "input_scale", input_scale.data(), input_scale.size());
    EmitMatrix(out, "weights", weights);
    EmitVector(out, "bias", bias.data(), bias.size());
    out << YAML::EndMap;
  } else {
    out << YAML::Key << "mlp" << YAML::Value << YAML::BeginMap;
    EmitMlp(out, mlp);
    out << YAML::EndMap;
  }
}

void ReadPredictorModel(YamlMap& top, const std::string& kind, int inputs, int outputs, const std::string& path,
                        ErrorList* errors, LinearPredictorParameters* linear, Mlp* mlp) {
  if (kind == "linear") {
    top.Child("mlp");
    YamlMap m(top.Child("linear"), path, "linear", errors);
    linear->input_mean = ReadVector(m, "input_mean", inputs);
    linear->input_scale = ReadVector(m, "input_scale", inputs);
    linear->weights = ReadMatrix(m, "weights", outputs, inputs);
    linear->bias = ReadVector(m, "bias", outputs);
    m.Finish();
    if (errors->empty() && (linear->input_scale.array() <= 0).any()) m.Error("input_scale", "must be positive");
    top.Finish();
    errors->ThrowIfAny();
  } else {
    top.Child("linear");
    YamlMap m(top.Child("mlp"), path, "mlp", errors);
    top.Finish();
    *mlp = ReadMlp(m, inputs, outputs, path, errors);
  }
}

Eigen::MatrixXd FitRidge(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, double ridge, Eigen::VectorXd* scale) {
  Eigen::VectorXd s = x.array().square().colwise().mean().sqrt().transpose();
  for (long i = 0; i < s.size(); ++i)
    if (s[i] < 1e-12) s[i] = 1;
  const Eigen::MatrixXd z = x.array().rowwise() / s.transpose().array();
  Eigen::MatrixXd gram = z.transpose() * z;
  gram.diagonal().array() += ridge * static_cast<double>(z.rows());
  if (scale) *scale = s;
  return gram.ldlt().solve(z.transpose() * y);
}

RidgeWeightUncertainty RidgeWeightDirections(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                                             const Eigen::VectorXd& scale, const Eigen::MatrixXd& weights,
                                             const std::vector<double>& ridges, int block_rows, double share,
                                             int max_directions) {
  RidgeWeightUncertainty out;
  const long n = x.rows(), in = x.cols(), outputs = y.cols();
  if (block_rows < 1) throw std::invalid_argument("RidgeWeightDirections: block_rows must be positive");
  const long blocks = (n + block_rows - 1) / block_rows;
  if (blocks < 2) return out;  // one block says nothing of its own scatter
  const Eigen::MatrixXd z = x.array().rowwise() / scale.transpose().array();
  const Eigen::MatrixXd r = y - z * weights;
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(outputs * in, blocks);  // column b: u_b
  const Eigen::MatrixXd gram = z.transpose() * z;
  for (long j = 0; j < outputs; ++j) {
    const double ridge = ridges[static_cast<std::size_t>(j)];
    if (std::isinf(ridge)) continue;  // fixed at zero
    Eigen::MatrixXd scores(in, blocks);
    for (long b = 0; b < blocks; ++b) {
      const long from = b * block_rows, rows = std::min<long>(block_rows, n - from);
      scores.col(b) = z.middleRows(from, rows).transpose() * r.col(j).segment(from, rows);
    }
    Eigen::MatrixXd g = gram;
    g.diagonal().array() += ridge * static_cast<double>(n);
    u.middleRows(j * in, in) = g.ldlt().solve(scores);
  }
  const Eigen::MatrixXd cov = u * u.transpose() * (static_cast<double>(blocks) / static_cast<double>(blocks - 1));
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
  const double trace = eig.eigenvalues().cwiseMax(0.0).sum();
  out.blocks = static_cast<int>(blocks);
  if (!(trace > 0)) return out;
  double held = 0;
  for (long l = eig.eigenvalues().size() - 1; l >= 0; --l) {  // largest first
    if (held >= share * trace || static_cast<int>(out.directions.size()) >= max_directions) break;
    const double value = std::max(0.0, eig.eigenvalues()[l]);
    if (value <= 0) break;
    Eigen::VectorXd v = eig.eigenvectors().col(l) * std::sqrt(value);
    // A sign of its own (the solver's is arbitrary): the largest entry positive.
    Eigen::Index top = 0;
    v.cwiseAbs().maxCoeff(&top);
    if (v[top] < 0) v = -v;
    Eigen::MatrixXd d(outputs, in);
    for (long j = 0; j < outputs; ++j) d.row(j) = v.segment(j * in, in).transpose();
    out.directions.push_back(std::move(d));
    held += value;
  }
  out.share = std::min(1.0, held / trace);  // summed in another order than trace: never past 1
  return out;
}

}  // namespace twinsim

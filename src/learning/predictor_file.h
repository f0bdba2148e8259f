// What the learned predictors of every robot share: the pieces of the versioned
// predictor file (YAML) and the closed-form ridge regression.
//
// A predictor file starts with `twinsim_predictor: VERSION`; an arm predictor then says
// `robot: arm` (omni files of format 2 carry no `robot` key and are omni). Each kind of
// predictor reads its own file (OmniPredictor::Load, ArmPredictor::Load) and uses
// CheckPredictorRobot() first, so that a file of the other robot is refused with a
// message naming the file and what it is, not a list of missing keys. Vectors and
// matrices are written as flow sequences of doubles with 17 significant digits
// (matrices row by row), so that a file read back gives the same doubles.
//
//   Eigen::MatrixXd w = FitRidge(x, y, 1e-3, &scale);   // y ~ ((x / scale) w)
//   EmitMatrix(out, "weights", w.transpose());
//   Eigen::MatrixXd back = ReadMatrix(map, "weights", rows, cols);
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include "core/robot_kind.h"
#include "io/yaml_reader.h"
#include "learning/mlp.h"

namespace YAML {
class Emitter;
class Node;
}  // namespace YAML

namespace twinsim {

// The robot a predictor file's root says it is for: its `robot` value, or "omni" when
// absent (the omni format predates the key).
std::string PredictorFileRobot(const YAML::Node& root);

// Throws InputError "path:line: this is a predictor for an omni robot, not for an arm;
// train one ..." when the file's robot is not `expected`.
void CheckPredictorRobot(const YAML::Node& root, const std::string& path, RobotKind expected);

// Reads the root's `twinsim_predictor` version (and marks `robot`, which
// CheckPredictorRobot() checked, as known). Throws InputError "WHAT format version V is
// not supported (this build reads version NEWEST)" (or "versions OLDEST to NEWEST")
// outside oldest..newest, and for a missing version (with the problems collected so far).
int ReadPredictorVersion(YamlMap& top, const std::string& what, int oldest, int newest);

// Reads the optional `trained_on` block: the training logs, the sample count and the
// numbers `fields` names (each into its double; unknown keys are errors).
void ReadTrainedOn(YamlMap& top, std::vector<std::string>* logs, int* samples,
                   std::initializer_list<std::pair<const char*, double*>> fields);

// Starts a predictor file: the root map, numbers with 17 significant digits, and
// `twinsim_predictor: version` first.
void BeginPredictorFile(YAML::Emitter& out, int version);
// Writes the `trained_on` block: the logs, the sample count, then `fields` in order.
void EmitTrainedOn(YAML::Emitter& out, const std::vector<std::string>& logs, int samples,
                   std::initializer_list<std::pair<const char*, double>> fields);
// Ends the root map and writes the file atomically; throws InputError when it cannot.
void WritePredictorFile(YAML::Emitter& out, const std::string& path);

// Reads a flow sequence of exactly `size` numbers under `key` (zeros after an error,
// which goes into the map's error list).
Eigen::VectorXd ReadVector(YamlMap& m, const std::string& key, int size);
// The most numbers ReadMatrix reads into one matrix: a layer of the widest network train
// makes (4096 x 4096, MlpOptions::IsValid).
inline constexpr std::int64_t kMostMatrixNumbers = 4096 * 4096;
// Reads a rows x cols matrix stored row by row under `key` (an error for more than
// kMostMatrixNumbers numbers).
Eigen::MatrixXd ReadMatrix(YamlMap& m, const std::string& key, int rows, int cols);

// Writes `key: [numbers]` (flow sequence).
void EmitVector(YAML::Emitter& out, const std::string& key, const double* data, long size);
// Writes a matrix row by row as one flow sequence.
void EmitMatrix(YAML::Emitter& out, const std::string& key, const Eigen::MatrixXd& m);

// Writes a network's parameters (layers, normalisation, weights and biases) as the
// entries of the current map.
void EmitMlp(YAML::Emitter& out, const Mlp& net);
// Reads what EmitMlp wrote, checking that the layers run from `inputs` to `outputs`.
// Throws InputError (every problem collected in `errors` first) for a corrupt file.
Mlp ReadMlp(YamlMap& m, int inputs, int outputs, const std::string& path, ErrorList* errors);

// A linear predictor's numbers: outputs = weights ((x - input_mean) / input_scale) + bias.
struct LinearPredictorParameters {
  Eigen::VectorXd input_mean, input_scale;  // in
  Eigen::MatrixXd weights;                  // out x in
  Eigen::VectorXd bias;                     // out
};

// Writes the model block of a predictor file of `kind`: `linear:` with the ridge fit's
// numbers, or `mlp:` with the network (what ReadPredictorModel reads back exactly).
void EmitPredictorModel(YAML::Emitter& out, const std::string& kind, const Eigen::VectorXd& input_mean,
                        const Eigen::VectorXd& input_scale, const Eigen::MatrixXd& weights, const Eigen::VectorXd& bias,
                        const Mlp& mlp);

// Reads the model block of a predictor file of `kind` ("linear" into *linear, "mlp" into
// *mlp) for `inputs` -> `outputs`, refusing the other kind's block, and finishes `top`
// (unknown keys are errors). Throws InputError listing every problem collected in
// `errors` (a wrong size, a non-positive input scale, a corrupt network).
void ReadPredictorModel(YamlMap& top, const std::string& kind, int inputs, int outputs, const std::string& path,
                        ErrorList* errors, LinearPredictorParameters* linear, Mlp* mlp);

// Ridge regression through the origin on columns scaled to unit RMS: returns W
// (in x out) minimising |Z W - y|^2 + ridge N |W|^2 with Z = x / scale (column-wise),
// and the scales (in; columns that are all zero get 1) in *scale. x: N x in, y: N x out.
// Predict with y = ((x / scale) W). Closed form (LDLT of the normal equations).
Eigen::MatrixXd FitRidge(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, double ridge, Eigen::VectorXd* scale);

// How uncertain ridge weights fitted on (x, y) are, from the data themselves: the
// residuals' scores summed over blocks of `block_rows` consecutive rows (the
// cluster-robust, "sandwich" covariance, so that residuals correlated within a block
// count once, not as independent rows), per output j with its ridge:
//   u_b = vec_j( G_j^-1 Z_b^T r_{b,j} ),  G_j = Z^T Z + ridge_j N I,
//   Cov(vec W) = B / (B - 1) sum_b u_b u_b^T   (B blocks).
// An infinite ridge is an output fixed at zero (a residual predictor without that
// correction): its weights are certain. Returned as the covariance's leading principal
// directions, each scaled by its standard deviation (outputs x inputs, on the scaled
// inputs, like the weights), until they hold `share` of its trace or `max_directions`:
// weights drawn as W + sum_l z_l D_l, z ~ N(0, I), have that covariance. `weights` is
// in x out (FitRidge's), `scale` FitRidge's.
struct RidgeWeightUncertainty {
  std::vector<Eigen::MatrixXd> directions;  // each out x in
  int blocks = 0;                           // B
  double share = 0;                         // of the covariance's trace the directions hold
};
RidgeWeightUncertainty RidgeWeightDirections(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                                             const Eigen::VectorXd& scale, const Eigen::MatrixXd& weights,
                                             const std::vector<double>& ridges, int block_rows, double share,
                                             int max_directions);

}  // namespace twinsim

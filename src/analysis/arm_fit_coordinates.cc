#include "analysis/arm_fit_coordinates.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "robots/arm/arm_dynamics.h"

namespace twinsim {

ArmFitCoordinates::ArmFitCoordinates(const ArmModel& start, const std::vector<ArmLog>& logs, bool offsets,
                                     bool stribeck, ArmPresliding presliding)
    : start_(start), n_(start.dof()), offsets_(offsets), stribeck_(stribeck), presliding_(presliding) {
  if (presliding != ArmPresliding::kNone && !stribeck)
    throw std::invalid_argument("arm fit coordinates: the bristles need the Stribeck coordinates");
  Eigen::ArrayXd tau2 = Eigen::ArrayXd::Zero(n_), qd2 = tau2;
  double samples = 0;
  for (const ArmLog& log : logs) {
    tau2 += log.tau.array().square().colwise().sum().transpose();
    qd2 += log.qd.array().square().colwise().sum().transpose();
    samples += log.rows();
  }
  samples = std::max(samples, 1.0);
  const Eigen::ArrayXd tau_rms = (tau2 / samples).sqrt(), qd_rms = (qd2 / samples).sqrt().max(1e-6);
  viscous_unit_.resize(n_);
  coulomb_unit_.resize(n_);
  breakaway_unit_.resize(n_);
  breakaway_limit_.resize(n_);
  stribeck_velocity_unit_.resize(n_);
  offset_unit_ = 0.1 * tau_rms.max(1e-9).matrix();
  for (int j = 0; j < n_; ++j) {
    viscous_unit_[j] = std::max(start_.joints[j].viscous, 1e-3 * tau_rms[j] / qd_rms[j]);
    coulomb_unit_[j] = std::max(start_.joints[j].coulomb, 1e-3 * tau_rms[j]);
    const JointEffects& e = start_.effects.joint(j);
    breakaway_unit_[j] = e.stribeck() ? e.stribeck_static - e.stribeck_coulomb : coulomb_unit_[j];
    breakaway_limit_[j] = std::max(kMaxBreakawayExcess * coulomb_unit_[j], 0.1 * tau_rms[j]);
    stribeck_velocity_unit_[j] = e.stribeck() ? e.stribeck_velocity : 0.1 * qd_rms[j];
  }
  if (presliding_ == ArmPresliding::kNone) return;
  bristle_unit_.resize(n_);
  Eigen::VectorXd q0 = Eigen::VectorXd::Zero(n_);
  if (!logs.empty() && logs.front().rows() > 0) q0 = logs.front().q.row(0).transpose();
  joint_inertia_ = MassMatrix(start_, q0).diagonal();
  for (int j = 0; j < n_; ++j) {
    const JointEffects& e = start_.effects.joint(j);
    bristle_unit_[j] = e.presliding() ? e.bristle_stiffness : coulomb_unit_[j] / (1e-3 * qd_rms[j]);
  }
}

ArmFitCoordinates::Kind ArmFitCoordinates::KindOf(int k) const {
  const int block = k / n_;
  if (block < 3) return static_cast<Kind>(block);
  if (offsets_ && block == 3) return Kind::kOffset;
  const int stribeck = block - (offsets_ ? 4 : 3);
  return stribeck == 0 ? Kind::kBreakaway : stribeck == 1 ? Kind::kStribeckVelocity : Kind::kBristleStiffness;
}

namespace {

// Each kind's words, heading and key, in the order of ArmFitCoordinates::Kind.
struct KindText {
  const char *words, *heading, *key;
};
constexpr KindText kKindTexts[] = {
    {"scale", "scale k", "scale"},
    {"viscous", "viscous", "viscous"},
    {"Coulomb", "Coulomb", "coulomb"},
    {"offset", "offset tau0", "offset"},
    {"break-away", "s - c", "breakaway"},
    {"Stribeck speed", "vs", "stribeck_velocity"},
    {"bristle stiffness", "sigma0", "bristle_stiffness"},
};

const KindText& TextOf(ArmFitCoordinates::Kind kind) { return kKindTexts[static_cast<int>(kind)]; }

}  // namespace

std::string ArmFitCoordinates::Heading(Kind kind) { return TextOf(kind).heading; }
std::string ArmFitCoordinates::Key(Kind kind) { return TextOf(kind).key; }

std::string ArmFitCoordinates::Name(int k) const {
  return std::string(TextOf(KindOf(k)).words) + " of joint " + std::to_string(k % n_ + 1);
}

std::vector<std::string> ArmFitCoordinates::Names(const std::vector<int>& ks) const {
  std::vector<std::string> names;
  for (int k : ks) names.push_back(Name(k));
  return names;
}

void ArmFitCoordinates::Bounds(int k, double* lower, double* upper) const {
  switch (KindOf(k)) {
    case Kind::kScale: *upper = std::log(100.0), *lower = -*upper; break;
    case Kind::kViscous:
    case Kind::kCoulomb: *lower = std::log(1e-6), *upper = std::log(1000.0); break;
    case Kind::kOffset: *lower = -20, *upper = 20; break;
    case Kind::kBreakaway: {
      // A start beyond the limits keeps its own excess.
      const int j = k % n_;
      *lower = std::min(std::log(1e-3 * coulomb_unit_[j] / breakaway_unit_[j]), 0.0);
      *upper = std::max(std::log(breakaway_limit_[j] / breakaway_unit_[j]), 0.0);
      break;
    }
    case Kind::kStribeckVelocity: *lower = std::log(1e-2), *upper = std::log(100.0); break;
    case Kind::kBristleStiffness: *lower = std::log(1e-3), *upper = std::log(1e4); break;
  }
}

ArmModel ArmFitCoordinates::Apply(const double* x) const {
  ArmModel m = start_;
  if ((offsets_ || stribeck_) && m.effects.joints.size() != static_cast<std::size_t>(n_)) m.effects.joints.resize(n_);
  for (int j = 0; j < n_; ++j) {
    ArmJoint& joint = m.joints[j];
    const double k = std::exp(x[j]);
    joint.child.mass *= k;
    joint.child.inertia *= k;
    joint.viscous = viscous_unit_[j] * std::exp(x[n_ + j]);
    joint.coulomb = coulomb_unit_[j] * std::exp(x[2 * n_ + j]);
    if (offsets_)
      m.effects.joints[j].torque_offset = start_.effects.joint(j).torque_offset + offset_unit_[j] * x[3 * n_ + j];
    if (stribeck_) {
      const int base = n_ * (offsets_ ? 4 : 3);
      JointEffects& e = m.effects.joints[j];
      e.stribeck_static = e.stribeck_coulomb + breakaway_unit_[j] * std::exp(x[base + j]);
      e.stribeck_velocity = stribeck_velocity_unit_[j] * std::exp(x[base + n_ + j]);
      if (presliding_ != ArmPresliding::kNone) {
        e.bristle_slip = presliding_ == ArmPresliding::kMaxwellSlip;
        e.bristle_stiffness = bristle_unit_[j] * std::exp(x[base + 2 * n_ + j]);
        e.bristle_damping = 2 * std::sqrt(e.bristle_stiffness * joint_inertia_[j]);
      }
    }
  }
  return m;
}

}  // namespace twinsim

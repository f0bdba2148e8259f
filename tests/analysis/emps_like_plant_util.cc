#include "analysis/emps_like_plant.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "analysis/arm_simulation_score.h"
#include "core/rng.h"
#include "diagnosis/mujoco_model.h"

namespace twinsim {
namespace testing {

std::string EmpsLikeNominalYaml() {
  return "robot: arm\n"
         "name: emps-like\n"
         "gravity: [0, 0, -9.81]\n"
         "sample_time: 0.001\n"
         "joints:\n"
         "  - name: axis\n"
         "    type: prismatic\n"
         "    axis: [1, 0, 0]\n"
         "    lower: -0.1\n"
         "    upper: 0.35\n"
         "    link: {name: cart, mass: 90, com: [0, 0, 0], inertia: [1, 1, 1, 0, 0, 0]}\n";
}

double EmpsLikeFrictionLoss(const EmpsLikeTruth& truth, double q) {
  constexpr double kPi = 3.14159265358979323846;
  return truth.coulomb * (1 + truth.coulomb_wave * std::cos(kPi * (q - 0.02) / 0.2));
}

double EmpsLikeCableForce(const EmpsLikeTruth& truth, double q) {
  constexpr double kPi = 3.14159265358979323846;
  return truth.cable * std::cos(2 * kPi * (q - 0.02) / 0.2);
}

double FreeRunFit(const ArmModel& model, const ArmLog& log) {
  ArmSimulationScoreOptions options;
  options.horizons = {0};
  return ScoreArmSimulation(model, log, options).horizons.front().fit[0];
}

#ifndef TWINSIM_HAVE_MUJOCO

std::string RecordEmpsLike(std::uint64_t, const EmpsLikeRecording&) {
  throw std::runtime_error("built without MuJoCo (apt-get install libmujoco-dev)");
}

#else

namespace {

constexpr double kDt = 0.001;          // s
constexpr double kPositionGain = 160.18;  // 1/s, Janot's kp
constexpr double kVelocityGain = 243.45;  // V/(m/s), Janot's kv
constexpr double kForcePerVolt = 35.15;   // N/V, Janot's gtau
constexpr double kVoltLimit = 10;         // V, the converter's range
constexpr double kVoltQuantum = 10.0 / 2048;  // V, a 12-bit converter over +-10 V
constexpr int kMaxwellSubsteps = 10;          // MuJoCo steps per sample of the Maxwell-slip cart
// s: the time constant of the slider's friction constraint. MuJoCo's dry friction is a
// soft constraint that pulls the speed to zero at 2 / time constant per second times the
// body's mass: its default (0.02 s) would let a 5 kg slider creep at 500 N s/m below
// the friction level instead of sticking.
constexpr double kSliderFrictionTime = 5 * kDt / kMaxwellSubsteps;

// The reference: moves between drawn positions with a trapezoidal speed profile (drawn
// top speed and acceleration), dwells between them.
std::vector<double> DrawReference(std::uint64_t seed, int rows) {
  Rng rng(0x656d7073 + 104729 * seed);
  std::vector<double> q(static_cast<std::size_t>(rows));
  double at = 0.12, t_in_move = 0, dwell = rng.Uniform(0.3, 1.0);
  double from = at, to = at, top = 0, acc = 1, duration = 0;
  bool moving = false;
  for (int k = 0; k < rows; ++k) {
    if (!moving) {
      dwell -= kDt;
      if (dwell <= 0) {
        from = at;
        do to = rng.Uniform(0.02, 0.22);
        while (std::abs(to - from) < 0.02);
        top = rng.Uniform(0.05, 0.35);
        acc = rng.Uniform(1.0, 3.0);
        const double distance = std::abs(to - from);
        top = std::min(top, std::sqrt(distance * acc));  // a triangle where the move is short
        duration = distance / top + top / acc;
        t_in_move = 0;
        moving = true;
      }
    }
    if (moving) {
      t_in_move += kDt;
      const double distance = std::abs(to - from), ramp = top / acc;
      double s;  // distance covered
      if (t_in_move < ramp) s = 0.5 * acc * t_in_move * t_in_move;
      else if (t_in_move < duration - ramp) s = 0.5 * acc * ramp * ramp + top * (t_in_move - ramp);
      else {
        const double left = std::max(0.0, duration - t_in_move);
        s = distance - 0.5 * acc * left * left;
      }
      at = from + (to > from ? 1 : -1) * std::min(s, distance);
      if (t_in_move >= duration) {
        at = to;
        moving = false;
        dwell = rng.Uniform(0.2, 1.0);
      }
    }
    q[static_cast<std::size_t>(k)] = at;
  }
  return q;
}

// Force pulses (N) added to the controller's output: 0.05 to 0.3 s long, +-20 to 60 N,
// one every 0.8 to 2 s.
std::vector<double> DrawPulses(std::uint64_t seed, int rows) {
  Rng rng(0x70756c73 + 7919 * seed);
  std::vector<double> f(static_cast<std::size_t>(rows), 0.0);
  double t = rng.Uniform(0.5, 1.5);
  while (t < rows * kDt) {
    const double length = rng.Uniform(0.05, 0.3), size = rng.Uniform(20, 60) * (rng.Uniform() < 0.5 ? -1 : 1);
    for (int k = static_cast<int>(t / kDt); k < std::min(rows, static_cast<int>((t + length) / kDt)); ++k)
      f[static_cast<std::size_t>(k)] = size;
    t += length + rng.Uniform(0.8, 2.0);
  }
  return f;
}

// The Maxwell-slip cart (EmpsLikeTruth::presliding_stiffness): a slider with the dry
// friction on a slide joint to the world, the cart on a spring joint to the slider.
// qpos[0] + qpos[1] is the cart's position; the viscous friction and the force are the
// caller's (world-relative: on both joints alike).
std::unique_ptr<MujocoModel> LoadMaxwellSlipCart(const EmpsLikeTruth& truth) {
  const double cart = truth.mass - truth.slider_mass;
  const double damping = 2 * truth.presliding_damping_ratio * std::sqrt(truth.presliding_stiffness * cart);
  std::ostringstream xml;
  xml.precision(17);
  xml << "<mujoco><option timestep=\"" << kDt / kMaxwellSubsteps
      << "\" integrator=\"RK4\"><flag contact=\"disable\"/></option>"
      << "<worldbody><body name=\"slider\"><joint name=\"slip\" type=\"slide\" axis=\"1 0 0\" frictionloss=\""
      << truth.coulomb << "\" solreffriction=\"" << kSliderFrictionTime
      << " 1\"/><inertial pos=\"0 0 0\" mass=\"" << truth.slider_mass
      << "\" diaginertia=\"1 1 1\"/><body name=\"cart\"><joint name=\"axis\" type=\"slide\" axis=\"1 0 0\" stiffness=\""
      << truth.presliding_stiffness << "\" damping=\"" << damping << "\"/><inertial pos=\"0 0 0\" mass=\"" << cart
      << "\" diaginertia=\"1 1 1\"/></body></body></worldbody></mujoco>\n";
  return LoadMujocoText(xml.str(), ".xml", "the Maxwell-slip cart");
}

std::unique_ptr<MujocoModel> LoadCart(const EmpsLikeTruth& truth) {
  if (truth.presliding_stiffness > 0) return LoadMaxwellSlipCart(truth);
  std::ostringstream xml;
  xml.precision(17);
  xml << "<mujoco><option timestep=\"" << kDt << "\" integrator=\"RK4\"><flag contact=\"disable\"/></option>"
      << "<worldbody><body name=\"cart\"><joint name=\"axis\" type=\"slide\" axis=\"1 0 0\" damping=\""
      << truth.viscous << "\" frictionloss=\"" << truth.coulomb << "\"/><inertial pos=\"0 0 0\" mass=\""
      << truth.mass << "\" diaginertia=\"1 1 1\"/></body></worldbody></mujoco>\n";
  return LoadMujocoText(xml.str(), ".xml", "the cart");
}

}  // namespace

std::string RecordEmpsLike(std::uint64_t seed, const EmpsLikeRecording& how) {
  const int rows = static_cast<int>(std::lround(how.seconds / kDt)) + 1;
  const std::vector<double> reference = DrawReference(seed, rows);
  const std::vector<double> pulses = how.pulses ? DrawPulses(seed, rows) : std::vector<double>(rows, 0.0);
  const std::unique_ptr<MujocoModel> cart = LoadCart(how.truth);
  MujocoModel& mj = *cart;
  Rng rng(0x6e6f6973 + 31 * seed);
  const bool maxwell = how.truth.presliding_stiffness > 0;
  mj.data->qpos[0] = reference[0];
  mj_forward(mj.model, mj.data);
  const auto position = [&mj, maxwell] { return mj.data->qpos[0] + (maxwell ? mj.data->qpos[1] : 0.0); };
  std::ostringstream csv;
  csv.precision(10);
  csv << "t,q1,tau1\n";
  // The velocity loop reads the encoder's differences through a first-order filter
  // (1 ms / 3 ms), as a drive's speed estimate does.
  double previous = reference[0], speed = 0;
  const double smoothing = kDt / 0.003;
  for (int k = 0; k < rows; ++k) {
    const double q = position();
    if (!std::isfinite(q)) throw std::runtime_error("MuJoCo's cart diverged");
    const double measured = how.quantum > 0 ? how.quantum * std::round(q / how.quantum) : q;
    speed += smoothing * ((measured - previous) / kDt - speed);
    previous = measured;
    double volts = kVelocityGain * (kPositionGain * (reference[static_cast<std::size_t>(k)] - measured) - speed);
    volts += pulses[static_cast<std::size_t>(k)] / kForcePerVolt;
    volts = std::clamp(volts, -kVoltLimit, kVoltLimit);
    volts = kVoltQuantum * std::round(volts / kVoltQuantum);
    const double force = kForcePerVolt * volts;
    csv << k * kDt << "," << measured << "," << force + rng.Gaussian(how.force_noise) << "\n";
    if (!maxwell) {
      mj.data->qfrc_applied[0] = force + how.truth.offset + EmpsLikeCableForce(how.truth, q);
      if (how.truth.coulomb_wave != 0) mj.model->dof_frictionloss[0] = EmpsLikeFrictionLoss(how.truth, q);
      mj_step(mj.model, mj.data);
      continue;
    }
    for (int s = 0; s < kMaxwellSubsteps; ++s) {
      // On the cart, whose position is the sum of both joints': the same force on each.
      const double speed = mj.data->qvel[0] + mj.data->qvel[1];
      mj.data->qfrc_applied[0] = mj.data->qfrc_applied[1] =
          force + how.truth.offset + EmpsLikeCableForce(how.truth, position()) - how.truth.viscous * speed;
      mj_step(mj.model, mj.data);
    }
  }
  return csv.str();
}

#endif

}  // namespace testing
}  // namespace twinsim

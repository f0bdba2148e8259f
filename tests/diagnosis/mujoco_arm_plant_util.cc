#include "diagnosis/mujoco_arm_plant.h"
#include "diagnosis/mujoco_model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

#include <unistd.h>

#include "core/math_constants.h"
#include "core/rng.h"

namespace twinsim {
namespace testing {

std::string ArmUrdf(const ArmModel& model) {
  std::ostringstream out;
  out.precision(17);
  auto origin = [&](const Eigen::Vector3d& xyz, const Eigen::Matrix3d& r) {
    const Eigen::Vector3d ypr = r.eulerAngles(2, 1, 0);  // URDF's rpy: R = Rz(y) Ry(p) Rx(r)
    out << "<origin xyz=\"" << xyz.x() << " " << xyz.y() << " " << xyz.z() << "\" rpy=\"" << ypr[2] << " "
        << ypr[1] << " " << ypr[0] << "\"/>";
  };
  out << "<?xml version=\"1.0\"?>\n<robot name=\"" << model.name << "\">\n<link name=\"base\"/>\n";
  std::string parent = "base";
  for (int i = 0; i < model.dof(); ++i) {
    const ArmJoint& j = model.joints[static_cast<std::size_t>(i)];
    const std::string link = "link" + std::to_string(i + 1);
    const Eigen::Matrix3d& in = j.child.inertia;
    out << "<link name=\"" << link << "\"><inertial>";
    origin(j.child.com, Eigen::Matrix3d::Identity());
    out << "<mass value=\"" << j.child.mass << "\"/><inertia ixx=\"" << in(0, 0) << "\" iyy=\"" << in(1, 1)
        << "\" izz=\"" << in(2, 2) << "\" ixy=\"" << in(0, 1) << "\" ixz=\"" << in(0, 2) << "\" iyz=\"" << in(1, 2)
        << "\"/></inertial></link>\n";
    out << "<joint name=\"" << j.name << "\" type=\"" << (j.type == JointType::kRevolute ? "revolute" : "prismatic")
        << "\"><parent link=\"" << parent << "\"/><child link=\"" << link << "\"/>";
    origin(j.origin.translation(), j.origin.linear());
    out << "<axis xyz=\"" << j.axis.x() << " " << j.axis.y() << " " << j.axis.z() << "\"/><limit lower=\"" << j.lower
        << "\" upper=\"" << j.upper << "\" effort=\"100\" velocity=\"10\"/></joint>\n";
    parent = link;
  }
  out << "</robot>\n";
  return out.str();
}

HiddenArmTorque HiddenOnJoint(int joint, std::function<double(double q, double qd)> torque) {
  return [joint, torque](double, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
    Eigen::VectorXd tau = Eigen::VectorXd::Zero(q.size());
    tau[joint] = torque(q[joint], qd[joint]);
    return tau;
  };
}

#ifndef TWINSIM_HAVE_MUJOCO

bool MujocoAvailable() { return false; }

ArmLog RecordMujocoArm(const ArmModel&, std::uint64_t, const ForeignArmRecording&) {
  throw std::runtime_error("built without MuJoCo (apt-get install libmujoco-dev)");
}

#else

bool MujocoAvailable() { return true; }

MujocoModel::~MujocoModel() {
  if (data) mj_deleteData(data);
  if (model) mj_deleteModel(model);
}

std::unique_ptr<MujocoModel> LoadMujocoText(const std::string& text, const std::string& extension,
                                            const std::string& what) {
  static std::atomic<int> count{0};
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("twinsim_mujoco_" + std::to_string(::getpid()) + "_" + std::to_string(count++) + extension))
                               .string();
  std::ofstream(path) << text;
  auto m = std::make_unique<MujocoModel>();
  char error[1000] = "";
  m->model = mj_loadXML(path.c_str(), nullptr, error, sizeof error);
  std::filesystem::remove(path);
  if (!m->model) throw std::runtime_error("MuJoCo cannot load " + what + ": " + error);
  m->data = mj_makeData(m->model);
  return m;
}

namespace {

constexpr int kHarmonics = 5;
constexpr double kFundamentalHz = 0.1;
constexpr double kRangeShare = 0.7;  // the most of a joint's range the excitation sweeps
constexpr double kMaxSpeed = 2.5;  // rad/s

// The excitation: per joint q0 + sum_l a_l sin(l w t) + b_l cos(l w t), as Swevers'
// finite Fourier series, scaled into the ranges and the speed.
struct Excitation {
  Eigen::VectorXd q0;
  Eigen::MatrixXd a, b;  // joints x harmonics

  void At(double t, Eigen::VectorXd* q, Eigen::VectorXd* qd, Eigen::VectorXd* qdd) const {
    const double w = 2 * kPi * kFundamentalHz;
    *q = q0;
    qd->setZero(q0.size());
    qdd->setZero(q0.size());
    for (int l = 1; l <= kHarmonics; ++l) {
      const double s = std::sin(l * w * t), c = std::cos(l * w * t), lw = l * w;
      *q += a.col(l - 1) * s + b.col(l - 1) * c;
      *qd += (a.col(l - 1) * c - b.col(l - 1) * s) * lw;
      *qdd -= (a.col(l - 1) * s + b.col(l - 1) * c) * lw * lw;
    }
  }
};

Excitation DrawExcitation(const ArmModel& model, Rng* rng) {
  const int n = model.dof();
  Excitation e;
  e.q0.resize(n);
  e.a.resize(n, kHarmonics);
  e.b.resize(n, kHarmonics);
  for (int j = 0; j < n; ++j) {
    const ArmJoint& joint = model.joints[static_cast<std::size_t>(j)];
    const double mid = 0.5 * (joint.lower + joint.upper), half = 0.5 * (joint.upper - joint.lower);
    e.q0[j] = mid + rng->Uniform(-0.2, 0.2) * half;
    for (int l = 0; l < kHarmonics; ++l) {
      e.a(j, l) = rng->Uniform(-1, 1) / (l + 1);
      e.b(j, l) = rng->Uniform(-1, 1) / (l + 1);
    }
    // Scale into the range around q0 and under the speed, over one period.
    double reach = 0, speed = 0;
    Excitation one = e;
    for (int k = 0; k < 1000; ++k) {
      Eigen::VectorXd q, qd, qdd;
      one.At(k / (1000 * kFundamentalHz), &q, &qd, &qdd);
      reach = std::max(reach, std::abs(q[j] - e.q0[j]));
      speed = std::max(speed, std::abs(qd[j]));
    }
    // How much of its range each joint sweeps is drawn too: a shoulder that stays near
    // horizontal holds its gravity torque near the peak for long stretches.
    const double share = rng->Uniform(0.1, kRangeShare);
    const double room = std::min(joint.upper - e.q0[j], e.q0[j] - joint.lower) - (1 - share) * half;
    const double scale = std::min(std::max(room, 0.1 * half) / reach, kMaxSpeed / speed);
    e.a.row(j) *= scale;
    e.b.row(j) *= scale;
  }
  return e;
}

std::unique_ptr<MujocoModel> LoadMujoco(const ArmModel& plant) {
  std::unique_ptr<MujocoModel> m = LoadMujocoText(ArmUrdf(plant), ".urdf", "the plant");
  if (m->model->nv != plant.dof()) throw std::runtime_error("MuJoCo's plant has another number of joints");
  m->model->opt.timestep = plant.sample_time;
  m->model->opt.integrator = mjINT_RK4;
  m->model->opt.disableflags |= mjDSBL_CONTACT;
  for (int i = 0; i < plant.dof(); ++i) m->model->dof_damping[i] = m->model->dof_frictionloss[i] = m->model->dof_armature[i] = 0;
  return m;
}

double Sign(double v) { return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0); }

// MuJoCo's inverse dynamics of the motion, plus the plant's joint friction (viscous and
// Coulomb, as the model file states them).
Eigen::VectorXd Needed(const ArmModel& plant, MujocoModel* mj, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                       const Eigen::VectorXd& qdd) {
  const int n = plant.dof();
  std::copy_n(q.data(), n, mj->data->qpos);
  std::copy_n(qd.data(), n, mj->data->qvel);
  std::copy_n(qdd.data(), n, mj->data->qacc);
  mj_inverse(mj->model, mj->data);
  Eigen::VectorXd tau = Eigen::Map<const Eigen::VectorXd>(mj->data->qfrc_inverse, n);
  for (int j = 0; j < n; ++j) {
    const ArmJoint& joint = plant.joints[static_cast<std::size_t>(j)];
    tau[j] += joint.viscous * qd[j] + joint.coulomb * Sign(qd[j]);
  }
  return tau;
}

double Quantise(double q, double quantum) { return quantum > 0 ? quantum * std::round(q / quantum) : q; }

}  // namespace

ArmLog RecordMujocoArm(const ArmModel& plant, std::uint64_t seed, const ForeignArmRecording& how) {
  const int n = plant.dof();
  const double dt = plant.sample_time;
  const int rows = static_cast<int>(std::lround(how.seconds / dt)) + 1;
  const double delay = plant.delay_samples * dt;
  Rng rng(0x6d756a6f + 7919 * seed);
  const Excitation excitation = DrawExcitation(plant, &rng);
  std::unique_ptr<MujocoModel> mj = LoadMujoco(plant);

  // Each joint's own time_delay (whole samples) beside the model's delay: what joint j
  // receives now was sent that many samples before.
  std::vector<int> joint_delay(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) joint_delay[static_cast<std::size_t>(j)] = static_cast<int>(std::lround(plant.effects.joint(j).time_delay / dt));

  // What the exact motion needs, sent `delay` (and joint j its own delay) early (the
  // closed loop's feedforward); open loop the hidden torque helps the motor, which sends
  // that much less.
  Eigen::MatrixXd feedforward(rows, n), open_loop(rows, n), q_exact(rows, n), qd_exact(rows, n);
  for (int k = 0; k < rows; ++k) {
    Eigen::VectorXd q, qd, qdd;
    excitation.At(k * dt, &q, &qd, &qdd);
    q_exact.row(k) = q.transpose();
    qd_exact.row(k) = qd.transpose();
    for (int j = 0; j < n; ++j) {
      const double ahead = delay + joint_delay[static_cast<std::size_t>(j)] * dt;
      excitation.At(k * dt + ahead, &q, &qd, &qdd);
      const Eigen::VectorXd needed = Needed(plant, mj.get(), q, qd, qdd);
      feedforward(k, j) = needed[j];
      open_loop(k, j) = needed[j] - (how.hidden ? how.hidden(k * dt + ahead, q, qd)[j] : 0.0);
    }
  }
  Eigen::VectorXd sigma(n);
  for (int j = 0; j < n; ++j) sigma[j] = how.noise_share * feedforward.col(j).cwiseAbs().mean();
  // Coloured: an AR(1) of the same spread, c_k = a c_(k-1) + sqrt(1 - a^2) w_k.
  const double a = how.noise_correlation > 0 ? std::exp(-dt / how.noise_correlation) : 0.0;
  Eigen::VectorXd coloured = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < n; ++j) coloured[j] = rng.Gaussian(sigma[j]);
  auto noise = [&](int j, double tau) {
    coloured[j] = a * coloured[j] + std::sqrt(1 - a * a) * rng.Gaussian(sigma[j]);
    return coloured[j] + rng.Gaussian(how.proportional_noise * std::abs(tau));
  };

  ArmLog log;
  log.dof = n;
  log.t.resize(rows);
  log.q.resize(rows, n);
  log.tau.resize(rows, n);
  if (!how.closed_loop) {
    for (int k = 0; k < rows; ++k) {
      log.t[k] = k * dt;
      for (int j = 0; j < n; ++j) {
        log.q(k, j) = Quantise(q_exact(k, j), how.quantum);
        log.tau(k, j) = open_loop(k, j) + noise(j, open_loop(k, j));
      }
    }
  } else {
    // PD at 5 Hz on each joint's own inertia at the start, velocity by differences of
    // the encoder; MuJoCo's own viscous damping and friction loss (a soft Coulomb).
    mjModel* m = mj->model;
    mjData* d = mj->data;
    for (int j = 0; j < n; ++j) {
      m->dof_damping[j] = plant.joints[static_cast<std::size_t>(j)].viscous;
      m->dof_frictionloss[j] = plant.joints[static_cast<std::size_t>(j)].coulomb;
    }
    mj_resetData(m, d);
    for (int j = 0; j < n; ++j) d->qpos[j] = q_exact(0, j), d->qvel[j] = qd_exact(0, j);
    mj_forward(m, d);
    std::vector<mjtNum> full(static_cast<std::size_t>(n * n));
    mj_fullM(m, full.data(), d->qM);
    const double w = 2 * kPi * 5;
    const int longest = plant.delay_samples + *std::max_element(joint_delay.begin(), joint_delay.end());
    std::deque<Eigen::VectorXd> sent(static_cast<std::size_t>(std::max(0, longest)), feedforward.row(0).transpose());
    Eigen::VectorXd previous(n);
    for (int k = 0; k < rows; ++k) {
      log.t[k] = k * dt;
      Eigen::VectorXd q(n), qd(n), measured(n);
      for (int j = 0; j < n; ++j) {
        q[j] = d->qpos[j], qd[j] = d->qvel[j];
        if (!std::isfinite(q[j])) throw std::runtime_error("MuJoCo's plant diverged");
        measured[j] = Quantise(q[j], how.quantum);
      }
      const Eigen::VectorXd speed = k == 0 ? qd_exact.row(0).transpose() : Eigen::VectorXd((measured - previous) / dt);
      previous = measured;
      Eigen::VectorXd command(n);
      for (int j = 0; j < n; ++j) {
        const double inertia = full[static_cast<std::size_t>(j * n + j)];
        command[j] = feedforward(k, j) + inertia * w * w * (q_exact(k, j) - measured[j]) +
                     2 * 0.7 * w * inertia * (qd_exact(k, j) - speed[j]);
      }
      log.q.row(k) = measured.transpose();
      log.tau.row(k) = command.transpose();
      sent.push_back(command);
      Eigen::VectorXd applied(n);  // joint j: what was sent its delay ago
      for (int j = 0; j < n; ++j) {
        const int age = plant.delay_samples + joint_delay[static_cast<std::size_t>(j)];
        applied[j] = sent[sent.size() - 1 - static_cast<std::size_t>(age)][j];
      }
      sent.pop_front();
      for (int j = 0; j < n; ++j) applied[j] += noise(j, applied[j]);
      if (how.hidden) applied += how.hidden(k * dt, q, qd);
      std::copy_n(applied.data(), n, d->qfrc_applied);
      mj_step(m, d);
    }
  }
  // Through the reader, as a user's file: qd and qdd derived from the quantised q.
  ArmLogOptions options;
  options.cutoff_hz = how.cutoff_hz;
  return ParseArmLog(FormatArmLog(log, false), "mujoco_" + std::to_string(seed) + ".csv", options);
}

#endif

}  // namespace testing
}  // namespace twinsim

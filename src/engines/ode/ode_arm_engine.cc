#include "engines/ode/ode_arm_engine.h"

#include <memory>
#include <ode/ode.h>

#include "engines/ode/ode_world.h"

#include <Eigen/Geometry>
#include <cmath>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/math_constants.h"
#include "robots/arm/arm_dynamics.h"

namespace twinsim {
namespace {

// Joint error reduction and constraint force mixing. The hinges and sliders drift apart
// by O(h^2) per step in maximal coordinates; ERP pulls that back each step, and ODE's
// double-precision default CFM keeps the joints practically rigid.
constexpr double kJointErp = 0.2;
constexpr double kJointCfm = 1e-10;

// Per body in a snapshot: position (3), quaternion (4), linear and angular velocity (3 + 3).
constexpr int kBodySnapshotSize = 13;

double WrapToPi(double a) { return std::remainder(a, 2 * kPi); }

class OdeArmEngine final : public ArmEngine {
 public:
  OdeArmEngine(const ArmModel& plant, double max_step);
  ~OdeArmEngine() override = default;  // ode_world_ destroys the world, bodies and joints
  OdeArmEngine(const OdeArmEngine&) = delete;
  OdeArmEngine& operator=(const OdeArmEngine&) = delete;

  std::string name() const override { return "ode"; }
  int dof() const override { return plant_.dof(); }
  void Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) override;
  void Step(const Eigen::VectorXd& tau, double dt) override;
  const Eigen::VectorXd& q() const override { return q_; }
  const Eigen::VectorXd& qd() const override { return qd_; }
  ArmEngineState Save() const override;
  void Restore(const ArmEngineState& state) override;

 private:
  bool revolute(int i) const { return plant_.joints[static_cast<std::size_t>(i)].type == JointType::kRevolute; }
  void ReadJoints();
  void CanonicalizeQuaternions();

  ArmModel plant_;
  double max_step_;  // s
  std::unique_ptr<OdeWorld> ode_world_;
  dWorldID world_ = nullptr;  // ode_world_'s
  std::vector<dBodyID> bodies_;   // per link
  std::vector<dJointID> joints_;  // per joint
  Eigen::VectorXd q_, qd_;        // q unwrapped
};

OdeArmEngine::OdeArmEngine(const ArmModel& plant, double max_step)
    : plant_(plant), max_step_(max_step), q_(Eigen::VectorXd::Zero(plant.dof())), qd_(q_) {
  ode_world_ = std::make_unique<OdeWorld>();
  world_ = ode_world_->id();
  const Eigen::Vector3d& g = plant_.gravity;
  dWorldSetGravity(world_, g.x(), g.y(), g.z());
  dWorldSetERP(world_, kJointErp);
  dWorldSetCFM(world_, kJointCfm);
  // An arm standing still must still feel the next torque.
  dWorldSetAutoDisableFlag(world_, 0);

  // Built at q = 0: ODE takes each hinge's and slider's zero from the bodies' relative
  // pose when its axis is set, so the joints then read the model's q.
  const std::vector<Eigen::Isometry3d> poses = ForwardKinematics(plant_, q_);
  for (int i = 0; i < dof(); ++i) {
    const ArmJoint& joint = plant_.joints[static_cast<std::size_t>(i)];
    const ArmLink& link = joint.child;
    const Eigen::Isometry3d& pose = poses[static_cast<std::size_t>(i)];
    dBodyID body = dBodyCreate(world_);
    dMass mass;
    const Eigen::Matrix3d& in = link.inertia;
    // The body's origin is the centre of mass (ODE requires it); its axes are the link's.
    dMassSetParameters(&mass, link.mass, 0, 0, 0, in(0, 0), in(1, 1), in(2, 2), in(0, 1), in(0, 2), in(1, 2));
    dBodySetMass(body, &mass);
    const Eigen::Vector3d c = pose * link.com;
    dBodySetPosition(body, c.x(), c.y(), c.z());
    const Eigen::Quaterniond r(pose.linear());
    const dQuaternion dq = {r.w(), r.x(), r.y(), r.z()};
    dBodySetQuaternion(body, dq);
    bodies_.push_back(body);

    // Body 1 is the link, body 2 its parent (none: the world): ODE's angle, rate and
    // torque are then the link's relative to the parent, about +axis.
    dBodyID parent = i > 0 ? bodies_[static_cast<std::size_t>(i - 1)] : nullptr;
    const Eigen::Vector3d axis = pose.linear() * joint.axis;
    const Eigen::Vector3d anchor = pose.translation();
    dJointID j;
    if (joint.type == JointType::kRevolute) {
      j = dJointCreateHinge(world_, nullptr);
      dJointAttach(j, body, parent);
      dJointSetHingeAnchor(j, anchor.x(), anchor.y(), anchor.z());
      dJointSetHingeAxis(j, axis.x(), axis.y(), axis.z());
    } else {
      j = dJointCreateSlider(world_, nullptr);
      dJointAttach(j, body, parent);
      dJointSetSliderAxis(j, axis.x(), axis.y(), axis.z());
    }
    joints_.push_back(j);
  }
  Reset(q_, qd_);
}

void OdeArmEngine::Reset(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  CheckArmState(name(), dof(), q, qd);
  // Link frames and their velocities in the world, base to tip.
  const std::vector<Eigen::Isometry3d> poses = ForwardKinematics(plant_, q);
  Eigen::Vector3d w = Eigen::Vector3d::Zero();       // rad/s, of the parent link
  Eigen::Vector3d v = Eigen::Vector3d::Zero();       // m/s, of the parent frame's origin
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // m, the parent frame's origin
  for (int i = 0; i < dof(); ++i) {
    const ArmJoint& joint = plant_.joints[static_cast<std::size_t>(i)];
    const Eigen::Isometry3d& pose = poses[static_cast<std::size_t>(i)];
    const Eigen::Vector3d p = pose.translation();
    const Eigen::Vector3d axis = pose.linear() * joint.axis;
    v += w.cross(p - origin);
    if (joint.type == JointType::kRevolute) {
      w += axis * qd[i];
    } else {
      v += axis * qd[i];
    }
    origin = p;
    const Eigen::Vector3d c = pose * joint.child.com;
    const Eigen::Vector3d vc = v + w.cross(c - p);
    dBodyID body = bodies_[static_cast<std::size_t>(i)];
    dBodySetPosition(body, c.x(), c.y(), c.z());
    const Eigen::Quaterniond r(pose.linear());
    const dQuaternion dq = {r.w(), r.x(), r.y(), r.z()};
    dBodySetQuaternion(body, dq);
    dBodySetLinearVel(body, vc.x(), vc.y(), vc.z());
    dBodySetAngularVel(body, w.x(), w.y(), w.z());
    dBodySetForce(body, 0, 0, 0);
    dBodySetTorque(body, 0, 0, 0);
  }
  CanonicalizeQuaternions();
  q_ = q;
  qd_ = qd;
}

void OdeArmEngine::Step(const Eigen::VectorXd& tau, double dt) {
  CheckArmStep(name(), dof(), tau, dt);
  EnsureOdeInitialized();
  const int n = ArmSubsteps(dt, max_step_);
  const double h = dt / n;
  for (int s = 0; s < n; ++s) {
    // ODE clears the force accumulators after every step: the held torques go in again.
    for (int i = 0; i < dof(); ++i) {
      if (revolute(i)) {
        dJointAddHingeTorque(joints_[static_cast<std::size_t>(i)], tau[i]);
      } else {
        dJointAddSliderForce(joints_[static_cast<std::size_t>(i)], tau[i]);
      }
    }
    dWorldStep(world_, h);
  }
  CanonicalizeQuaternions();
  ReadJoints();
}

void OdeArmEngine::ReadJoints() {
  for (int i = 0; i < dof(); ++i) {
    dJointID j = joints_[static_cast<std::size_t>(i)];
    if (revolute(i)) {
      // ODE's angle lives in (-pi, pi]; the arm's q may wind further.
      q_[i] += WrapToPi(dJointGetHingeAngle(j) - q_[i]);
      qd_[i] = dJointGetHingeAngleRate(j);
    } else {
      q_[i] = dJointGetSliderPosition(j);
      qd_[i] = dJointGetSliderPositionRate(j);
    }
  }
}

bool SameQuaternion(const dReal* a, const dReal* b) {
  return a[0] == b[0] && a[1] == b[1] && a[2] == b[2] && a[3] == b[3];
}

// Sets a body's quaternion to exactly `q` where ODE's re-normalisation allows: `q` is a
// fixed point of it, or one of a pair it alternates between (then the other one of the
// pair is passed in).
void SetQuaternionExactly(dBodyID body, const dReal* q) {
  dQuaternion x = {q[0], q[1], q[2], q[3]};
  for (int k = 0; k < 3; ++k) {
    dBodySetQuaternion(body, x);
    const dReal* got = dBodyGetQuaternion(body);
    if (SameQuaternion(got, q)) return;
    for (int i = 0; i < 4; ++i) x[i] = got[i];
  }
}

void OdeArmEngine::CanonicalizeQuaternions() {
  // dBodySetQuaternion re-normalises what it is given, which may move the last bit of a
  // quaternion the stepper had normalised. Re-normalising the live quaternions until
  // they stop changing leaves each at a fixed point of that map or on a pair it
  // alternates between (measured: about one body-step in six), which
  // SetQuaternionExactly() can both put back bit for bit.
  for (dBodyID body : bodies_) {
    for (int k = 0; k < 4; ++k) {
      const dReal* now = dBodyGetQuaternion(body);
      const dQuaternion before = {now[0], now[1], now[2], now[3]};
      dBodySetQuaternion(body, before);
      if (SameQuaternion(dBodyGetQuaternion(body), before)) break;
    }
  }
}

ArmEngineState OdeArmEngine::Save() const {
  ArmEngineState s{q_, qd_, {}};
  s.exact.reserve(bodies_.size() * kBodySnapshotSize);
  for (dBodyID body : bodies_) {
    const dReal* p = dBodyGetPosition(body);
    const dReal* r = dBodyGetQuaternion(body);
    const dReal* v = dBodyGetLinearVel(body);
    const dReal* w = dBodyGetAngularVel(body);
    s.exact.insert(s.exact.end(), {p[0], p[1], p[2], r[0], r[1], r[2], r[3], v[0], v[1], v[2], w[0], w[1], w[2]});
  }
  return s;
}

void OdeArmEngine::Restore(const ArmEngineState& state) {
  CheckArmState(name(), dof(), state.q, state.qd);
  if (state.exact.size() != bodies_.size() * kBodySnapshotSize) {
    throw std::invalid_argument("ode arm backend: state of another arm or backend");
  }
  const double* x = state.exact.data();
  for (dBodyID body : bodies_) {
    dBodySetPosition(body, x[0], x[1], x[2]);
    SetQuaternionExactly(body, x + 3);
    dBodySetLinearVel(body, x[7], x[8], x[9]);
    dBodySetAngularVel(body, x[10], x[11], x[12]);
    dBodySetForce(body, 0, 0, 0);
    dBodySetTorque(body, 0, 0, 0);
    x += kBodySnapshotSize;
  }
  q_ = state.q;
  qd_ = state.qd;
}

}  // namespace

std::unique_ptr<ArmEngine> MakeOdeArmEngine(const ArmModel& plant, const ArmEngineOptions& options) {
  const double max_step = options.max_step > 0 ? options.max_step : DefaultArmMaxStep("ode");
  return std::make_unique<OdeArmEngine>(plant, max_step);
}

}  // namespace twinsim

#include "engines/ode/ode_omni_engine.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Geometry>
#include <memory>
#include <ode/ode.h>

#include "engines/ode/ode_world.h"

namespace twinsim {
namespace {

// Wheel-floor contacts are springs of this stiffness, critically damped for the share
// of the robot's mass that rests on one wheel. 1e5 N/m sinks a 2.5 kg robot on four
// wheels by about 0.06 mm, far below anything the analytic model would notice, and ODE's
// implicit soft constraint stays stable at any step. Equal springs under a rigid chassis
// share the weight as the least-norm solution of OmniModel::wheel_load, taken about the
// true centre of mass (the wheels' own masses move it slightly off a lopsided layout).
constexpr double kContactStiffness = 1e5;   // N/m
constexpr double kContactDampingRatio = 1.0;

// Chassis against walls and other chassis: a hard bumper (a 20 N push dents it 0.02 mm),
// critically damped for the lighter robot so that the restitution below is the only
// bounce.
constexpr double kBumperStiffness = 1e6;  // N/m
constexpr double kBumperFriction = 0.3;
constexpr double kBumperRestitution = 0.1;
constexpr double kBumperBounceVelocity = 0.1;  // m/s, slower impacts do not bounce
constexpr int kMaxContactsPerPair = 4;
// At 1/300 s a robot at 2.5 m/s is found 8 mm inside a wall; pushing that out at the
// full ERP rate would throw it back at 0.4 m/s whatever the restitution. The wheels'
// own spring correction stays below 0.01 m/s, so the cap never touches them at rest.
constexpr double kOmniMaxCorrectingSpeed = 0.1;  // m/s

constexpr double kHingeErp = 0.8;  // fraction of a hinge's position error fixed per step

// The robot's vertical axis is body z; a wheel's axle never has a vertical part while
// the robot is level, so a projection shorter than this means the robot lies on its side.
constexpr double kMinAxleProjection = 1e-6;

// Collision categories: only the chassis and walls live in the collision space (wheels
// are tested against the floor directly), so these bits keep wall-wall pairs out.
constexpr unsigned long kChassisCategory = 1u << 0;
constexpr unsigned long kWallCategory = 1u << 1;

// ERP and CFM of a spring-damper constraint for one step of dt seconds (ODE manual,
// "How do I simulate a spring"): stiffness k N/m, damping c N s/m.
std::pair<double, double> SpringErpCfm(double k, double c, double dt) {
  const double denom = dt * k + c;
  return {dt * k / denom, 1.0 / denom};
}

// Damping c = 2 zeta sqrt(k m), N s/m, for a mass m kg on a spring of k N/m.
double ContactDamping(double stiffness, double mass) {
  return 2.0 * kContactDampingRatio * std::sqrt(stiffness * mass);
}

struct OdeRobot {
  OmniModel model;
  dBodyID chassis = nullptr;
  dGeomID chassis_geom = nullptr;
  std::vector<dBodyID> wheels;
  std::vector<dGeomID> wheel_geoms;
  std::vector<dJointID> hinges;
  std::vector<Eigen::Vector3d> wheel_offsets;  // m, wheel centre from the robot's centre at com_height, robot frame
  Eigen::Vector3d chassis_com = Eigen::Vector3d::Zero();  // m, the chassis body's origin from there, robot frame
  std::vector<Eigen::Vector3d> axles;          // unit a_i, robot frame
  Eigen::VectorXd torques;                     // n, N·m about a_i
  double wheel_contact_mass = 0;               // kg, the static share of one wheel
  // m, how far the wheels' contact springs sink under the robot's weight at rest:
  // SetState places the robot there, so that the floor carries it from the first step.
  // Placed touching, the springs carried nothing for the first steps and the wheels had
  // no grip: a replay that sets the observer's estimate every frame lost traction every
  // frame (an identified 11 kg Robotino predicted 6.0 mm on ODE against 2.9 on the
  // analytic engine and Bullet, which agree).
  double static_sink = 0;
};

// A chassis contact found by the broad phase, kept so that contact joints are created
// in an order that depends on the geometry alone, never on the space's internal lists.
struct BumperContact {
  int key_a = 0;  // the lower geom key of the pair (a chassis)
  int key_b = 0;
  int count = 0;
  dContactGeom geoms[kMaxContactsPerPair];
};

class OdeOmniEngine : public OmniEngine {
 public:
  OdeOmniEngine(const std::vector<OmniModel>& robots, const FieldModel& field);
  ~OdeOmniEngine() override;
  OdeOmniEngine(const OdeOmniEngine&) = delete;
  OdeOmniEngine& operator=(const OdeOmniEngine&) = delete;

  std::string name() const override { return "ode"; }
  int num_robots() const override { return static_cast<int>(robots_.size()); }
  void SetState(int robot, const OmniBodyState& state) override;
  OmniBodyState GetState(int robot) const override;
  void GetWheelSpeeds(int robot, Eigen::VectorXd* out) const override;
  void MoveRobot(int robot, const Pose2& pose) override;
  std::vector<double> SaveExact(int robot) const override;
  void RestoreExact(int robot, const std::vector<double>& snapshot) override;
  void SetWheelTorques(int robot, const Eigen::VectorXd& torques) override;
  void Step(double dt) override;

 private:
  void BuildRobot(int index, const OmniModel& model);
  void BuildWalls(const FieldModel& field);
  void CheckRobot(int robot) const;
  void AddWheelContacts(double dt);
  void AddBumperContacts(double dt);
  static void NearCallback(void* data, dGeomID o1, dGeomID o2);

  std::unique_ptr<OdeWorld> ode_world_;
  dWorldID world_ = nullptr;  // ode_world_'s
  dSpaceID space_ = nullptr;  // chassis and walls, which it owns
  dGeomID floor_ = nullptr;   // plane z = 0, tested against the wheels only
  dJointGroupID contact_group_ = nullptr;
  std::vector<OdeRobot> robots_;
  std::vector<BumperContact> bumper_contacts_;  // scratch, refilled every Step
};

// Geom keys: chassis i is i, wall j is num_robots + j, so a chassis always sorts first.
void SetGeomKey(dGeomID geom, int key) {
  dGeomSetData(geom, reinterpret_cast<void*>(static_cast<std::intptr_t>(key)));
}
int GeomKey(dGeomID geom) {
  return static_cast<int>(reinterpret_cast<std::intptr_t>(dGeomGetData(geom)));
}

OdeOmniEngine::OdeOmniEngine(const std::vector<OmniModel>& robots, const FieldModel& field) {
  for (const OmniModel& m : robots) {
    if (m.num_wheels() < 3 || m.geometry.rows() != m.num_wheels() || m.total_mass <= 0)
      throw std::invalid_argument("ode engine: robot model '" + m.name +
                                  "' needs at least 3 wheels and Finalize()");
  }
  EnsureOdeInitialized();
  ode_world_ = std::make_unique<OdeWorld>();
  world_ = ode_world_->id();
  const Eigen::Vector3d gravity = field.Gravity();
  SetUpFieldWorld(world_, gravity.x(), gravity.y(), gravity.z());
  // The world ERP only drives the hinges (contacts bring their own). Explicit Euler lets a
  // wheel centre drift outwards by b (omega dt)^2 / 2 per step on a spinning robot; at
  // ODE's default 0.2 that settles 2% of b out at 26 rad/s and 1/300 s, and the wheels
  // then spin 2% too fast. 0.8 leaves 0.3%; the direct solver takes it without jitter.
  dWorldSetERP(world_, kHingeErp);
  dWorldSetContactMaxCorrectingVel(world_, kOmniMaxCorrectingSpeed);
  // A hash space keeps the broad phase near-linear when 22 robots share the field.
  space_ = dHashSpaceCreate(nullptr);
  floor_ = dCreatePlane(nullptr, 0, 0, 1, 0);
  contact_group_ = dJointGroupCreate(0);

  robots_.resize(robots.size());
  for (std::size_t i = 0; i < robots.size(); ++i) BuildRobot(static_cast<int>(i), robots[i]);
  if (field.walls) BuildWalls(field);

  // Default places: a grid of still robots along the field's x axis, clear of each other.
  double max_radius = 0;
  for (const OmniModel& m : robots) max_radius = std::max(max_radius, m.chassis_radius);
  const double spacing = 2.5 * max_radius;  // m
  const int columns = std::max(1, static_cast<int>(field.length / spacing) - 1);
  for (int i = 0; i < num_robots(); ++i) {
    OmniBodyState state;
    state.pose.x = -0.5 * (columns - 1) * spacing + (i % columns) * spacing;
    state.pose.y = (i / columns) * spacing;
    state.wheel_speeds = Eigen::VectorXd::Zero(robots_[i].model.num_wheels());
    SetState(i, state);
  }
}

OdeOmniEngine::~OdeOmniEngine() {
  // Joints and bodies belong to the world, geoms to the space (or to nobody).
  dJointGroupDestroy(contact_group_);
  for (OdeRobot& robot : robots_) {
    for (dGeomID g : robot.wheel_geoms) dGeomDestroy(g);
  }
  dGeomDestroy(floor_);
  dSpaceDestroy(space_);  // destroys the chassis and wall geoms it holds
  // ode_world_ then destroys the world with every body and hinge.
}

void OdeOmniEngine::BuildRobot(int index, const OmniModel& model) {
  OdeRobot& robot = robots_[index];
  robot.model = model;
  const int n = model.num_wheels();
  robot.torques = Eigen::VectorXd::Zero(n);
  robot.wheel_contact_mass = model.total_mass / n;
  dVector3 gravity;
  dWorldGetGravity(world_, gravity);
  robot.static_sink = model.total_mass * std::abs(gravity[2]) / (n * kContactStiffness);

  // Built at the origin with yaw 0, so the hinges' body-relative anchors and axes are
  // exactly the robot-frame numbers that SetState uses.
  robot.chassis = dBodyCreate(world_);
  const double m = model.chassis_mass, r_c = model.chassis_radius, h = model.chassis_height;
  const double i_xy = m * (3 * r_c * r_c + h * h) / 12.0;
  const double i_z = model.chassis_inertia_z > 0 ? model.chassis_inertia_z : 0.5 * m * r_c * r_c;
  dMass mass;
  dMassSetParameters(&mass, m, 0, 0, 0, i_xy, i_xy, i_z, 0, 0, 0);
  dBodySetMass(robot.chassis, &mass);
  // ODE's bodies have their centre of mass at their origin: the chassis' sits at its
  // centre of mass, and the cylinder hangs around the robot's centre.
  robot.chassis_com = Eigen::Vector3d(model.chassis_com.x(), model.chassis_com.y(), 0);
  dBodySetPosition(robot.chassis, robot.chassis_com.x(), robot.chassis_com.y(), model.com_height);

  robot.chassis_geom = dCreateCylinder(space_, r_c, h);
  dGeomSetBody(robot.chassis_geom, robot.chassis);
  dGeomSetOffsetPosition(robot.chassis_geom, -robot.chassis_com.x(), -robot.chassis_com.y(),
                         model.ground_clearance + 0.5 * h - model.com_height);
  dGeomSetCategoryBits(robot.chassis_geom, kChassisCategory);
  dGeomSetCollideBits(robot.chassis_geom, kChassisCategory | kWallCategory);
  SetGeomKey(robot.chassis_geom, index);

  const double r = model.wheel_radius, b = model.wheel_distance;
  const double i_spin = model.wheel_spin_inertia, i_diam = model.wheel_inertia_diametral;
  for (int i = 0; i < n; ++i) {
    const double c = std::cos(model.wheel_angles[i]), s = std::sin(model.wheel_angles[i]);
    const Eigen::Vector3d axle(-c, -s, 0);
    const Eigen::Vector3d offset(b * c, b * s, r - model.com_height);
    robot.axles.push_back(axle);
    robot.wheel_offsets.push_back(offset);

    dBodyID wheel = dBodyCreate(world_);
    // Spin inertia about the axle, diametral about the two axes across it, written in
    // the wheel's frame (which starts aligned with the chassis).
    const Eigen::Matrix3d inertia =
        i_diam * Eigen::Matrix3d::Identity() + (i_spin - i_diam) * axle * axle.transpose();
    dMassSetParameters(&mass, model.wheel_mass, 0, 0, 0, inertia(0, 0), inertia(1, 1),
                       inertia(2, 2), inertia(0, 1), inertia(0, 2), inertia(1, 2));
    dBodySetMass(wheel, &mass);
    dBodySetPosition(wheel, offset.x(), offset.y(), r);
    // ODE's explicit gyroscopic term on a wheel spinning at ~100 rad/s on a yawing chassis
    // drains spin each step, an O(dt) error: 3% of the yaw acceleration at 1/300 s. The
    // true term is a horizontal torque that shifts ~0.2 N of load between wheels and
    // cannot change the spin, so a planar drive loses nothing by leaving it out.
    dBodySetGyroscopicMode(wheel, 0);

    // A sphere touches the floor right under the wheel centre however the chassis rolls.
    dGeomID sphere = dCreateSphere(nullptr, r);
    dGeomSetBody(sphere, wheel);

    // Wheel is body 1 and chassis body 2: ODE's hinge rate and torque are body 1
    // relative to body 2 about the axis, so a positive torque spins the wheel about +a_i.
    dJointID hinge = dJointCreateHinge(world_, nullptr);
    dJointAttach(hinge, wheel, robot.chassis);
    dJointSetHingeAnchor(hinge, offset.x(), offset.y(), r);
    dJointSetHingeAxis(hinge, axle.x(), axle.y(), axle.z());

    robot.wheels.push_back(wheel);
    robot.wheel_geoms.push_back(sphere);
    robot.hinges.push_back(hinge);
  }
}

void OdeOmniEngine::BuildWalls(const FieldModel& field) {
  const double hw = field.wall_height;
  const auto boxes = field.WallBoxes();
  for (int j = 0; j < 4; ++j) {
    const auto& box = boxes[static_cast<std::size_t>(j)];
    dGeomID wall = dCreateBox(space_, box[2], box[3], hw);
    dGeomSetPosition(wall, box[0], box[1], 0.5 * hw);
    dGeomSetCategoryBits(wall, kWallCategory);
    dGeomSetCollideBits(wall, kChassisCategory);
    SetGeomKey(wall, num_robots() + j);
  }
}

void OdeOmniEngine::CheckRobot(int robot) const {
  if (robot < 0 || robot >= num_robots())
    throw std::invalid_argument("ode engine: robot index " + std::to_string(robot) +
                                " out of range [0, " + std::to_string(num_robots()) + ")");
}

void OdeOmniEngine::SetState(int index, const OmniBodyState& state) {
  CheckRobot(index);
  OdeRobot& robot = robots_[index];
  const int n = robot.model.num_wheels();
  if (state.wheel_speeds.size() != n)
    throw std::invalid_argument("ode engine: " + std::to_string(state.wheel_speeds.size()) +
                                " wheel speeds for a robot with " + std::to_string(n) +
                                " wheels");

  const double theta = state.pose.theta;
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  dQuaternion q = {std::cos(0.5 * theta), 0, 0, std::sin(0.5 * theta)};
  const Twist2 v_field = BodyToField(state.velocity, theta);
  const Eigen::Vector3d com(state.pose.x, state.pose.y, robot.model.com_height - robot.static_sink);
  const Eigen::Vector3d v(v_field.vx, v_field.vy, 0);
  const Eigen::Vector3d w(0, 0, state.velocity.omega);

  auto place = [&q](dBodyID body, const Eigen::Vector3d& p, const Eigen::Vector3d& lin,
                    const Eigen::Vector3d& ang) {
    dBodySetPosition(body, p.x(), p.y(), p.z());
    dBodySetQuaternion(body, q);
    dBodySetLinearVel(body, lin.x(), lin.y(), lin.z());
    dBodySetAngularVel(body, ang.x(), ang.y(), ang.z());
    dBodySetForce(body, 0, 0, 0);
    dBodySetTorque(body, 0, 0, 0);
    dBodyEnable(body);
  };
  const Eigen::Vector3d chassis_com = rot * robot.chassis_com;
  place(robot.chassis, com + chassis_com, v + w.cross(chassis_com), w);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d offset = rot * robot.wheel_offsets[i];
    place(robot.wheels[i], com + offset, v + w.cross(offset),
          w + state.wheel_speeds[i] * (rot * robot.axles[i]));
  }
}

OmniBodyState OdeOmniEngine::GetState(int index) const {
  CheckRobot(index);
  const OdeRobot& robot = robots_[index];
  const dReal* p = dBodyGetPosition(robot.chassis);
  const dReal* rot = dBodyGetRotation(robot.chassis);  // 3x4, row-major
  const dReal* v = dBodyGetLinearVel(robot.chassis);
  const dReal* w = dBodyGetAngularVel(robot.chassis);

  // The robot's centre: the chassis body's origin less its centre-of-mass offset.
  OmniBodyState state;
  state.pose.theta = std::atan2(rot[4], rot[0]);
  const double c = std::cos(state.pose.theta), s = std::sin(state.pose.theta);
  const double ox = c * robot.chassis_com.x() - s * robot.chassis_com.y();
  const double oy = s * robot.chassis_com.x() + c * robot.chassis_com.y();
  state.pose.x = p[0] - ox;
  state.pose.y = p[1] - oy;
  const Twist2 v_field{v[0] + w[2] * oy, v[1] - w[2] * ox, w[2]};
  state.velocity = FieldToBody(v_field, state.pose.theta);

  GetWheelSpeeds(index, &state.wheel_speeds);
  return state;
}

void OdeOmniEngine::GetWheelSpeeds(int index, Eigen::VectorXd* out) const {
  CheckRobot(index);
  const OdeRobot& robot = robots_[index];
  const dReal* rot = dBodyGetRotation(robot.chassis);  // 3x4, row-major
  const dReal* w = dBodyGetAngularVel(robot.chassis);
  const int n = robot.model.num_wheels();
  out->resize(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& a = robot.axles[i];
    const dReal* ww = dBodyGetAngularVel(robot.wheels[i]);
    (*out)[i] = (ww[0] - w[0]) * (rot[0] * a.x() + rot[1] * a.y() + rot[2] * a.z()) +
                (ww[1] - w[1]) * (rot[4] * a.x() + rot[5] * a.y() + rot[6] * a.z()) +
                (ww[2] - w[2]) * (rot[8] * a.x() + rot[9] * a.y() + rot[10] * a.z());
  }
}

void OdeOmniEngine::MoveRobot(int index, const Pose2& pose) {
  CheckRobot(index);
  OdeRobot& robot = robots_[index];
  const Pose2 from = GetState(index).pose;
  const double turn = pose.theta - from.theta;
  const double c = std::cos(turn), s = std::sin(turn);
  const dQuaternion q_turn = {std::cos(0.5 * turn), 0, 0, std::sin(0.5 * turn)};
  auto move = [&](dBodyID body) {
    const dReal* p = dBodyGetPosition(body);
    const double rx = p[0] - from.x, ry = p[1] - from.y;
    dBodySetPosition(body, pose.x + c * rx - s * ry, pose.y + s * rx + c * ry, p[2]);
    dQuaternion q;
    dQMultiply0(q, q_turn, dBodyGetQuaternion(body));
    dBodySetQuaternion(body, q);
    const dReal* v = dBodyGetLinearVel(body);
    dBodySetLinearVel(body, c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]);
    const dReal* w = dBodyGetAngularVel(body);
    dBodySetAngularVel(body, c * w[0] - s * w[1], s * w[0] + c * w[1], w[2]);
  };
  move(robot.chassis);
  for (dBodyID wheel : robot.wheels) move(wheel);
}

// Per body: position (3), quaternion (4), linear (3) and angular velocity (3).
constexpr int kOmniBodySnapshotSize = 13;

std::vector<double> OdeOmniEngine::SaveExact(int index) const {
  CheckRobot(index);
  const OdeRobot& robot = robots_[index];
  std::vector<double> out;
  out.reserve(kOmniBodySnapshotSize * (1 + robot.wheels.size()));
  auto save = [&out](dBodyID body) {
    for (const dReal* values : {dBodyGetPosition(body), dBodyGetQuaternion(body), dBodyGetLinearVel(body),
                                dBodyGetAngularVel(body)}) {
      const int count = values == dBodyGetQuaternion(body) ? 4 : 3;
      out.insert(out.end(), values, values + count);
    }
  };
  save(robot.chassis);
  for (dBodyID wheel : robot.wheels) save(wheel);
  return out;
}

void OdeOmniEngine::RestoreExact(int index, const std::vector<double>& snapshot) {
  CheckRobot(index);
  OdeRobot& robot = robots_[index];
  if (snapshot.size() != kOmniBodySnapshotSize * (1 + robot.wheels.size()))
    throw std::invalid_argument("ode engine: snapshot of the wrong size");
  const double* v = snapshot.data();
  auto restore = [&v](dBodyID body) {
    dBodySetPosition(body, v[0], v[1], v[2]);
    dQuaternion q = {v[3], v[4], v[5], v[6]};
    dBodySetQuaternion(body, q);
    dBodySetLinearVel(body, v[7], v[8], v[9]);
    dBodySetAngularVel(body, v[10], v[11], v[12]);
    v += kOmniBodySnapshotSize;
  };
  restore(robot.chassis);
  for (dBodyID wheel : robot.wheels) restore(wheel);
}

void OdeOmniEngine::SetWheelTorques(int index, const Eigen::VectorXd& torques) {
  CheckRobot(index);
  OdeRobot& robot = robots_[index];
  if (torques.size() != robot.model.num_wheels())
    throw std::invalid_argument("ode engine: " + std::to_string(torques.size()) +
                                " wheel torques for a robot with " +
                                std::to_string(robot.model.num_wheels()) + " wheels");
  robot.torques = torques;
}

void OdeOmniEngine::AddWheelContacts(double dt) {
  for (OdeRobot& robot : robots_) {
    const auto [erp, cfm] = SpringErpCfm(
        kContactStiffness, ContactDamping(kContactStiffness, robot.wheel_contact_mass), dt);
    const dReal* rot = dBodyGetRotation(robot.chassis);
    for (int i = 0; i < robot.model.num_wheels(); ++i) {
      dContact contact{};
      if (dCollide(robot.wheel_geoms[i], floor_, 1, &contact.geom, sizeof(dContactGeom)) == 0)
        continue;
      // Friction direction 1 is the axle laid on the floor (the rollers' free direction);
      // direction 2 (ODE takes normal x fdir1) is then the rolling direction.
      const Eigen::Vector3d& a = robot.axles[i];
      double ax = rot[0] * a.x() + rot[1] * a.y() + rot[2] * a.z();
      double ay = rot[4] * a.x() + rot[5] * a.y() + rot[6] * a.z();
      const double len = std::hypot(ax, ay);
      // Coulomb (mu times the normal force) rather than ODE's default force cap.
      contact.surface.mode = dContactApprox1 | dContactSoftERP | dContactSoftCFM;
      if (len > kMinAxleProjection) {
        contact.surface.mode |= dContactMu2 | dContactFDir1;
        contact.surface.mu = robot.model.roller_friction;
        contact.surface.mu2 = robot.model.wheel_friction;
        contact.fdir1[0] = ax / len;
        contact.fdir1[1] = ay / len;
        contact.fdir1[2] = 0;
      } else {
        contact.surface.mu = robot.model.wheel_friction;
      }
      contact.surface.soft_erp = erp;
      contact.surface.soft_cfm = cfm;
      dJointID joint = dJointCreateContact(world_, contact_group_, &contact);
      dJointAttach(joint, robot.wheels[i], nullptr);
    }
  }
}

void OdeOmniEngine::NearCallback(void* data, dGeomID o1, dGeomID o2) {
  auto* self = static_cast<OdeOmniEngine*>(data);
  if (GeomKey(o2) < GeomKey(o1)) std::swap(o1, o2);
  BumperContact found;
  found.key_a = GeomKey(o1);
  found.key_b = GeomKey(o2);
  found.count = dCollide(o1, o2, kMaxContactsPerPair, found.geoms, sizeof(dContactGeom));
  if (found.count > 0) self->bumper_contacts_.push_back(found);
}

void OdeOmniEngine::AddBumperContacts(double dt) {
  bumper_contacts_.clear();
  dSpaceCollide(space_, this, &NearCallback);
  std::sort(bumper_contacts_.begin(), bumper_contacts_.end(),
            [](const BumperContact& x, const BumperContact& y) {
              return std::make_pair(x.key_a, x.key_b) < std::make_pair(y.key_a, y.key_b);
            });
  for (const BumperContact& pair : bumper_contacts_) {
    // Damped for the lighter robot of the pair (a wall counts as infinitely heavy).
    double mass = robots_[pair.key_a].model.total_mass;
    if (pair.key_b < num_robots()) mass = std::min(mass, robots_[pair.key_b].model.total_mass);
    const auto [erp, cfm] =
        SpringErpCfm(kBumperStiffness, ContactDamping(kBumperStiffness, mass), dt);
    dBodyID body_a = robots_[pair.key_a].chassis;
    dBodyID body_b = pair.key_b < num_robots() ? robots_[pair.key_b].chassis : nullptr;
    for (int k = 0; k < pair.count; ++k) {
      dContact contact{};
      contact.geom = pair.geoms[k];
      contact.surface = BouncingSurface(kBumperFriction, kBumperRestitution, kBumperBounceVelocity, erp, cfm);
      dJointID joint = dJointCreateContact(world_, contact_group_, &contact);
      dJointAttach(joint, body_a, body_b);
    }
  }
}

void OdeOmniEngine::Step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw std::invalid_argument("ode engine: step " + std::to_string(dt) + " s must be > 0");
  EnsureOdeInitialized();
  // ODE clears the force accumulators after every step, so the held torques go in again.
  for (OdeRobot& robot : robots_) {
    for (int i = 0; i < robot.model.num_wheels(); ++i)
      dJointAddHingeTorque(robot.hinges[i], robot.torques[i]);
  }
  AddWheelContacts(dt);
  AddBumperContacts(dt);
  dWorldStep(world_, dt);
  dJointGroupEmpty(contact_group_);
}

}  // namespace

std::unique_ptr<OmniEngine> MakeOdeOmniEngine(const std::vector<OmniModel>& robots,
                                              const FieldModel& field) {
  return std::make_unique<OdeOmniEngine>(robots, field);
}

}  // namespace twinsim

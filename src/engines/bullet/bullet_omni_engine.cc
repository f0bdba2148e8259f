#include "engines/bullet/bullet_omni_engine.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace twinsim {
namespace {

// What a collision object is (btCollisionObject::getUserIndex()): contacts are told
// apart by it, wheel-floor contacts getting the wheel's anisotropic friction.
constexpr int kStaticBody = 0;
constexpr int kChassisBody = 1;
constexpr int kWheelBody = 2;

// Collision filter groups: wheels touch only the floor, chassis only walls and chassis.
constexpr int kFloorGroup = 1 << 0;
constexpr int kWallGroup = 1 << 1;
constexpr int kChassisGroup = 1 << 2;
constexpr int kWheelGroup = 1 << 3;

constexpr double kChassisFriction = 0.3;  // Coulomb coefficient, chassis-wall and chassis-chassis

// Sequential-impulse sweeps per step. The chassis is ~46 times heavier than a wheel and
// hangs on it by a hinge whose impulses Bullet does not warm-start; with 20 sweeps the
// chassis stays within 3e-4 rad of level under 2 m/s^2 drives, and more sweeps change
// the drive results by less than 1e-4.
constexpr int kOmniSolverIterations = 20;
// Baumgarte factor of the hinges. Integrating chassis and wheel separately moves a wheel
// outwards by b (omega dt)^2 / 2 per step while the robot turns; at the default 0.2 the
// hinge let it drift 2 mm out at 36 rad/s (2% less yaw speed after a 1 s spin-up at
// 1/300 s), at 0.8 0.7 mm (0.4%).
constexpr double kJointErp = 0.8;
// Baumgarte factor of chassis contacts (walls, other robots; wheel contacts bring their
// spring's own). Bullet's default keeps colliding robots from being pushed apart faster
// than they came: 0.8 threw two robots meeting at 2 m/s each apart at 0.5 m/s.
constexpr double kContactErp = 0.2;

// Wheel-floor contacts are springs of this stiffness, critically damped for the share
// of the robot's mass that rests on one wheel (as in the ODE engine). 1e5 N/m sinks a
// 2.5 kg robot on four wheels by about 0.06 mm. Equal springs under a rigid chassis share
// the weight as the least-norm solution (OmniModel::wheel_load); perfectly rigid contacts
// would leave four wheels' loads statically indeterminate, to wherever the solver's
// sweep order and warm start put them.
constexpr double kContactStiffness = 1e5;  // N/m
constexpr double kContactDampingRatio = 1.0;

// One wheel's floor contact: its friction and spring and, for warm starting, the
// impulses the solver found in the step before. Reached from the wheel body's user
// pointer.
struct WheelContact {
  double rolling_friction = 0;  // Coulomb coefficient along the rolling direction
  double roller_friction = 0;   // Coulomb coefficient across the wheel, along its axle
  double damping = 0;           // N s/m, of the contact spring (kContactStiffness)
  btScalar normal_impulse = 0;   // N s
  btScalar rolling_impulse = 0;  // N s, along friction direction 1
  btScalar roller_impulse = 0;   // N s, along friction direction 2
  long step = -1;                // OmniWorld step that stored the impulses; -1: none
};

WheelContact* WheelContactOf(const btCollisionObject* object) {
  if (object == nullptr || object->getUserIndex() != kWheelBody) return nullptr;
  return static_cast<WheelContact*>(object->getUserPointer());
}

// Bullet's sequential-impulse solver with two corrections to the friction rows that
// setupFrictionConstraint (Bullet 3.24) builds:
// - Its target velocity leaves out the external torque impulse of the step (contact and
//   joint rows include it), so a wheel torque would spin the wheel up unresisted for one
//   step, every step: a standing rolling slip of r tau dt / I_spin (0.23 m/s for
//   0.047 N m at 1/300 s) that wheel speeds would show. The missing term is added back
//   to every friction row.
// - Both friction rows of a contact get m_combinedFriction. Scaling the second row's
//   direction by roller/wheel friction would scale its force limit, but the row's
//   effective mass adds the body's unscaled inverse mass, so below ~0.5 m/s of sliding
//   roller friction would act as a weak viscous drag. The axle row of a wheel contact
//   gets the roller coefficient here instead.
class WheelFrictionSolver final : public btSequentialImpulseConstraintSolver {
 protected:
  btScalar solveGroupCacheFriendlySetup(btCollisionObject** bodies, int num_bodies,
                                        btPersistentManifold** manifolds, int num_manifolds,
                                        btTypedConstraint** constraints, int num_constraints,
                                        const btContactSolverInfo& info,
                                        btIDebugDraw* debug_drawer) override {
    const btScalar residual = btSequentialImpulseConstraintSolver::solveGroupCacheFriendlySetup(
        bodies, num_bodies, manifolds, num_manifolds, constraints, num_constraints, info,
        debug_drawer);
    for (int i = 0; i < m_tmpSolverContactFrictionConstraintPool.size(); ++i) {
      btSolverConstraint& row = m_tmpSolverContactFrictionConstraintPool[i];
      const btSolverBody& a = m_tmpSolverBodyPool[row.m_solverBodyIdA];
      const btSolverBody& b = m_tmpSolverBodyPool[row.m_solverBodyIdB];
      const btScalar missing = row.m_relpos1CrossNormal.dot(a.m_externalTorqueImpulse) +
                               row.m_relpos2CrossNormal.dot(b.m_externalTorqueImpulse);
      row.m_rhs -= missing * row.m_jacDiagABInv;
    }
    if (!(info.m_solverMode & SOLVER_USE_2_FRICTION_DIRECTIONS)) return residual;
    // Each contact row names its first friction row; the second (the axle direction set
    // by OmniWorld) follows it.
    for (int i = 0; i < m_tmpSolverContactConstraintPool.size(); ++i) {
      const btSolverConstraint& contact = m_tmpSolverContactConstraintPool[i];
      const WheelContact* wheel = WheelContactOf(SolverBody(contact.m_solverBodyIdA));
      if (wheel == nullptr) wheel = WheelContactOf(SolverBody(contact.m_solverBodyIdB));
      if (wheel == nullptr) continue;
      m_tmpSolverContactFrictionConstraintPool[contact.m_frictionIndex + 1].m_friction =
          wheel->roller_friction;
    }
    return residual;
  }

 private:
  const btCollisionObject* SolverBody(int id) const {
    return m_tmpSolverBodyPool[id].m_originalBody;  // null for static bodies
  }
};

// A discrete dynamics world that prepares every wheel-floor contact before solving
// (one point, the wheel's friction frame, warm start from the step before), and solves
// the whole world as one group in an order fixed by the bodies alone. Bullet's island
// splitting sorts constraints with an unstable sort on island ids that depend on
// broadphase history, and hands manifolds over in creation order; either would make a
// run after SetState differ in the last bits from one in a freshly built world.
class OmniWorld final : public btDiscreteDynamicsWorld {
 public:
  using btDiscreteDynamicsWorld::btDiscreteDynamicsWorld;

  // Solver calls so far; WheelContact::step refers to it.
  long step() const { return step_; }

  void solveConstraints(btContactSolverInfo& info) override {
    ++step_;
    manifolds_.clear();
    wheel_manifolds_.clear();
    for (int m = 0; m < m_dispatcher1->getNumManifolds(); ++m) {
      btPersistentManifold* manifold = m_dispatcher1->getManifoldByIndexInternal(m);
      if (manifold->getNumContacts() == 0) continue;
      const btCollisionObject* wheel = manifold->getBody0();
      WheelContact* contact = WheelContactOf(wheel);
      if (contact == nullptr) {
        wheel = manifold->getBody1();
        contact = WheelContactOf(wheel);
      }
      if (contact != nullptr) {
        PrepareWheelContact(*wheel, *contact, manifold);
        wheel_manifolds_.push_back(manifold);
      } else {
        for (int p = 0; p < manifold->getNumContacts(); ++p) {
          btManifoldPoint& point = manifold->getContactPoint(p);
          point.m_combinedFriction = kChassisFriction;
          point.m_combinedRestitution = 0;
        }
      }
      manifolds_.push_back(manifold);
    }
    std::sort(manifolds_.begin(), manifolds_.end(),
              [](const btPersistentManifold* a, const btPersistentManifold* b) {
                return Key(a) < Key(b);
              });

    const int num_objects = m_collisionObjects.size();
    const int num_manifolds = static_cast<int>(manifolds_.size());
    const int num_constraints = m_constraints.size();
    m_constraintSolver->prepareSolve(num_objects, num_manifolds);
    m_constraintSolver->solveGroup(num_objects ? &m_collisionObjects[0] : nullptr, num_objects,
                                   num_manifolds ? manifolds_.data() : nullptr, num_manifolds,
                                   num_constraints ? &m_constraints[0] : nullptr,
                                   num_constraints, info, m_debugDrawer, m_dispatcher1);
    m_constraintSolver->allSolved(info, m_debugDrawer);

    for (btPersistentManifold* manifold : wheel_manifolds_) {
      WheelContact* contact = WheelContactOf(manifold->getBody0());
      if (contact == nullptr) contact = WheelContactOf(manifold->getBody1());
      const btManifoldPoint& point = manifold->getContactPoint(0);
      contact->normal_impulse = point.m_appliedImpulse;
      contact->rolling_impulse = point.m_appliedImpulseLateral1;
      contact->roller_impulse = point.m_appliedImpulseLateral2;
      contact->step = step_;
    }
  }

 protected:
  // Islands serve sleeping and per-island solving; neither is used here.
  void calculateSimulationIslands() override {}

 private:
  // Orders manifolds by the two bodies' fixed places in the world.
  static std::pair<int, int> Key(const btPersistentManifold* manifold) {
    const int a = manifold->getBody0()->getWorldArrayIndex();
    const int b = manifold->getBody1()->getWorldArrayIndex();
    return {std::min(a, b), std::max(a, b)};
  }

  // A sphere touches a plane at one point, its lowest; older points that Bullet keeps
  // in the manifold are lifted copies and go. Bullet matches a new point to a cached one
  // by its place on the wheel, which spin moves by more than the breaking threshold
  // (0.02 r = 0.5 mm) per step above ~20 rad/s at 1 ms, and drops points that slid
  // sideways as far: the warm-start impulse would then restart from zero, and the wheel
  // loads, which the solver settles only over many steps, wander until a wheel skids
  // (seen at 1 ms in a sideways drive). So each wheel's impulses are carried from step
  // to step here instead.
  // Friction direction 1 is the rolling direction (horizontal, across the axle),
  // direction 2 the axle projected on the floor; WheelFrictionSolver gives direction 2
  // its own coefficient.
  void PrepareWheelContact(const btCollisionObject& wheel, const WheelContact& contact,
                           btPersistentManifold* manifold) const {
    int lowest = 0;
    for (int p = 1; p < manifold->getNumContacts(); ++p)
      if (manifold->getContactPoint(p).getDistance() <
          manifold->getContactPoint(lowest).getDistance())
        lowest = p;
    if (manifold->getNumContacts() > 1) {
      const btManifoldPoint kept = manifold->getContactPoint(lowest);
      manifold->clearManifold();
      manifold->addManifoldPoint(kept);
    }
    btManifoldPoint& point = manifold->getContactPoint(0);
    const bool warm = contact.step == step_ - 1;
    point.m_appliedImpulse = warm ? contact.normal_impulse : 0;
    point.m_appliedImpulseLateral1 = warm ? contact.rolling_impulse : 0;
    point.m_appliedImpulseLateral2 = warm ? contact.roller_impulse : 0;

    // The wheel body's local x axis is its axle.
    const btVector3 axle = wheel.getWorldTransform().getBasis().getColumn(0);
    btVector3 across(axle.x(), axle.y(), 0);
    const btScalar length = across.length();
    across = length > 1e-9 ? across / length : btVector3(1, 0, 0);
    point.m_combinedFriction = contact.rolling_friction;
    point.m_combinedRestitution = 0;
    point.m_lateralFrictionDir1 = btVector3(-across.y(), across.x(), 0);
    point.m_lateralFrictionDir2 = across;
    point.m_combinedContactStiffness1 = kContactStiffness;
    point.m_combinedContactDamping1 = contact.damping;
    point.m_contactPointFlags |=
        BT_CONTACT_FLAG_LATERAL_FRICTION_INITIALIZED | BT_CONTACT_FLAG_CONTACT_STIFFNESS_DAMPING;
  }

  long step_ = 0;  // solver calls so far
  std::vector<btPersistentManifold*> manifolds_;        // this step's, in solving order
  std::vector<btPersistentManifold*> wheel_manifolds_;  // this step's wheel-floor ones
};

class BulletOmniEngine final : public OmniEngine {
 public:
  BulletOmniEngine(const std::vector<OmniModel>& robots, const FieldModel& field);
  ~BulletOmniEngine() override;

  std::string name() const override { return "bullet"; }
  int num_robots() const override { return static_cast<int>(robots_.size()); }
  void SetState(int robot, const OmniBodyState& state) override;
  OmniBodyState GetState(int robot) const override;
  void GetWheelSpeeds(int robot, Eigen::VectorXd* out) const override;
  void MoveRobot(int robot, const Pose2& pose) override;
  std::vector<double> SaveExact(int robot) const override;
  void RestoreExact(int robot, const std::vector<double>& snapshot) override;
  void SetWheelTorques(int robot, const Eigen::VectorXd& torques) override;
  void Step(double dt) override;

  // For tests: the world and a robot's bodies.
  btDiscreteDynamicsWorld* world() { return world_.get(); }
  btRigidBody* chassis(int robot) { return robots_.at(robot)->chassis.get(); }
  btRigidBody* wheel(int robot, int i) { return robots_.at(robot)->wheels.at(i).get(); }

 private:
  // One robot's bodies. Members are destroyed bottom-up: hinges, bodies, then shapes.
  struct Robot {
    OmniModel model;
    std::vector<WheelContact> contacts;  // n, one per wheel; the wheel bodies point here
    std::vector<btVector3> axles;  // a_i in the chassis frame (unit)
    btVector3 chassis_com{0, 0, 0};  // m, the chassis body's origin from the robot's centre at com_height, robot frame
    Eigen::VectorXd torques;       // n, N·m about a_i
    std::unique_ptr<btCylinderShapeZ> chassis_cylinder;
    std::unique_ptr<btCompoundShape> chassis_shape;
    std::unique_ptr<btSphereShape> wheel_shape;
    std::unique_ptr<btRigidBody> chassis;
    std::vector<std::unique_ptr<btRigidBody>> wheels;
    std::vector<std::unique_ptr<btHingeConstraint>> hinges;
  };

  void BuildRobot(Robot& robot);
  void BuildWalls(const FieldModel& field);
  Robot& CheckedRobot(int robot) const;
  void ForgetContacts(Robot& robot);

  // Declared in the order Bullet needs them built; destroyed in reverse.
  std::unique_ptr<btDefaultCollisionConfiguration> config_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btDbvtBroadphase> broadphase_;
  std::unique_ptr<WheelFrictionSolver> solver_;
  std::unique_ptr<OmniWorld> world_;
  std::unique_ptr<btStaticPlaneShape> floor_shape_;
  std::unique_ptr<btRigidBody> floor_;
  std::vector<std::unique_ptr<btBoxShape>> wall_shapes_;
  std::vector<std::unique_ptr<btRigidBody>> walls_;
  std::vector<std::unique_ptr<Robot>> robots_;  // heap: bodies keep pointers into them
};

// Puts a body at `pose` moving with `velocity`/`spin` (field frame), with no forces and
// no interpolation history.
void PlaceBody(btRigidBody* body, const btTransform& pose, const btVector3& velocity,
               const btVector3& spin) {
  body->setCenterOfMassTransform(pose);
  body->setLinearVelocity(velocity);
  body->setAngularVelocity(spin);
  body->setInterpolationLinearVelocity(velocity);
  body->setInterpolationAngularVelocity(spin);
  body->clearForces();
}

BulletOmniEngine::BulletOmniEngine(const std::vector<OmniModel>& robots,
                                   const FieldModel& field) {
  for (const OmniModel& m : robots) {
    if (m.num_wheels() < 3 || m.geometry.rows() != m.num_wheels() || m.total_mass <= 0)
      throw std::invalid_argument("bullet engine: robot model '" + m.name +
                                  "' needs at least 3 wheels and Finalize()");
  }
  config_ = std::make_unique<btDefaultCollisionConfiguration>();
  dispatcher_ = std::make_unique<btCollisionDispatcher>(config_.get());
  broadphase_ = std::make_unique<btDbvtBroadphase>();
  solver_ = std::make_unique<WheelFrictionSolver>();
  world_ = std::make_unique<OmniWorld>(dispatcher_.get(), broadphase_.get(), solver_.get(),
                                       config_.get());
  const Eigen::Vector3d gravity = field.Gravity();
  world_->setGravity(btVector3(gravity.x(), gravity.y(), gravity.z()));

  btContactSolverInfo& info = world_->getSolverInfo();
  info.m_numIterations = kOmniSolverIterations;
  info.m_erp = kJointErp;
  info.m_erp2 = kContactErp;
  info.m_restitution = 0;
  // Friction directions are set per contact (OmniWorld); warm starting carries the
  // contact impulses from step to step and is reset with the contacts in SetState.
  info.m_solverMode = SOLVER_USE_2_FRICTION_DIRECTIONS | SOLVER_ENABLE_FRICTION_DIRECTION_CACHING |
                      SOLVER_USE_WARMSTARTING;

  floor_shape_ = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0);
  floor_ = std::make_unique<btRigidBody>(
      btRigidBody::btRigidBodyConstructionInfo(0, nullptr, floor_shape_.get()));
  floor_->setUserIndex(kStaticBody);
  world_->addRigidBody(floor_.get(), kFloorGroup, kWheelGroup);
  if (field.walls) BuildWalls(field);

  for (const OmniModel& m : robots) {
    robots_.push_back(std::make_unique<Robot>());
    robots_.back()->model = m;
    BuildRobot(*robots_.back());
  }

  // Default places: a grid of still robots along the field's x axis, clear of each other.
  double max_radius = 0;
  for (const OmniModel& m : robots) max_radius = std::max(max_radius, m.chassis_radius);
  const double spacing = 2.5 * max_radius;  // m
  const int columns = std::max(1, static_cast<int>(field.length / spacing) - 1);
  for (int i = 0; i < num_robots(); ++i) {
    OmniBodyState state;
    state.pose.x = -0.5 * (columns - 1) * spacing + (i % columns) * spacing;
    state.pose.y = (i / columns) * spacing;
    state.wheel_speeds = Eigen::VectorXd::Zero(robots_[i]->model.num_wheels());
    SetState(i, state);
  }
}

BulletOmniEngine::~BulletOmniEngine() {
  // Take everything out of the world; the members then free constraints, bodies,
  // shapes, world, solver, broadphase, dispatcher and configuration in that order.
  for (auto& robot : robots_)
    for (auto& hinge : robot->hinges) world_->removeConstraint(hinge.get());
  for (auto& robot : robots_) {
    for (auto& wheel : robot->wheels) world_->removeRigidBody(wheel.get());
    world_->removeRigidBody(robot->chassis.get());
  }
  for (auto& wall : walls_) world_->removeRigidBody(wall.get());
  world_->removeRigidBody(floor_.get());
}

void BulletOmniEngine::BuildRobot(Robot& robot) {
  const OmniModel& m = robot.model;
  const int n = m.num_wheels();
  // Sized once: the wheel bodies keep pointers to the elements.
  const double damping =
      2 * kContactDampingRatio * std::sqrt(kContactStiffness * m.total_mass / n);  // N s/m
  robot.contacts.assign(n, WheelContact{m.wheel_friction, m.roller_friction, damping});
  robot.torques = Eigen::VectorXd::Zero(n);

  // Chassis: a solid cylinder for the tilt axes, the model's yaw inertia; the body's
  // origin is the centre of mass, so the cylinder hangs from it as a compound child.
  const double r_c = m.chassis_radius, h = m.chassis_height;  // m
  const double i_tilt = m.chassis_mass * (3 * r_c * r_c + h * h) / 12;  // kg m^2
  const double i_yaw = m.chassis_inertia_z > 0 ? m.chassis_inertia_z
                                               : 0.5 * m.chassis_mass * r_c * r_c;  // kg m^2
  robot.chassis_cylinder = std::make_unique<btCylinderShapeZ>(btVector3(r_c, r_c, 0.5 * h));
  // Bullet rounds convex edges by the margin; keep the rounding small against the size.
  robot.chassis_cylinder->setMargin(std::min(0.005, 0.25 * std::min(r_c, 0.5 * h)));
  robot.chassis_shape = std::make_unique<btCompoundShape>(/*enableDynamicAabbTree=*/false, 1);
  // The chassis' centre of mass may lie off the robot's centre (chassis.com).
  robot.chassis_com = btVector3(m.chassis_com.x(), m.chassis_com.y(), 0);
  robot.chassis_shape->addChildShape(
      btTransform(btMatrix3x3::getIdentity(),
                  btVector3(-robot.chassis_com.x(), -robot.chassis_com.y(), m.ground_clearance + 0.5 * h - m.com_height)),
      robot.chassis_cylinder.get());
  btRigidBody::btRigidBodyConstructionInfo chassis_info(
      m.chassis_mass, nullptr, robot.chassis_shape.get(), btVector3(i_tilt, i_tilt, i_yaw));
  chassis_info.m_friction = kChassisFriction;
  chassis_info.m_restitution = 0;
  robot.chassis = std::make_unique<btRigidBody>(chassis_info);
  robot.chassis->setUserIndex(kChassisBody);
  // Robots often stand still between commands; a sleeping body would ignore the next one.
  robot.chassis->setActivationState(DISABLE_DEACTIVATION);
  world_->addRigidBody(robot.chassis.get(), kChassisGroup, kWallGroup | kChassisGroup);

  // Wheels: spheres on the floor; body x axis = axle, so the inertia is diagonal.
  robot.wheel_shape = std::make_unique<btSphereShape>(m.wheel_radius);
  for (int i = 0; i < n; ++i) {
    const double c = std::cos(m.wheel_angles[i]), s = std::sin(m.wheel_angles[i]);
    robot.axles.emplace_back(-c, -s, 0);

    btRigidBody::btRigidBodyConstructionInfo wheel_info(
        m.wheel_mass, nullptr, robot.wheel_shape.get(),
        btVector3(m.wheel_spin_inertia, m.wheel_inertia_diametral, m.wheel_inertia_diametral));
    wheel_info.m_restitution = 0;
    auto wheel = std::make_unique<btRigidBody>(wheel_info);
    wheel->setUserIndex(kWheelBody);
    wheel->setUserPointer(&robot.contacts[i]);
    wheel->setActivationState(DISABLE_DEACTIVATION);
    // Bullet's implicit gyroscopic step damps the yaw a wheel shares with the chassis
    // once it spins fast (4% less yaw speed after a 1 s spin-up to 36 rad/s); the term it
    // models only shifts hinge torques about horizontal axes, so wheels go without it.
    wheel->setFlags(wheel->getFlags() & ~BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY);
    world_->addRigidBody(wheel.get(), kWheelGroup, kFloorGroup);

    // Hinge frames: z = the axle a_i, x = up. In the chassis frame y is then d_i; in the
    // wheel's frame (x = a_i, z = up when level) the same axes read z = x_w, x = z_w.
    btTransform in_chassis, in_wheel;
    in_chassis.setOrigin(btVector3(m.wheel_distance * c, m.wheel_distance * s, m.wheel_radius - m.com_height) -
                         robot.chassis_com);
    in_chassis.getBasis().setValue(0, -s, -c,  //
                                   0, c, -s,   //
                                   1, 0, 0);
    in_wheel.setOrigin(btVector3(0, 0, 0));
    in_wheel.getBasis().setValue(0, 0, 1,   //
                                 0, -1, 0,  //
                                 1, 0, 0);
    auto hinge = std::make_unique<btHingeConstraint>(*robot.chassis, *wheel, in_chassis,
                                                     in_wheel, /*useReferenceFrameA=*/false);
    world_->addConstraint(hinge.get(), /*disableCollisionsBetweenLinkedBodies=*/true);
    robot.wheels.push_back(std::move(wheel));
    robot.hinges.push_back(std::move(hinge));
  }
}

void BulletOmniEngine::BuildWalls(const FieldModel& field) {
  const double t = field.wall_thickness, height = field.wall_height;  // m
  const double half_l = 0.5 * field.length, half_w = 0.5 * field.width;  // m
  struct Box {
    btVector3 centre, half_extents;  // m
  };
  // The long walls reach over the corners so that no gap is left there.
  const Box boxes[] = {
      {{half_l + 0.5 * t, 0, 0.5 * height}, {0.5 * t, half_w + t, 0.5 * height}},
      {{-half_l - 0.5 * t, 0, 0.5 * height}, {0.5 * t, half_w + t, 0.5 * height}},
      {{0, half_w + 0.5 * t, 0.5 * height}, {half_l + t, 0.5 * t, 0.5 * height}},
      {{0, -half_w - 0.5 * t, 0.5 * height}, {half_l + t, 0.5 * t, 0.5 * height}},
  };
  for (const Box& box : boxes) {
    auto shape = std::make_unique<btBoxShape>(box.half_extents);
    // The default 4 cm margin would exceed a thin wall's half thickness.
    shape->setMargin(std::min({0.01, 0.25 * t, 0.25 * height}));
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shape.get());
    info.m_startWorldTransform.setOrigin(box.centre);
    info.m_friction = kChassisFriction;
    info.m_restitution = 0;
    auto wall = std::make_unique<btRigidBody>(info);
    wall->setUserIndex(kStaticBody);
    world_->addRigidBody(wall.get(), kWallGroup, kChassisGroup);
    wall_shapes_.push_back(std::move(shape));
    walls_.push_back(std::move(wall));
  }
}

BulletOmniEngine::Robot& BulletOmniEngine::CheckedRobot(int robot) const {
  if (robot < 0 || robot >= num_robots())
    throw std::invalid_argument("bullet engine: robot index " + std::to_string(robot) +
                                " out of range (" + std::to_string(num_robots()) + " robots)");
  return *robots_[robot];
}

void BulletOmniEngine::SetState(int robot_index, const OmniBodyState& state) {
  Robot& robot = CheckedRobot(robot_index);
  const OmniModel& m = robot.model;
  const int n = m.num_wheels();
  if (state.wheel_speeds.size() != n)
    throw std::invalid_argument("bullet engine: " + std::to_string(state.wheel_speeds.size()) +
                                " wheel speeds for a robot with " + std::to_string(n) +
                                " wheels");

  const double theta = state.pose.theta;  // rad
  // chassis_pose: the robot's centre at com_height; the chassis body sits at its centre
  // of mass, chassis_com from there.
  const btTransform chassis_pose(btQuaternion(btVector3(0, 0, 1), theta),
                                 btVector3(state.pose.x, state.pose.y, m.com_height));
  const Twist2 v_field = BodyToField(state.velocity, theta);
  const btVector3 velocity(v_field.vx, v_field.vy, 0);  // m/s
  const btVector3 spin(0, 0, v_field.omega);             // rad/s
  const btVector3 com = chassis_pose.getBasis() * robot.chassis_com;  // m, field frame
  PlaceBody(robot.chassis.get(), btTransform(chassis_pose.getBasis(), chassis_pose.getOrigin() + com),
            velocity + spin.cross(com), spin);

  for (int i = 0; i < n; ++i) {
    const double alpha = m.wheel_angles[i];  // rad
    const btVector3 offset =
        chassis_pose.getBasis() * btVector3(m.wheel_distance * std::cos(alpha),
                                            m.wheel_distance * std::sin(alpha),
                                            m.wheel_radius - m.com_height);  // m, field frame
    const btTransform wheel_pose(btQuaternion(btVector3(0, 0, 1), theta + alpha + kPi),
                                 chassis_pose.getOrigin() + offset);
    const btVector3 axle = chassis_pose.getBasis() * robot.axles[i];
    PlaceBody(robot.wheels[i].get(), wheel_pose, velocity + spin.cross(offset),
              spin + axle * state.wheel_speeds[i]);
  }

  ForgetContacts(robot);
}

void BulletOmniEngine::ForgetContacts(Robot& robot) {
  // Manifolds hold contact points and warm-start impulses; without them the next step
  // starts as in a freshly built world.
  btOverlappingPairCache* pairs = world_->getPairCache();
  pairs->cleanProxyFromPairs(robot.chassis->getBroadphaseHandle(), dispatcher_.get());
  for (auto& wheel : robot.wheels)
    pairs->cleanProxyFromPairs(wheel->getBroadphaseHandle(), dispatcher_.get());
  for (WheelContact& contact : robot.contacts) contact.step = -1;
  solver_->reset();
}

// Snapshot layout: per body (chassis, then wheels) the origin (3), the basis row by row
// (9; a quaternion would not round-trip bit for bit) and the linear and angular
// velocities (3 + 3); then per wheel its floor contact's warm-start impulses (3) and
// whether they are current (1). Contacts with walls and other robots are not kept.
constexpr int kBodySnapshotSize = 18;
constexpr int kWheelContactSnapshotSize = 4;

void BulletOmniEngine::MoveRobot(int robot_index, const Pose2& pose) {
  Robot& robot = CheckedRobot(robot_index);
  const Pose2 from = GetState(robot_index).pose;
  const btMatrix3x3 turn(btQuaternion(btVector3(0, 0, 1), pose.theta - from.theta));
  const btVector3 old_centre(from.x, from.y, 0), new_centre(pose.x, pose.y, 0);
  auto move = [&](btRigidBody* body) {
    const btTransform& t = body->getWorldTransform();
    const btTransform moved(turn * t.getBasis(), new_centre + turn * (t.getOrigin() - old_centre));
    PlaceBody(body, moved, turn * body->getLinearVelocity(), turn * body->getAngularVelocity());
  };
  move(robot.chassis.get());
  for (auto& wheel : robot.wheels) move(wheel.get());
}

std::vector<double> BulletOmniEngine::SaveExact(int robot_index) const {
  const Robot& robot = CheckedRobot(robot_index);
  std::vector<double> out;
  out.reserve(robot.wheels.size() * (kBodySnapshotSize + kWheelContactSnapshotSize) +
              kBodySnapshotSize);
  auto save = [&out](const btRigidBody& body) {
    const btTransform& pose = body.getWorldTransform();
    for (int i = 0; i < 3; ++i) out.push_back(pose.getOrigin()[i]);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out.push_back(pose.getBasis()[r][c]);
    for (int i = 0; i < 3; ++i) out.push_back(body.getLinearVelocity()[i]);
    for (int i = 0; i < 3; ++i) out.push_back(body.getAngularVelocity()[i]);
  };
  save(*robot.chassis);
  for (const auto& wheel : robot.wheels) save(*wheel);
  for (const WheelContact& contact : robot.contacts) {
    out.insert(out.end(), {contact.normal_impulse, contact.rolling_impulse,
                           contact.roller_impulse, contact.step == world_->step() ? 1.0 : 0.0});
  }
  return out;
}

void BulletOmniEngine::RestoreExact(int robot_index, const std::vector<double>& snapshot) {
  Robot& robot = CheckedRobot(robot_index);
  if (snapshot.size() != robot.wheels.size() * (kBodySnapshotSize + kWheelContactSnapshotSize) +
                              kBodySnapshotSize)
    throw std::invalid_argument("bullet engine: snapshot of the wrong size");
  const double* v = snapshot.data();
  auto restore = [&v](btRigidBody* body) {
    const btTransform pose(btMatrix3x3(v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11]),
                           btVector3(v[0], v[1], v[2]));
    PlaceBody(body, pose, btVector3(v[12], v[13], v[14]), btVector3(v[15], v[16], v[17]));
    v += kBodySnapshotSize;
  };
  restore(robot.chassis.get());
  for (auto& wheel : robot.wheels) restore(wheel.get());
  ForgetContacts(robot);
  for (WheelContact& contact : robot.contacts) {
    contact.normal_impulse = v[0];
    contact.rolling_impulse = v[1];
    contact.roller_impulse = v[2];
    contact.step = v[3] != 0 ? world_->step() : -1;
    v += kWheelContactSnapshotSize;
  }
}

OmniBodyState BulletOmniEngine::GetState(int robot_index) const {
  const Robot& robot = CheckedRobot(robot_index);
  // The world transform, not the motion state: bodies have none, and nothing is
  // interpolated between steps.
  const btTransform& pose = robot.chassis->getWorldTransform();
  const btMatrix3x3& basis = pose.getBasis();
  // The robot's centre: the chassis body's origin less its centre-of-mass offset.
  const btVector3 com = basis * robot.chassis_com;  // m, field frame
  OmniBodyState state;
  state.pose.x = pose.getOrigin().x() - com.x();
  state.pose.y = pose.getOrigin().y() - com.y();
  state.pose.theta = std::atan2(basis[1][0], basis[0][0]);
  const btVector3 v = robot.chassis->getLinearVelocity() - robot.chassis->getAngularVelocity().cross(com);
  const btVector3& spin = robot.chassis->getAngularVelocity();
  state.velocity = FieldToBody(Twist2{v.x(), v.y(), spin.z()}, state.pose.theta);

  GetWheelSpeeds(robot_index, &state.wheel_speeds);
  return state;
}

void BulletOmniEngine::GetWheelSpeeds(int robot_index, Eigen::VectorXd* out) const {
  const Robot& robot = CheckedRobot(robot_index);
  const btMatrix3x3& basis = robot.chassis->getWorldTransform().getBasis();
  const btVector3& spin = robot.chassis->getAngularVelocity();
  const int n = robot.model.num_wheels();
  out->resize(n);
  for (int i = 0; i < n; ++i) {
    const btVector3 axle = basis * robot.axles[i];
    (*out)[i] = (robot.wheels[i]->getAngularVelocity() - spin).dot(axle);
  }
}

void BulletOmniEngine::SetWheelTorques(int robot_index, const Eigen::VectorXd& torques) {
  Robot& robot = CheckedRobot(robot_index);
  if (torques.size() != robot.model.num_wheels())
    throw std::invalid_argument("bullet engine: " + std::to_string(torques.size()) +
                                " wheel torques for a robot with " +
                                std::to_string(robot.model.num_wheels()) + " wheels");
  robot.torques = torques;
}

void BulletOmniEngine::Step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw std::invalid_argument("bullet engine: step " + std::to_string(dt) + " s must be > 0");
  // Bullet clears forces after every step, so the held torques are applied anew.
  for (auto& robot : robots_) {
    const btMatrix3x3& basis = robot->chassis->getWorldTransform().getBasis();
    for (int i = 0; i < robot->torques.size(); ++i) {
      if (robot->torques[i] == 0) continue;
      const btVector3 torque = (basis * robot->axles[i]) * robot->torques[i];  // N·m
      robot->wheels[i]->applyTorque(torque);
      robot->chassis->applyTorque(-torque);
    }
  }
  // maxSubSteps = 0: one step of exactly dt, no fixed-step accumulator, no interpolation.
  world_->stepSimulation(dt, 0);
}

}  // namespace

std::unique_ptr<OmniEngine> MakeBulletOmniEngine(const std::vector<OmniModel>& robots,
                                                 const FieldModel& field) {
  return std::make_unique<BulletOmniEngine>(robots, field);
}

}  // namespace twinsim

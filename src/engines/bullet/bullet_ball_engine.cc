#include "engines/bullet/bullet_ball_engine.h"

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace twinsim {
namespace {

// The robots' hulls are shrunk by their collision margin, which Bullet adds back around
// them: the surface the ball meets is the model's outline (corners rounded by 0.5 mm).
constexpr double kHullMargin = 0.0005;  // m
constexpr double kWallMargin = 0.001;   // m, inside the boxes
// Slower approaches do not bounce (Bullet's default is 0.2 m/s): as in the ODE engine.
constexpr double kBounceVelocity = 0.02;  // m/s
constexpr int kSolverIterations = 20;

class BulletBallEngine : public BallEngine {
 public:
  BulletBallEngine(const BallModel& ball, const std::vector<OmniModel>& robots, const FieldModel& field);
  ~BulletBallEngine() override;
  BulletBallEngine(const BulletBallEngine&) = delete;
  BulletBallEngine& operator=(const BulletBallEngine&) = delete;

  std::string name() const override { return "bullet"; }
  void SetBall(const BallState& state) override;
  BallState GetBall() const override;
  void SetRobot(int robot, const Pose2& pose, const Twist2& velocity) override;
  void AddBallForce(const Eigen::Vector3d& force, const Eigen::Vector3d& torque) override;
  void Step(double dt) override;

 private:
  struct Chassis {
    std::unique_ptr<btConvexHullShape> shape;
    std::unique_ptr<btRigidBody> body;
    Pose2 pose;
    Twist2 velocity;  // field frame
  };
  btRigidBody* AddStatic(btCollisionShape* shape, const btTransform& where, double friction, double restitution);

  BallModel model_;
  std::unique_ptr<btDefaultCollisionConfiguration> config_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btDbvtBroadphase> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> solver_;
  std::unique_ptr<btDiscreteDynamicsWorld> world_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<btRigidBody>> statics_;
  std::unique_ptr<btSphereShape> ball_shape_;
  std::unique_ptr<btRigidBody> ball_;
  std::vector<Chassis> robots_;
};

BulletBallEngine::BulletBallEngine(const BallModel& ball, const std::vector<OmniModel>& robots,
                                   const FieldModel& field)
    : model_(ball) {
  std::string why;
  if (!ball.IsValid(&why)) throw std::invalid_argument("bullet ball engine: " + why);
  config_ = std::make_unique<btDefaultCollisionConfiguration>();
  dispatcher_ = std::make_unique<btCollisionDispatcher>(config_.get());
  broadphase_ = std::make_unique<btDbvtBroadphase>();
  solver_ = std::make_unique<btSequentialImpulseConstraintSolver>();
  world_ = std::make_unique<btDiscreteDynamicsWorld>(dispatcher_.get(), broadphase_.get(), solver_.get(),
                                                     config_.get());
  const Eigen::Vector3d gravity = field.Gravity();
  world_->setGravity(btVector3(gravity.x(), gravity.y(), gravity.z()));
  btContactSolverInfo& info = world_->getSolverInfo();
  info.m_numIterations = kSolverIterations;
  info.m_restitutionVelocityThreshold = kBounceVelocity;

  btTransform at;
  at.setIdentity();
  shapes_.push_back(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0));
  AddStatic(shapes_.back().get(), at, ball.sliding_friction, ball.floor_restitution);
  if (field.walls) {
    const double hw = field.wall_height;
    for (const auto& b : field.WallBoxes()) {
      auto box = std::make_unique<btBoxShape>(btVector3(0.5 * b[2], 0.5 * b[3], 0.5 * hw));
      box->setMargin(kWallMargin);
      at.setOrigin(btVector3(b[0], b[1], 0.5 * hw));
      AddStatic(box.get(), at, ball.robot_friction, ball.restitution);
      shapes_.push_back(std::move(box));
    }
  }

  for (const OmniModel& m : robots) {
    Chassis c;
    c.shape = std::make_unique<btConvexHullShape>();
    const std::vector<Eigen::Vector2d> outline = ChassisOutline(m);
    const double r = m.chassis_radius, front = m.FrontDistance();
    for (double z : {m.ground_clearance + kHullMargin, m.ground_clearance + m.chassis_height - kHullMargin}) {
      for (const Eigen::Vector2d& p : outline) {
        // Pull each point in by the margin along the arc's radius or, on the front, along x.
        Eigen::Vector2d q = p * (r - kHullMargin) / r;
        q.x() = std::min(q.x(), front - kHullMargin);
        c.shape->addPoint(btVector3(q.x(), q.y(), z), false);
      }
    }
    c.shape->recalcLocalAabb();
    c.shape->setMargin(kHullMargin);
    btRigidBody::btRigidBodyConstructionInfo ci(0, nullptr, c.shape.get());
    ci.m_friction = ball.robot_friction;
    ci.m_restitution = ball.restitution;
    c.body = std::make_unique<btRigidBody>(ci);
    c.body->setCollisionFlags(c.body->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    c.body->setActivationState(DISABLE_DEACTIVATION);
    world_->addRigidBody(c.body.get());
    robots_.push_back(std::move(c));
  }
  for (std::size_t i = 0; i < robots_.size(); ++i)
    SetRobot(static_cast<int>(i), Pose2{0, 1e3 + 10.0 * static_cast<double>(i), 0}, Twist2{});

  ball_shape_ = std::make_unique<btSphereShape>(ball.radius);
  btVector3 inertia;
  ball_shape_->calculateLocalInertia(ball.mass, inertia);  // 2/5 m r^2
  btRigidBody::btRigidBodyConstructionInfo ci(ball.mass, nullptr, ball_shape_.get(), inertia);
  ci.m_friction = 1;     // times each surface's coefficient
  ci.m_restitution = 1;  // likewise
  ci.m_linearDamping = 0;
  ci.m_angularDamping = 0;
  ball_ = std::make_unique<btRigidBody>(ci);
  ball_->setActivationState(DISABLE_DEACTIVATION);
  world_->addRigidBody(ball_.get());
  BallState rest;
  rest.position.z() = ball.radius;
  SetBall(rest);
}

BulletBallEngine::~BulletBallEngine() {
  world_->removeRigidBody(ball_.get());
  for (Chassis& c : robots_) world_->removeRigidBody(c.body.get());
  for (auto& s : statics_) world_->removeRigidBody(s.get());
}

btRigidBody* BulletBallEngine::AddStatic(btCollisionShape* shape, const btTransform& where, double friction,
                                         double restitution) {
  btRigidBody::btRigidBodyConstructionInfo ci(0, nullptr, shape);
  ci.m_startWorldTransform = where;
  ci.m_friction = friction;
  ci.m_restitution = restitution;
  statics_.push_back(std::make_unique<btRigidBody>(ci));
  world_->addRigidBody(statics_.back().get());
  return statics_.back().get();
}

void BulletBallEngine::SetBall(const BallState& s) {
  btTransform t;
  t.setIdentity();
  t.setOrigin(btVector3(s.position.x(), s.position.y(), s.position.z()));
  ball_->setWorldTransform(t);
  ball_->setInterpolationWorldTransform(t);
  ball_->setLinearVelocity(btVector3(s.velocity.x(), s.velocity.y(), s.velocity.z()));
  ball_->setAngularVelocity(btVector3(s.spin.x(), s.spin.y(), s.spin.z()));
  ball_->setInterpolationLinearVelocity(ball_->getLinearVelocity());
  ball_->setInterpolationAngularVelocity(ball_->getAngularVelocity());
  ball_->clearForces();
  // Manifolds hold contact points and warm-start impulses; without them the next step
  // starts as in a freshly built world.
  world_->getPairCache()->cleanProxyFromPairs(ball_->getBroadphaseHandle(), dispatcher_.get());
  solver_->reset();
}

BallState BulletBallEngine::GetBall() const {
  const btVector3& p = ball_->getWorldTransform().getOrigin();
  const btVector3& v = ball_->getLinearVelocity();
  const btVector3& w = ball_->getAngularVelocity();
  BallState s;
  s.position = Eigen::Vector3d(p.x(), p.y(), p.z());
  s.velocity = Eigen::Vector3d(v.x(), v.y(), v.z());
  s.spin = Eigen::Vector3d(w.x(), w.y(), w.z());
  return s;
}

void BulletBallEngine::SetRobot(int robot, const Pose2& pose, const Twist2& velocity) {
  if (robot < 0 || robot >= static_cast<int>(robots_.size()))
    throw std::invalid_argument("bullet ball engine: robot index " + std::to_string(robot) + " out of range");
  Chassis& c = robots_[static_cast<std::size_t>(robot)];
  c.pose = pose;
  c.velocity = velocity;
  btTransform t(btQuaternion(btVector3(0, 0, 1), pose.theta), btVector3(pose.x, pose.y, 0));
  c.body->setWorldTransform(t);
  c.body->setInterpolationWorldTransform(t);
  c.body->setLinearVelocity(btVector3(velocity.vx, velocity.vy, 0));
  c.body->setAngularVelocity(btVector3(0, 0, velocity.omega));
}

void BulletBallEngine::AddBallForce(const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
  ball_->applyCentralForce(btVector3(force.x(), force.y(), force.z()));
  ball_->applyTorque(btVector3(torque.x(), torque.y(), torque.z()));
}

void BulletBallEngine::Step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("bullet ball engine: step must be > 0");
  // Bullet takes a kinematic body's velocity from its last two transforms: the one a
  // step ago goes in as the interpolation transform, so the chassis stands at its pose
  // and moves with its velocity.
  for (Chassis& c : robots_) {
    const Pose2 before{c.pose.x - c.velocity.vx * dt, c.pose.y - c.velocity.vy * dt,
                       c.pose.theta - c.velocity.omega * dt};
    c.body->setInterpolationWorldTransform(
        btTransform(btQuaternion(btVector3(0, 0, 1), before.theta), btVector3(before.x, before.y, 0)));
  }
  world_->stepSimulation(dt, 0);
  ball_->clearForces();
}

}  // namespace

std::unique_ptr<BallEngine> MakeBulletBallEngine(const BallModel& ball, const std::vector<OmniModel>& robots,
                                                 const FieldModel& field) {
  return std::make_unique<BulletBallEngine>(ball, robots, field);
}

}  // namespace twinsim

#include "engines/ode/ode_ball_engine.h"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <ode/ode.h>

#include "engines/ode/ode_world.h"

namespace twinsim {
namespace {

// Contacts are hard (ODE's rigid constraint with a tiny CFM) so that a bounce is exactly
// the restitution; penetration is pushed out at no more than this speed, so that fixing
// a step's overlap never throws the ball off (a 46 g ball meeting a wall at 6 m/s is
// found up to 5 mm inside it at 1/1200 s).
constexpr double kMaxCorrectingSpeed = 0.05;  // m/s
constexpr double kContactErp = 0.2;
constexpr double kContactCfm = 1e-9;
// Slower approaches do not bounce: a ball resting on the floor stays in contact.
constexpr double kBounceVelocity = 0.02;  // m/s
constexpr int kMaxContacts = 4;
// Below this slip speed friction direction 1 follows the ball's velocity (or x).
constexpr double kMinSlip = 1e-9;  // m/s

// A robot's chassis: a kinematic body with a convex prism whose vertex and plane arrays
// ODE reads in place, so they live here.
struct OdeChassis {
  dBodyID body = nullptr;
  dGeomID geom = nullptr;
  double reach = 0;               // m, centre to the farthest point of the outline
  double height = 0;              // m, the body's origin above the floor: the prism's middle, inside it as ODE wants
  std::vector<dReal> planes;      // 4 per face: outward normal, distance
  std::vector<dReal> points;      // 3 per vertex
  std::vector<unsigned> polygons; // per face: count, vertex indices (counter-clockwise from outside)
};

class OdeBallEngine : public BallEngine {
 public:
  OdeBallEngine(const BallModel& ball, const std::vector<OmniModel>& robots, const FieldModel& field);
  ~OdeBallEngine() override;
  OdeBallEngine(const OdeBallEngine&) = delete;
  OdeBallEngine& operator=(const OdeBallEngine&) = delete;

  std::string name() const override { return "ode"; }
  void SetBall(const BallState& state) override;
  BallState GetBall() const override;
  void SetRobot(int robot, const Pose2& pose, const Twist2& velocity) override;
  void AddBallForce(const Eigen::Vector3d& force, const Eigen::Vector3d& torque) override;
  void Step(double dt) override;

 private:
  void BuildChassis(OdeChassis* chassis, const OmniModel& model);
  // Adds the contacts of the ball with `other` (a geom of `body`, null: static).
  void Touch(dGeomID other, dBodyID body, double friction, double restitution);

  BallModel model_;
  std::unique_ptr<OdeWorld> ode_world_;
  dWorldID world_ = nullptr;
  dBodyID ball_ = nullptr;
  dGeomID ball_geom_ = nullptr;
  dGeomID floor_ = nullptr;
  std::vector<dGeomID> walls_;
  std::vector<OdeChassis> robots_;
  dJointGroupID contacts_ = nullptr;
};

OdeBallEngine::OdeBallEngine(const BallModel& ball, const std::vector<OmniModel>& robots, const FieldModel& field)
    : model_(ball) {
  std::string why;
  if (!ball.IsValid(&why)) throw std::invalid_argument("ode ball engine: " + why);
  EnsureOdeInitialized();
  ode_world_ = std::make_unique<OdeWorld>();
  world_ = ode_world_->id();
  const Eigen::Vector3d gravity = field.Gravity();
  SetUpFieldWorld(world_, gravity.x(), gravity.y(), gravity.z());
  dWorldSetContactMaxCorrectingVel(world_, kMaxCorrectingSpeed);
  dWorldSetContactSurfaceLayer(world_, 0);
  contacts_ = dJointGroupCreate(0);

  ball_ = dBodyCreate(world_);
  dMass mass;
  dMassSetSphereTotal(&mass, ball.mass, ball.radius);  // I = 2/5 m r^2
  dBodySetMass(ball_, &mass);
  ball_geom_ = dCreateSphere(nullptr, ball.radius);
  dGeomSetBody(ball_geom_, ball_);
  floor_ = dCreatePlane(nullptr, 0, 0, 1, 0);

  if (field.walls) {
    const double hw = field.wall_height;
    for (const auto& b : field.WallBoxes()) {
      dGeomID wall = dCreateBox(nullptr, b[2], b[3], hw);
      dGeomSetPosition(wall, b[0], b[1], 0.5 * hw);
      walls_.push_back(wall);
    }
  }
  robots_.resize(robots.size());
  for (std::size_t i = 0; i < robots.size(); ++i) BuildChassis(&robots_[i], robots[i]);
  // Out of the way until placed.
  for (std::size_t i = 0; i < robots.size(); ++i)
    SetRobot(static_cast<int>(i), Pose2{0, 1e3 + 10.0 * static_cast<double>(i), 0}, Twist2{});
  BallState rest;
  rest.position.z() = ball.radius;
  SetBall(rest);
}

OdeBallEngine::~OdeBallEngine() {
  dJointGroupDestroy(contacts_);
  for (OdeChassis& c : robots_) dGeomDestroy(c.geom);
  for (dGeomID w : walls_) dGeomDestroy(w);
  dGeomDestroy(floor_);
  dGeomDestroy(ball_geom_);
}

void OdeBallEngine::BuildChassis(OdeChassis* c, const OmniModel& model) {
  const std::vector<Eigen::Vector2d> outline = ChassisOutline(model);
  const auto k = static_cast<unsigned>(outline.size());
  // Relative to the body's origin, the middle of the prism.
  c->height = model.ground_clearance + 0.5 * model.chassis_height;
  const double top = 0.5 * model.chassis_height, bottom = -top;
  for (double z : {bottom, top}) {
    for (const Eigen::Vector2d& p : outline) c->points.insert(c->points.end(), {p.x(), p.y(), z});
  }
  for (unsigned i = 0; i < k; ++i) {
    const unsigned j = (i + 1) % k;
    const Eigen::Vector2d e = outline[j] - outline[i];
    const Eigen::Vector2d n = Eigen::Vector2d(e.y(), -e.x()).normalized();
    c->planes.insert(c->planes.end(), {n.x(), n.y(), 0, n.dot(outline[i])});
    c->polygons.insert(c->polygons.end(), {4u, i, j, k + j, k + i});
    c->reach = std::max(c->reach, outline[i].norm());
  }
  c->planes.insert(c->planes.end(), {0, 0, 1, top});
  c->polygons.push_back(k);
  for (unsigned i = 0; i < k; ++i) c->polygons.push_back(k + i);
  c->planes.insert(c->planes.end(), {0, 0, -1, top});
  c->polygons.push_back(k);
  for (unsigned i = k; i-- > 0;) c->polygons.push_back(i);

  c->body = dBodyCreate(world_);
  dBodySetKinematic(c->body);
  c->geom = dCreateConvex(nullptr, c->planes.data(), k + 2, c->points.data(), 2 * k, c->polygons.data());
  dGeomSetBody(c->geom, c->body);
}

void OdeBallEngine::SetBall(const BallState& s) {
  dBodySetPosition(ball_, s.position.x(), s.position.y(), s.position.z());
  const dQuaternion identity = {1, 0, 0, 0};
  dBodySetQuaternion(ball_, identity);
  dBodySetLinearVel(ball_, s.velocity.x(), s.velocity.y(), s.velocity.z());
  dBodySetAngularVel(ball_, s.spin.x(), s.spin.y(), s.spin.z());
  dBodySetForce(ball_, 0, 0, 0);
  dBodySetTorque(ball_, 0, 0, 0);
  dBodyEnable(ball_);
}

BallState OdeBallEngine::GetBall() const {
  const dReal* p = dBodyGetPosition(ball_);
  const dReal* v = dBodyGetLinearVel(ball_);
  const dReal* w = dBodyGetAngularVel(ball_);
  BallState s;
  s.position = Eigen::Vector3d(p[0], p[1], p[2]);
  s.velocity = Eigen::Vector3d(v[0], v[1], v[2]);
  s.spin = Eigen::Vector3d(w[0], w[1], w[2]);
  return s;
}

void OdeBallEngine::SetRobot(int robot, const Pose2& pose, const Twist2& velocity) {
  if (robot < 0 || robot >= static_cast<int>(robots_.size()))
    throw std::invalid_argument("ode ball engine: robot index " + std::to_string(robot) + " out of range");
  const OdeChassis& c = robots_[static_cast<std::size_t>(robot)];
  dBodyID body = c.body;
  dBodySetPosition(body, pose.x, pose.y, c.height);
  const dQuaternion q = {std::cos(0.5 * pose.theta), 0, 0, std::sin(0.5 * pose.theta)};
  dBodySetQuaternion(body, q);
  dBodySetLinearVel(body, velocity.vx, velocity.vy, 0);
  dBodySetAngularVel(body, 0, 0, velocity.omega);
}

void OdeBallEngine::AddBallForce(const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
  dBodyAddForce(ball_, force.x(), force.y(), force.z());
  dBodyAddTorque(ball_, torque.x(), torque.y(), torque.z());
}

void OdeBallEngine::Touch(dGeomID other, dBodyID body, double friction, double restitution) {
  dContactGeom found[kMaxContacts];
  const int n = dCollide(ball_geom_, other, kMaxContacts, found, sizeof(dContactGeom));
  const dReal* v = dBodyGetLinearVel(ball_);
  const dReal* w = dBodyGetAngularVel(ball_);
  for (int i = 0; i < n; ++i) {
    dContact contact{};
    contact.geom = found[i];
    // ODE's normal points from the second geom into the first (the ball): the slip of
    // the ball's surface at the contact relative to the other body, across the normal.
    const Eigen::Vector3d normal(found[i].normal[0], found[i].normal[1], found[i].normal[2]);
    const Eigen::Vector3d r = -model_.radius * normal;
    Eigen::Vector3d slip = Eigen::Vector3d(v[0], v[1], v[2]) + Eigen::Vector3d(w[0], w[1], w[2]).cross(r);
    if (body) {
      dVector3 vb;
      dBodyGetPointVel(body, found[i].pos[0], found[i].pos[1], found[i].pos[2], vb);
      slip -= Eigen::Vector3d(vb[0], vb[1], vb[2]);
    }
    slip -= slip.dot(normal) * normal;
    // Friction direction 1 along the slip makes ODE's per-direction Coulomb limit the
    // true one (a pyramid would allow sqrt(2) mu N on a diagonal slide).
    Eigen::Vector3d dir = slip;
    if (dir.norm() < kMinSlip) dir = Eigen::Vector3d::UnitX() - normal.x() * normal;
    if (dir.norm() < kMinSlip) dir = Eigen::Vector3d::UnitY() - normal.y() * normal;
    dir.normalize();
    contact.fdir1[0] = dir.x();
    contact.fdir1[1] = dir.y();
    contact.fdir1[2] = dir.z();
    contact.surface = BouncingSurface(friction, restitution, kBounceVelocity, kContactErp, kContactCfm);
    contact.surface.mode |= dContactFDir1;
    dJointID joint = dJointCreateContact(world_, contacts_, &contact);
    dJointAttach(joint, ball_, body);
  }
}

void OdeBallEngine::Step(double dt) {
  if (!(dt > 0) || !std::isfinite(dt)) throw std::invalid_argument("ode ball engine: step must be > 0");
  EnsureOdeInitialized();
  // The ball against everything in a fixed order: the contacts, and so the result,
  // depend on the geometry alone.
  Touch(floor_, nullptr, model_.sliding_friction, model_.floor_restitution);
  for (dGeomID wall : walls_) Touch(wall, nullptr, model_.robot_friction, model_.restitution);
  const dReal* p = dBodyGetPosition(ball_);
  for (const OdeChassis& c : robots_) {
    const dReal* q = dBodyGetPosition(c.body);
    if (std::hypot(p[0] - q[0], p[1] - q[1]) > c.reach + 2 * model_.radius) continue;
    Touch(c.geom, c.body, model_.robot_friction, model_.restitution);
  }
  dWorldStep(world_, dt);
  dJointGroupEmpty(contacts_);
}

}  // namespace

std::unique_ptr<BallEngine> MakeOdeBallEngine(const BallModel& ball, const std::vector<OmniModel>& robots,
                                              const FieldModel& field) {
  return std::make_unique<OdeBallEngine>(ball, robots, field);
}

}  // namespace twinsim

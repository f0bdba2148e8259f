#include "estimation/omni_observer.h"

#include <Eigen/Dense>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/engine_names.h"
#include "core/error.h"
#include "core/math_constants.h"
#include "robots/omni/omni_kinematics.h"
#include "sim/newtonian_omni_backend.h"

namespace twinsim {

bool OmniObserverOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& s) {
    if (why) *why = s;
    return false;
  };
  if (!(gate > 0)) return fail("observer gate must be positive");
  if (reacquire_after < 1) return fail("observer reacquire_after must be 1 or more");
  if (!(initial_speed_sd > 0) || !(initial_turn_sd > 0)) return fail("observer initial spreads must be positive");
  if (!(speed_step > 0) || !(turn_step > 0)) return fail("observer finite-difference steps must be positive");
  if (jacobian_interval < 1) return fail("observer jacobian_interval must be 1 or more");
  return true;
}

namespace {

// A Newtonian backend (analytic, ode, bullet) for the filter: the observer lies below the
// backends' factory (learning/'s residual track runs it), so it builds its own.
std::unique_ptr<OmniBackend> MakeFilterBackend(const OmniModel& model, const std::string& name, const FrameTiming& timing) {
  if (!IsKnownEngine(name)) {
    throw InputError("the observer needs a backend that holds the robot's velocity (analytic, ode, bullet); " + name +
                     (name == "learned" ? " predicts from its own window of measured poses" : " is none of them"));
  }
  FieldModel field;
  field.walls = false;  // a logged robot may be anywhere
  return MakeNewtonianOmniBackend(name, {model}, field, timing);
}

}  // namespace

namespace {

using WithoutDrift = Eigen::Matrix<double, kObserverStatesWithoutDrift, kObserverStatesWithoutDrift>;

// P <- F P F^T + Q, kept symmetric, on a filter of N states.
template <int N>
void PropagateCovariance(const Eigen::Matrix<double, N, N>& f, const Eigen::Matrix<double, N, N>& q,
                         Eigen::Matrix<double, N, N>* p) {
  *p = f * *p * f.transpose() + q;
  *p = 0.5 * (*p + p->transpose()).eval();
}

// The covariance's parts over one frame (OmniCovariancePart): each carried by F, and Q
// split by the states it drives (the pose and the model's velocity; the slip; the drift).
// Without a drift (`drift` false) its part stays zero, as its states do in P.
void PropagateParts(const ObserverMatrix& f, const ObserverMatrix& q, bool drift,
                    std::array<ObserverMatrix, kCovarianceParts>* parts) {
  constexpr int kVelocityEnd = 6, kSlipEnd = 9;
  for (int i = 0; i < kCovarianceParts; ++i) {
    ObserverMatrix& p = (*parts)[static_cast<std::size_t>(i)];
    p = f * p * f.transpose();
    if (i == kProcessNoise) p.topLeftCorner<kVelocityEnd, kVelocityEnd>() += q.topLeftCorner<kVelocityEnd, kVelocityEnd>();
    if (i == kDrivingNoise) p.block<3, 3>(kVelocityEnd, kVelocityEnd) += q.block<3, 3>(kVelocityEnd, kVelocityEnd);
    if (i == kDrift && drift) p.block<3, 3>(kSlipEnd, kSlipEnd) += q.block<3, 3>(kSlipEnd, kSlipEnd);
    p = 0.5 * (p + p.transpose()).eval();
  }
}

// The correction of a filter of N states by a pose innovation nu (S's factor `llt`, R
// the pose's covariance), in Joseph's form: P <- (I - K H) P (I - K H)^T + K R K^T, H the
// first three states. Returns K nu.
template <int N>
Eigen::Matrix<double, N, 1> CorrectCovariance(const Eigen::LLT<Eigen::Matrix3d>& llt, const Eigen::Vector3d& nu,
                                              const Eigen::Matrix3d& r, Eigen::Matrix<double, N, N>* p) {
  const Eigen::Matrix<double, N, 3> gain = llt.solve(p->template topLeftCorner<N, 3>().transpose()).transpose();
  const Eigen::Matrix<double, N, 1> delta = gain * nu;
  Eigen::Matrix<double, N, N> ikh = Eigen::Matrix<double, N, N>::Identity();
  ikh.template leftCols<3>() -= gain;
  *p = ikh * *p * ikh.transpose() + gain * r * gain.transpose();
  *p = 0.5 * (*p + p->transpose()).eval();
  return delta;
}

FrameTiming TimingAt(double frame_rate) {
  if (!(frame_rate > 0)) throw InputError("observer: the frame rate must be positive");
  FrameTiming timing;
  timing.frame_rate = frame_rate;
  timing.physics_substeps = DefaultPhysicsSubsteps(frame_rate);
  return timing;
}

}  // namespace

Eigen::Matrix3d MeasurementCovariance(const OmniModel& model) {
  const double sxy = model.ObserverNoiseXy(), sth = model.ObserverNoiseTheta();
  Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
  r.diagonal() << sxy * sxy, sxy * sxy, sth * sth;
  return r;
}

OmniObserver::OmniObserver(const OmniModel& model, const std::string& backend, double frame_rate,
                           const OmniObserverOptions& options)
    : OmniObserver(model, MakeFilterBackend(model, backend, TimingAt(frame_rate)), options) {}

OmniObserver::OmniObserver(const OmniModel& model, std::unique_ptr<OmniBackend> backend,
                           const OmniObserverOptions& options)
    : model_(model), options_(options), backend_(std::move(backend)) {
  if (std::string why; !options.IsValid(&why)) throw InputError(why);
  if (!backend_->has_velocity_state()) {
    throw InputError("the observer needs a backend that holds the robot's velocity (analytic, ode, bullet); " +
                     backend_->name() + " predicts from its own window of measured poses");
  }
  const FrameTiming& timing = backend_->timing();
  dt_ = timing.frame_dt();
  wheels_from_body_ = OmniKinematics(model_).wheels_from_body();
  if (backend_->name() != "analytic") twin_ = MakeFilterBackend(model, "analytic", timing);
  delay_ = model.command_delay_frames + model.vision_delay_frames;
  sent_.assign(static_cast<std::size_t>(delay_ + 1), Twist2{});
  r_ = MeasurementCovariance(model);
  slip_decay_ = std::exp(-dt_ / model.driving_noise.correlation_time);
  has_drift_ = model.driving_noise.drift.any();
  drift_decay_ = std::exp(-dt_ / model.driving_noise.drift.correlation_time);
}

OmniObserver::~OmniObserver() = default;

ObserverMatrix OmniObserver::InitialCovariance() const {
  ObserverMatrix p = ObserverMatrix::Zero();
  p.topLeftCorner<3, 3>() = r_;
  p(3, 3) = p(4, 4) = options_.initial_speed_sd * options_.initial_speed_sd;
  p(5, 5) = options_.initial_turn_sd * options_.initial_turn_sd;
  for (int a = 0; a < 3; ++a) {
    p(6 + a, 6 + a) = std::pow(model_.driving_noise.sd[static_cast<std::size_t>(a)], 2);
    p(9 + a, 9 + a) = std::pow(model_.driving_noise.drift.sd[static_cast<std::size_t>(a)], 2);
  }
  return p;
}

ObserverMatrix OmniObserver::ProcessNoise(double theta, double speed, double acceleration, double turn_rate) const {
  const double c = std::cos(theta), s = std::sin(theta);
  const Eigen::Vector3d along[3] = {{c, s, 0}, {-s, c, 0}, {0, 0, 1}};
  ObserverMatrix q = ObserverMatrix::Zero();
  const double dt = dt_, dt2 = dt * dt / 2, dt3 = dt * dt * dt / 3;
  for (int a = 0; a < 3; ++a) {
    const double qa = std::pow(model_.observer.process_noise[static_cast<std::size_t>(a)], 2);
    const Eigen::Vector3d& g = along[a];
    q.topLeftCorner<3, 3>() += qa * dt3 * g * g.transpose();
    q.block<3, 1>(0, 3 + a) += qa * dt2 * g;
    q.block<1, 3>(3 + a, 0) += qa * dt2 * g.transpose();
    q(3 + a, 3 + a) += qa * dt;
    q(6 + a, 6 + a) = std::pow(model_.driving_noise.Spread(a, speed, acceleration, turn_rate), 2) * (1 - slip_decay_ * slip_decay_);
    q(9 + a, 9 + a) = std::pow(model_.driving_noise.drift.sd[static_cast<std::size_t>(a)], 2) * (1 - drift_decay_ * drift_decay_);
  }
  return q;
}

void OmniObserver::Step(const Twist2& acting, bool jacobian) {
  const Pose2 p0 = backend_->pose(0);
  const Twist2 v0 = backend_->velocity(0);
  const bool difference = jacobian && (frames_since_jacobian_ < 0 || frames_since_jacobian_ + 1 >= options_.jacobian_interval);
  OmniBackendState before;
  if (difference) before = backend_->Save();
  backend_->StepFrame({acting});
  last_acting_ = acting;
  Pose2 base_pose = backend_->pose(0);  // the model's own step, for F
  Twist2 base_velocity = backend_->velocity(0);
  const double acceleration = std::hypot(base_velocity.vx - v0.vx, base_velocity.vy - v0.vy) / dt_;  // m/s^2
  // The slip and the drift move the body on, unseen by the wheels; then they decay.
  const double c = std::cos(p0.theta), sn = std::sin(p0.theta);
  Pose2 moved = base_pose;
  const Eigen::Vector3d unseen = Unseen();
  if (!unseen.isZero()) {
    moved.x += dt_ * (c * unseen[0] - sn * unseen[1]);
    moved.y += dt_ * (sn * unseen[0] + c * unseen[1]);
    moved.theta += dt_ * unseen[2];
    backend_->MoveBody(0, moved);
  }
  slip_ *= slip_decay_;
  drift_ *= drift_decay_;
  if (!jacobian) return;
  // F's model-velocity columns by forward differences of the model over the frame.
  if (difference) {
    OmniBackend* fd = backend_.get();
    OmniBackendState after;
    if (twin_) {
      for (OmniRobotState& r : before.robots) r.engine_snapshot.clear();  // the twin's engine has no 3D state
      fd = twin_.get();
      fd->Restore(before);
      fd->StepFrame({acting});
      base_pose = fd->pose(0);
      base_velocity = fd->velocity(0);
    } else {
      after = backend_->Save();
    }
    const double steps[3] = {options_.speed_step, options_.speed_step, options_.turn_step};
    for (int j = 0; j < 3; ++j) {
      fd->Restore(before);
      Twist2 v = v0;
      (j == 0 ? v.vx : j == 1 ? v.vy : v.omega) += steps[j];
      fd->SetVelocity(0, v);
      fd->StepFrame({acting});
      const Pose2 p = fd->pose(0);
      const Twist2 w = fd->velocity(0);
      const double h = steps[j];
      velocity_columns_.col(j) << (p.x - base_pose.x) / h, (p.y - base_pose.y) / h,
          WrapAngle(p.theta - base_pose.theta) / h, (w.vx - base_velocity.vx) / h, (w.vy - base_velocity.vy) / h,
          (w.omega - base_velocity.omega) / h;
    }
    if (!twin_) backend_->Restore(after);
    frames_since_jacobian_ = 0;
  } else {
    ++frames_since_jacobian_;
  }
  Propagate(p0, c, sn, moved, difference, v0, acceleration);
}

void OmniObserver::Propagate(const Pose2& p0, double c, double sn, const Pose2& moved, bool difference, const Twist2& v0,
                             double acceleration) {
  ObserverMatrix f = ObserverMatrix::Identity();
  f(0, 2) = -(moved.y - p0.y);
  f(1, 2) = moved.x - p0.x;
  // The differenced columns are in the robot frame of their frame: turn them to this one.
  const double turn = p0.theta - jacobian_theta_;
  if (difference) jacobian_theta_ = p0.theta;
  f.block<6, 3>(0, 3) = velocity_columns_;
  if (!difference && turn != 0) {
    const double ct = std::cos(turn), st = std::sin(turn);
    for (int j = 0; j < 3; ++j) {
      const double x = f(0, 3 + j), y = f(1, 3 + j);
      f(0, 3 + j) = ct * x - st * y;
      f(1, 3 + j) = st * x + ct * y;
    }
  }
  // The slip's and the drift's columns: they move the pose along the robot's axes, and
  // decay.
  for (int first : {6, 9}) {
    f(0, first) = dt_ * c;
    f(0, first + 1) = -dt_ * sn;
    f(1, first) = dt_ * sn;
    f(1, first + 1) = dt_ * c;
    f(2, first + 2) = dt_;
    for (int a = 0; a < 3; ++a) f(first + a, first + a) = first == 6 ? slip_decay_ : drift_decay_;
  }
  const ObserverMatrix q = ProcessNoise(p0.theta, std::hypot(v0.vx, v0.vy), acceleration, v0.omega);
  if (parts_) PropagateParts(f, q, has_drift_, parts_);
  if (has_drift_) {
    PropagateCovariance<kObserverStates>(f, q, &p_);
  } else {
    // Without a drift, on the first nine states alone (its rows and columns stay zero).
    WithoutDrift p = p_.topLeftCorner<kObserverStatesWithoutDrift, kObserverStatesWithoutDrift>();
    PropagateCovariance<kObserverStatesWithoutDrift>(f.topLeftCorner<kObserverStatesWithoutDrift, kObserverStatesWithoutDrift>(),
                                                     q.topLeftCorner<kObserverStatesWithoutDrift, kObserverStatesWithoutDrift>(), &p);
    p_.topLeftCorner<kObserverStatesWithoutDrift, kObserverStatesWithoutDrift>() = p;
  }
}

Twist2 OmniObserver::Acting(int ahead, const std::vector<Twist2>& planned) const {
  // Step `ahead` (0 = from the newest frame to the next) acts on the command sent at
  // frame newest + ahead - D: sent_ holds newest - D .. newest.
  if (ahead <= delay_) return sent_[static_cast<std::size_t>(ahead)];
  const int i = ahead - delay_ - 1;  // into planned
  if (planned.empty()) return sent_.back();
  return planned[static_cast<std::size_t>(std::min<int>(i, static_cast<int>(planned.size()) - 1))];
}

void OmniObserver::Restart(const Pose2& pose, const Twist2& velocity) {
  backend_->MoveBody(0, pose);
  backend_->SetVelocity(0, velocity);
  slip_.setZero();
  drift_.setZero();
  p_ = InitialCovariance();
  refused_in_a_row_ = 0;
}

bool OmniObserver::AddFrame(const std::optional<Pose2>& camera, const Twist2& command) {
  if (camera && !IsFinite(*camera)) throw InputError("observer: a camera pose is not finite");
  if (!IsFinite(command)) throw InputError("observer: a command is not finite");
  ++frame_;
  if (!started_) {
    sent_.pop_front();
    sent_.push_back(command);
    if (!camera) return false;
    Begin(*camera, Twist2{});
    return true;
  }
  // From the previous frame to this one, under the command sent D frames before it.
  const Twist2 acting = sent_.front();
  sent_.pop_front();
  sent_.push_back(command);
  Advance(acting, true);
  if (!camera) return false;
  return CorrectFrame(*camera);
}

void OmniObserver::Advance(const Twist2& acting, bool covariance) {
  Step(acting, covariance);
  const Pose2 pose = backend_->pose(0);
  const Twist2 velocity = backend_->velocity(0);
  if (!IsFinite(pose) || !IsFinite(velocity) || !p_.allFinite() || !slip_.allFinite() || !drift_.allFinite()) {
    std::ostringstream msg;
    msg << "observer: model " << model_.name << " on " << backend_->name() << " diverged at frame " << frame_;
    throw CheckFailed(msg.str());
  }
}

void OmniObserver::Begin(const Pose2& pose, const Twist2& velocity) {
  backend_->Reset(0, pose, velocity);
  slip_.setZero();
  drift_.setZero();
  frames_since_jacobian_ = -1;
  p_ = InitialCovariance();
  refused_in_a_row_ = 0;
  started_ = true;
}

void OmniObserver::Start(const Pose2& pose, const Twist2& velocity) {
  if (!IsFinite(pose) || !IsFinite(velocity)) throw InputError("observer: a start pose or velocity is not finite");
  ++frame_;
  Begin(pose, velocity);
}

void OmniObserver::PredictFrame(const Twist2& acting, bool covariance) {
  if (!started_) throw std::logic_error("OmniObserver::PredictFrame before Start");
  if (!IsFinite(acting)) throw InputError("observer: a command is not finite");
  ++frame_;
  Advance(acting, covariance);
}

bool OmniObserver::CorrectFrame(const Pose2& camera) {
  if (!started_) throw std::logic_error("OmniObserver::CorrectFrame before Start");
  if (!IsFinite(camera)) throw InputError("observer: a camera pose is not finite");
  const Pose2 pose = backend_->pose(0);
  const Twist2 velocity = backend_->velocity(0);
  const Eigen::Vector3d nu(camera.x - pose.x, camera.y - pose.y, WrapAngle(camera.theta - pose.theta));
  const Eigen::Matrix3d s = p_.topLeftCorner<3, 3>() + r_;
  const Eigen::LLT<Eigen::Matrix3d> llt(s);
  const double nis = nu.dot(llt.solve(nu));
  stats_.last_nis = nis;
  if (!(nis <= options_.gate)) {
    ++stats_.refused;
    if (++refused_in_a_row_ >= options_.reacquire_after) {
      ++stats_.restarts;
      Restart(camera, velocity);
    }
    return false;
  }
  refused_in_a_row_ = 0;
  Eigen::Matrix<double, kObserverStates, 1> delta = Eigen::Matrix<double, kObserverStates, 1>::Zero();
  if (has_drift_) {
    delta = CorrectCovariance<kObserverStates>(llt, nu, r_, &p_);
  } else {
    WithoutDrift p = p_.topLeftCorner<kObserverStatesWithoutDrift, kObserverStatesWithoutDrift>();
    delta.head<kObserverStatesWithoutDrift>() = CorrectCovariance<kObserverStatesWithoutDrift>(llt, nu, r_, &p);
    p_.topLeftCorner<kObserverStatesWithoutDrift, kObserverStatesWithoutDrift>() = p;
  }
  backend_->MoveBody(0, Pose2{pose.x + delta[0], pose.y + delta[1], pose.theta + delta[2]});
  backend_->SetVelocity(0, Twist2{velocity.vx + delta[3], velocity.vy + delta[4], velocity.omega + delta[5]});
  slip_ += delta.segment<3>(6);
  drift_ += delta.tail<3>();

  const double log_det = 2 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
  ++stats_.updates;
  stats_.nis_sum += nis;
  stats_.log_likelihood += -0.5 * (nis + log_det + 3 * std::log(2 * kPi));
  return true;
}

void OmniObserver::MovePose(const Pose2& pose) {
  if (!started_) throw std::logic_error("OmniObserver::MovePose before Start");
  backend_->MoveBody(0, pose);
}

OmniObserverState OmniObserver::Save() const {
  OmniObserverState s;
  s.backend = backend_->Save();
  s.covariance = p_;
  s.slip = slip_;
  s.drift = drift_;
  s.velocity_columns = velocity_columns_;
  s.jacobian_theta = jacobian_theta_;
  s.frames_since_jacobian = frames_since_jacobian_;
  s.last_acting = last_acting_;
  s.sent = sent_;
  s.started = started_;
  s.frame = frame_;
  s.refused_in_a_row = refused_in_a_row_;
  s.stats = stats_;
  return s;
}

void OmniObserver::Restore(const OmniObserverState& s) {
  backend_->Restore(s.backend);
  p_ = s.covariance;
  slip_ = s.slip;
  drift_ = s.drift;
  velocity_columns_ = s.velocity_columns;
  jacobian_theta_ = s.jacobian_theta;
  frames_since_jacobian_ = s.frames_since_jacobian;
  last_acting_ = s.last_acting;
  sent_ = s.sent;
  started_ = s.started;
  frame_ = s.frame;
  refused_in_a_row_ = s.refused_in_a_row;
  stats_ = s.stats;
}

bool ParseOmniReplayState(const std::string& word, OmniReplayState* state, std::string* why, const std::string& what) {
  for (int k = 0; k < static_cast<int>(std::size(kOmniReplayStateWords)); ++k) {
    if (word != kOmniReplayStateWords[k]) continue;
    *state = static_cast<OmniReplayState>(k);
    return true;
  }
  if (why) *why = what + " must be observer or tracker, got '" + word + "'";
  return false;
}

OmniEstimate OmniObserver::Estimate() const {
  OmniEstimate e;
  if (!started_) return e;
  e.frame = frame_;
  e.pose = backend_->pose(0);
  e.model_velocity = backend_->velocity(0);
  e.slip = Twist2{slip_[0], slip_[1], slip_[2]};
  e.drift = Twist2{drift_[0], drift_[1], drift_[2]};
  const Eigen::Vector3d unseen = Unseen();
  e.velocity = Twist2{e.model_velocity.vx + unseen[0], e.model_velocity.vy + unseen[1], e.model_velocity.omega + unseen[2]};
  e.covariance = p_;
  return e;
}

OmniPrediction OmniObserver::PredictAhead(int k, const std::vector<Twist2>& planned, bool covariance, bool parts) {
  if (!started_) throw std::logic_error("OmniObserver::PredictAhead before the first camera pose");
  OmniPrediction out;
  if (k <= 0) return out;
  covariance = covariance || parts;
  const OmniObserverState saved = Save();
  std::array<ObserverMatrix, kCovarianceParts> split;
  if (parts) {
    split.fill(ObserverMatrix::Zero());
    split[kStartEstimate] = p_;
    if (!has_drift_) {  // P's drift states are not propagated without a drift: nor are they here
      split[kStartEstimate].bottomRows<kObserverStates - kObserverStatesWithoutDrift>().setZero();
      split[kStartEstimate].rightCols<kObserverStates - kObserverStatesWithoutDrift>().setZero();
    }
    parts_ = &split;
  }
  // parts_ points into this frame: cleared however the prediction ends.
  struct ClearParts {
    std::array<ObserverMatrix, kCovarianceParts>** parts;
    ~ClearParts() { *parts = nullptr; }
  } clear_parts{&parts_};
  double last_theta = backend_->pose(0).theta;
  // The mean distance from the seen inputs along the frames predicted so far.
  const OmniSeenInputs& seen = model_.observer.seen_inputs;
  double distance_sum = 0;
  for (int j = 0; j < k; ++j) {
    Step(Acting(j, planned), covariance);
    Pose2 pose = backend_->pose(0);
    pose.theta = last_theta = last_theta + WrapAngle(pose.theta - last_theta);
    out.pose.push_back(pose);
    if (covariance) {
      double distance = 0;
      if (!seen.empty()) {
        distance_sum += seen.Distance(InputFeature());
        distance = distance_sum / (j + 1);
        out.input_distance.push_back(distance);
      }
      // The model's safeguard on its intervals (identity without one).
      const std::array<double, 2> scale = model_.observer.IntervalScaleAt(j + 1, distance);
      const Eigen::Vector3d d(scale[0], scale[0], scale[1]);
      out.pose_covariance.push_back(d.asDiagonal() * p_.topLeftCorner<3, 3>() * d.asDiagonal());
      if (parts) {
        OmniCovarianceParts pose_parts;
        for (std::size_t i = 0; i < pose_parts.size(); ++i) pose_parts[i] = split[i].topLeftCorner<3, 3>();
        out.pose_covariance_parts.push_back(pose_parts);
      }
    }
  }
  Restore(saved);
  return out;
}

Eigen::VectorXd OmniObserver::InputFeature() const {
  const Twist2 v = backend_->velocity(0);
  const Eigen::Vector3d unseen = Unseen();
  return SeenInputFeature(wheels_from_body_, last_acting_, Twist2{v.vx + unseen[0], v.vy + unseen[1], v.omega + unseen[2]});
}

}  // namespace twinsim

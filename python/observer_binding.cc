// twinsim.OmniObserver: the omni robot's Kalman filter (estimation/omni_observer.h),
// fed frame by frame from a team's own software (docs/api.md).
#include "python/observer_binding.h"

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <optional>

#include "core/error.h"
#include "estimation/omni_observer.h"

namespace twinsim {
namespace {

py::array_t<double> PoseArray(const Pose2& p) { return py::array_t<double>(3, std::array<double, 3>{p.x, p.y, p.theta}.data()); }
py::array_t<double> TwistArray(const Twist2& v) {
  return py::array_t<double>(3, std::array<double, 3>{v.vx, v.vy, v.omega}.data());
}

Twist2 ToTwist(const std::vector<double>& v, const char* what) {
  if (v.size() != 3) throw InputError(std::string(what) + ": expected 3 numbers (vx, vy, omega), got " + std::to_string(v.size()));
  return Twist2{v[0], v[1], v[2]};
}

}  // namespace

void BindOmniObserver(py::module_& m, const std::function<OmniModel(const py::handle&)>& model_of) {
  py::class_<OmniObserver>(m, "OmniObserver",
                           "The omni robot's Kalman filter: feed camera frames and the commands sent, get the state now "
                           "and the pose k frames ahead (docs/identification.md, 'The observer')")
      .def(py::init([model_of](const py::handle& model, const std::string& backend, double frame_rate) {
             return std::make_unique<OmniObserver>(model_of(model), backend, frame_rate);
           }),
           py::arg("model"), py::arg("backend") = "analytic", py::arg("frame_rate") = 60.0)
      .def(
          "add_frame",
          [](OmniObserver& o, const std::optional<std::vector<double>>& pose, const std::vector<double>& command) {
            std::optional<Pose2> camera;
            if (pose) {
              if (pose->size() != 3) throw InputError("pose: expected 3 numbers (x, y, theta) or None");
              camera = Pose2{(*pose)[0], (*pose)[1], (*pose)[2]};
            }
            return o.AddFrame(camera, ToTwist(command, "command"));
          },
          py::arg("pose"), py::arg("command"),
          "One camera frame: the pose captured in it (None: the camera lost the robot) and the command sent in it; "
          "True when the pose was taken")
      .def_property_readonly("started", &OmniObserver::started)
      .def_property_readonly("delay_frames", &OmniObserver::delay_frames)
      .def_property_readonly(
          "estimate",
          [](const OmniObserver& o) {
            const OmniEstimate e = o.Estimate();
            py::dict d;
            d["frame"] = e.frame;
            d["pose"] = PoseArray(e.pose);
            d["velocity"] = TwistArray(e.velocity);
            d["model_velocity"] = TwistArray(e.model_velocity);
            d["slip"] = TwistArray(e.slip);
            d["drift"] = TwistArray(e.drift);
            const int n = o.has_drift() ? kObserverStates : kObserverStatesWithoutDrift;
            d["covariance"] = Eigen::MatrixXd(e.covariance.topLeftCorner(n, n));
            return d;
          },
          "dict: frame, pose, velocity (model_velocity + slip + drift), model_velocity, slip, drift, covariance (9 x 9; 12 x 12 with a drift)")
      .def(
          "predict",
          [](OmniObserver& o, int k, const std::vector<std::vector<double>>& planned, bool covariance) {
            std::vector<Twist2> commands;
            for (const auto& c : planned) commands.push_back(ToTwist(c, "planned"));
            if (!o.started()) throw InputError("predict: no camera pose yet");
            if (k < 1) throw InputError("predict: k must be 1 or more");
            const OmniPrediction p = o.PredictAhead(k, commands, covariance);
            py::array_t<double> poses({static_cast<py::ssize_t>(k), static_cast<py::ssize_t>(3)});
            auto w = poses.mutable_unchecked<2>();
            for (int j = 0; j < k; ++j) {
              w(j, 0) = p.pose[static_cast<std::size_t>(j)].x;
              w(j, 1) = p.pose[static_cast<std::size_t>(j)].y;
              w(j, 2) = p.pose[static_cast<std::size_t>(j)].theta;
            }
            py::dict d;
            d["pose"] = poses;
            if (covariance) {
              py::array_t<double> c({static_cast<py::ssize_t>(k), static_cast<py::ssize_t>(3), static_cast<py::ssize_t>(3)});
              auto cw = c.mutable_unchecked<3>();
              for (int j = 0; j < k; ++j)
                for (int r = 0; r < 3; ++r)
                  for (int q = 0; q < 3; ++q) cw(j, r, q) = p.pose_covariance[static_cast<std::size_t>(j)](r, q);
              d["pose_covariance"] = c;
            }
            return d;
          },
          py::arg("k"), py::arg("planned") = std::vector<std::vector<double>>{}, py::arg("covariance") = false,
          "The poses of the next k frames (k x 3): the commands already sent act first, then `planned`, then the last "
          "held; with covariance=True their 3 x 3 covariances too (k x 3 x 3)")
      .def_property_readonly("innovations", [](const OmniObserver& o) {
        const OmniInnovationStats& s = o.innovations();
        py::dict d;
        d["updates"] = s.updates;
        d["refused"] = s.refused;
        d["restarts"] = s.restarts;
        d["mean_nis"] = s.updates ? s.nis_sum / s.updates : 0.0;
        d["log_likelihood"] = s.log_likelihood;
        return d;
      });
}

}  // namespace twinsim

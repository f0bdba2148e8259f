#include "control/tracking_plots.h"

#include <stdexcept>

#include "control/writing_task.h"

namespace twinsim {
namespace {

std::vector<double> Column(const Eigen::MatrixXd& m, int j, double scale = 1) {
  std::vector<double> v(static_cast<std::size_t>(m.rows()));
  for (Eigen::Index r = 0; r < m.rows(); ++r) v[static_cast<std::size_t>(r)] = scale * m(r, j);
  return v;
}

std::vector<double> Times(const TrackingTrial& trial) { return std::vector<double>(trial.t.data(), trial.t.data() + trial.t.size()); }

std::string JointUnit(const ArmModel& plant, int j, const char* revolute, const char* prismatic) {
  return plant.joints.at(static_cast<std::size_t>(j)).type == JointType::kPrismatic ? prismatic : revolute;
}

}  // namespace

PathPlot ToolPathPlot(const TrackingTrial& trial, const ArmModel& plant, const Eigen::Vector3d& tool,
                      const std::string& title) {
  PathPlot plot;
  plot.title = title;
  plot.height = 700;
  plot.orientation_every = 0;
  plot.x_label = "-y [m] (seen from behind the arm)";
  plot.y_label = "z [m]";
  auto path = [&](const std::string& name, const Eigen::MatrixXd& q) {
    PlotPath p;
    p.name = name;
    for (Eigen::Index k = 0; k < q.rows(); ++k) {
      const Eigen::Vector3d point = ToolPoint(plant, q.row(k).transpose(), tool);
      p.poses.push_back(Pose2{-point.y(), point.z(), 0});
    }
    plot.paths.push_back(std::move(p));
  };
  path("reference", trial.q_ref);
  path("realised (" + trial.controller + " on " + trial.backend + ")", trial.q);
  return plot;
}

SeriesPlot JointTorquePlot(const TrackingTrial& trial, const ArmModel& plant, int joint, const std::string& title) {
  if (joint < 0 || joint >= plant.dof() || joint >= trial.command.cols())
    throw std::out_of_range("JointTorquePlot: no joint " + std::to_string(joint + 1));
  SeriesPlot plot;
  plot.title = title;
  plot.y_label = JointUnit(plant, joint, "torque [N m]", "force [N]");
  const std::vector<double> t = Times(trial);
  plot.series.push_back({"controller output (sent)", t, Column(trial.command, joint)});
  plot.series.push_back({"model torque", t, Column(trial.model_torque, joint)});
  if ((trial.demand.col(joint) - trial.command.col(joint)).cwiseAbs().maxCoeff() > 0)
    plot.series.push_back({"demand before clamping", t, Column(trial.demand, joint)});
  const double limit = plant.joints[static_cast<std::size_t>(joint)].effort_limit;
  if (limit > 0 && !t.empty()) {
    plot.series.push_back({"effort limit", {t.front(), t.back()}, {limit, limit}});
    plot.series.push_back({"-effort limit", {t.front(), t.back()}, {-limit, -limit}});
  }
  return plot;
}

SeriesPlot TrackingErrorPlot(const TrackingTrial& trial, const ArmModel& plant, const std::string& title) {
  SeriesPlot plot;
  plot.title = title;
  bool prismatic = false, revolute = false;
  for (const ArmJoint& j : plant.joints) (j.type == JointType::kPrismatic ? prismatic : revolute) = true;
  plot.y_label = prismatic && revolute ? "q_ref - q [mrad or mm]" : prismatic ? "q_ref - q [mm]" : "q_ref - q [mrad]";
  const Eigen::MatrixXd error = trial.q_ref - trial.q;
  const std::vector<double> t = Times(trial);
  for (int j = 0; j < error.cols(); ++j) {
    const std::string& name = plant.joints.at(static_cast<std::size_t>(j)).name;
    plot.series.push_back({"joint " + std::to_string(j + 1) + (name.empty() ? "" : " (" + name + ")"), t,
                           Column(error, j, 1000)});
  }
  return plot;
}

}  // namespace twinsim

#include "analysis/arm_model_comparison.h"

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "analysis/arm_simulation_score.h"
#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "learning/arm_features.h"
#include "sim/arm_simulation.h"

namespace twinsim {

std::string ModelGap::BriefReport() const {
  std::ostringstream s;
  s << name << ": ";
  if (!finite) return s.str() + "diverged";
  Eigen::Index worst = 0;
  q_rms.maxCoeff(&worst);
  s << std::setprecision(3) << "q RMS " << q_rms.maxCoeff() * 1e3 << " mrad (joint " << worst + 1 << "), max "
    << q_max.maxCoeff() * 1e3 << " mrad, torque RMS " << tau_rms.maxCoeff() << " N·m";
  return s.str();
}

ModelGap CompareTrials(const std::string& name, const TrackingTrial& measured, const TrackingTrial& candidate) {
  if (measured.q.rows() != candidate.q.rows() || measured.q.cols() != candidate.q.cols())
    throw std::invalid_argument("CompareTrials: runs of different length or joint count");
  ModelGap gap;
  gap.name = name;
  const Eigen::MatrixXd dq = candidate.q - measured.q;
  const Eigen::MatrixXd dtau = candidate.command - measured.command;
  const double rows = static_cast<double>(dq.rows());
  gap.q_rms = (dq.array().square().colwise().sum() / rows).sqrt().transpose();
  gap.q_max = dq.cwiseAbs().colwise().maxCoeff().transpose();
  gap.tau_rms = (dtau.array().square().colwise().sum() / rows).sqrt().transpose();
  gap.finite = gap.q_rms.allFinite() && gap.tau_rms.allFinite();
  return gap;
}

std::string WritingComparison::FullReport() const {
  std::ostringstream s;
  s << std::fixed << std::setprecision(3);
  s << "candidate                      joint  q RMS (mrad)  q max (mrad)  tau RMS (N·m)\n";
  for (const ModelGap& g : gaps) {
    if (!g.finite) {
      s << std::left << std::setw(31) << g.name << "diverged\n";
      continue;
    }
    for (Eigen::Index j = 0; j < g.q_rms.size(); ++j) {
      s << std::left << std::setw(31) << (j == 0 ? g.name : "") << std::right << std::setw(5) << j + 1
        << std::setw(14) << g.q_rms[j] * 1e3 << std::setw(14) << g.q_max[j] * 1e3 << std::setw(15) << g.tau_rms[j]
        << "\n";
    }
  }
  return s.str();
}

WritingComparison CompareOnReference(const ArmModel& plant, const ArmModel& hat, const ArmReference& reference,
                                     const std::vector<ArmCandidate>& candidates, const TrackingOptions& options) {
  WritingComparison out;
  out.measured = RunTrackingTrial(plant, hat, reference, options);
  for (const ArmCandidate& c : candidates) {
    try {
      out.runs.push_back(RunTrackingTrial(c.model, c.backend(), hat, reference, options));
      out.gaps.push_back(CompareTrials(c.name, out.measured, out.runs.back()));
    } catch (const CheckFailed&) {
      out.runs.emplace_back();
      ModelGap gap;
      gap.name = c.name;
      gap.finite = false;
      const Eigen::VectorXd nan = Eigen::VectorXd::Constant(hat.dof(), std::numeric_limits<double>::quiet_NaN());
      gap.q_rms = gap.q_max = gap.tau_rms = nan;
      out.gaps.push_back(gap);
    }
  }
  return out;
}

Eigen::MatrixXd PhysicalRolloutError(const ArmModel& model, const std::string& backend, const ArmLog& log, int start,
                                     int steps) {
  if (log.dof != model.dof() || start - model.delay_samples < 0 || steps < 0 || start + steps >= log.rows())
    throw std::invalid_argument("PhysicalRolloutError: the window does not fit the log");
  ArmSimulation sim(model, MakeArmBackend(backend, model));
  Eigen::MatrixXd q;
  SimulateArmFromLog(&sim, log, start, steps, &q);
  return q - log.q.middleRows(start + 1, steps);
}

namespace {

template <typename Rollout>
RolloutStats Stats(int dof, int first, int last, int steps, int every, const Rollout& rollout) {
  if (steps < 1 || every < 1) throw std::invalid_argument("rollout stats: steps and every must be positive");
  RolloutStats stats;
  Eigen::ArrayXd one = Eigen::ArrayXd::Zero(dof), fin = one, max = one;
  for (int s = first; s + steps <= last; s += every) {
    const Eigen::MatrixXd e = rollout(s);
    one += e.row(0).transpose().array().square();
    fin += e.row(steps - 1).transpose().array().square();
    max = max.max(e.row(steps - 1).transpose().array().abs());
    ++stats.runs;
  }
  const double runs = std::max(1, stats.runs);
  stats.one_step_rms = (one / runs).sqrt().matrix();
  stats.final_rms = (fin / runs).sqrt().matrix();
  stats.final_max = max.matrix();
  return stats;
}

}  // namespace

RolloutStats PredictorRolloutStats(const ArmPredictor& predictor, const ArmLog& log, int first, int last, int steps,
                                   int every) {
  const ArmSequence seq = ToArmSequence(log, predictor.layout());
  first = std::max(first, seq.first_known_torque + predictor.layout().history - 1);
  return Stats(log.dof, first, std::min(last, log.rows() - 1), steps, every,
               [&](int s) { return ArmRolloutError(predictor, seq, s, steps); });
}

RolloutStats PhysicalRolloutStats(const ArmModel& model, const std::string& backend, const ArmLog& log, int first,
                                  int last, int steps, int every) {
  first = std::max(first, model.delay_samples);
  return Stats(log.dof, first, std::min(last, log.rows() - 1), steps, every,
               [&](int s) { return PhysicalRolloutError(model, backend, log, s, steps); });
}

}  // namespace twinsim

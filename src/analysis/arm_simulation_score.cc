#include "analysis/arm_simulation_score.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "backends/arm_backend_factory.h"
#include "core/error.h"
#include "core/samples.h"
#include "io/csv_table.h"
#include "sim/arm_simulation.h"

namespace twinsim {

bool ArmSimulationScoreOptions::IsValid(std::string* why) const {
  if (horizons.empty()) {
    *why = "no horizon to score";
    return false;
  }
  for (double h : horizons) {
    if (h == 0 && scored_rows) {
      *why = "the free run (horizon 0) scores every row: it cannot be limited to some";
      return false;
    }
    if (!std::isfinite(h) || h < 0) {
      char text[64];
      std::snprintf(text, sizeof text, "%g", h);
      *why = std::string("a horizon must be 0 (the free run) or a positive number of seconds, not ") + text;
      return false;
    }
  }
  return true;
}

namespace {

// Where each joint of `model` may go in a simulation of `log`: its limits, widened to
// what the log itself reached (a sensor's offset or a limit written a little tight is
// not the model's fault).
void JointRange(const ArmModel& model, const ArmLog& log, Eigen::VectorXd* lower, Eigen::VectorXd* upper) {
  const int n = model.dof();
  lower->resize(n);
  upper->resize(n);
  for (int j = 0; j < n; ++j) {
    const ArmJoint& joint = model.joints[static_cast<std::size_t>(j)];
    (*lower)[j] = std::min(joint.lower, log.q.col(j).minCoeff());
    (*upper)[j] = std::max(joint.upper, log.q.col(j).maxCoeff());
  }
}

// Whether a window's simulated q (its rows start + 1 ..) leaves [lower, upper] anywhere;
// the first such window is recorded in *score.
bool LeavesRange(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, const Eigen::VectorXd& t, int start,
                 const Eigen::MatrixXd& q, ArmHorizonScore* score) {
  for (Eigen::Index r = 0; r < q.rows(); ++r) {
    for (Eigen::Index j = 0; j < q.cols(); ++j) {
      const double v = q(r, j);
      if (v >= lower[j] && v <= upper[j]) continue;
      if (score->left_range_joint < 0) {
        score->left_range_joint = static_cast<int>(j);
        score->left_range_row = start + 1 + static_cast<int>(r);
        score->left_range_t = t[score->left_range_row];
        score->left_range_q = v;
        score->left_range_limit = v < lower[j] ? lower[j] : upper[j];
      }
      return true;
    }
  }
  return false;
}

// `free_run` (if given) receives the simulated q of the last window: the free run's
// whole path when horizon is 0.
ArmHorizonScore ScoreHorizon(ArmSimulation* sim, const ArmLog& log, double horizon,
                             const std::function<bool(int)>& scored_rows, Eigen::MatrixXd* free_run) {
  const int n = log.dof;
  int length = 0;
  const std::vector<int> starts = ArmSimulationWindows(sim->model(), log, horizon, &length, scored_rows);
  ArmHorizonScore score;
  score.horizon = horizon;
  Eigen::VectorXd lower, upper;
  JointRange(sim->model(), log, &lower, &upper);
  Eigen::ArrayXd model = Eigen::ArrayXd::Zero(n), hold = model, velocity = model, sum = model, squares = model;
  Eigen::MatrixXd q(length, n);
  for (int start : starts) {
    if (!SimulateArmFromLog(sim, log, start, length, &q, true)) ++score.diverged;
    if (LeavesRange(lower, upper, log.t, start, q, &score)) ++score.left_range;
    ++score.windows;
    for (int r = 0; r < length; ++r) {
      const int row = start + 1 + r;
      const Eigen::ArrayXd measured = log.q.row(row).transpose().array();
      model += (q.row(r).transpose().array() - measured).square();
      hold += (log.q.row(start).transpose().array() - measured).square();
      velocity += (ConstantVelocityQ(log, start, r + 1).transpose().array() - measured).square();
      sum += measured;
      squares += measured.square();
    }
    score.rows += length;
  }
  if (free_run) *free_run = q;
  const double rows = std::max(1, score.rows);
  score.rmse = (model / rows).sqrt().matrix();
  score.hold = (hold / rows).sqrt().matrix();
  score.constant_velocity = (velocity / rows).sqrt().matrix();
  // ||q - mean q||^2 = sum q^2 - (sum q)^2 / rows
  const Eigen::ArrayXd spread = (squares - sum.square() / rows).max(0).sqrt();
  score.fit.resize(n);
  for (int j = 0; j < n; ++j)
    score.fit[j] = spread[j] > 0 ? 100 * (1 - std::sqrt(model[j]) / spread[j]) : std::nan("");
  return score;
}

}  // namespace

bool SimulateArmFromLog(ArmSimulation* sim, const ArmLog& log, int start, int steps, Eigen::MatrixXd* q,
                        bool hold_on_runaway) {
  return SimulateArmFromState(sim, log, start, steps, log.q.row(start).transpose(), log.qd.row(start).transpose(), q,
                              hold_on_runaway);
}

bool SimulateArmFromState(ArmSimulation* sim, const ArmLog& log, int start, int steps, const Eigen::VectorXd& q0,
                          const Eigen::VectorXd& qd0, Eigen::MatrixXd* q, bool hold_on_runaway) {
  const int n = sim->model().dof(), d = sim->model().delay_samples;
  if (log.dof != n || start - d < 0 || steps < 0 || start + steps >= log.rows())
    throw std::invalid_argument("SimulateArmFromLog: the window does not fit the log");
  q->resize(steps, n);
  sim->Reset(q0, qd0, log.tau.row(start - d).transpose());
  // The commands logged in the D rows before the start are in flight.
  ArmSimulationState state = sim->Save();
  for (int k = start - d + 1; k < start; ++k) state.commands_in_flight.Push(log.tau.row(k).transpose());
  sim->Restore(state);
  int k = start;
  const ArmController replay = [&](double, const Eigen::VectorXd&, const Eigen::VectorXd&) {
    return Eigen::VectorXd(log.tau.row(k++).transpose());
  };
  for (int r = 0; r < steps; ++r) {
    try {
      sim->Step(replay);
      // A state that left the numbers before the step's own checks saw it runs away too.
      if (!sim->backend().q().allFinite())
        throw CheckFailed("the simulated q is not finite at row " + std::to_string(start + 1 + r) + " of " + log.path);
    } catch (const CheckFailed&) {
      if (!hold_on_runaway) throw;
      const Eigen::RowVectorXd last = r > 0 ? Eigen::RowVectorXd(q->row(r - 1)) : q0.transpose();
      for (int rest = r; rest < steps; ++rest) q->row(rest) = last;
      return false;
    }
    q->row(r) = sim->backend().q().transpose();
  }
  return true;
}

Eigen::RowVectorXd ConstantVelocityQ(const ArmLog& log, int start, int ahead) {
  return log.q.row(start) + static_cast<double>(ahead) * log.sample_period * log.qd.row(start);
}

ArmModel ArmModelAtLogPeriod(const ArmModel& model, double period) {
  ArmModel at = model;
  at.delay_samples = static_cast<int>(std::lround(model.delay_samples * model.sample_time / period));
  at.sample_time = period;
  return at;
}

std::vector<int> ArmSimulationWindows(const ArmModel& model, const ArmLog& log, double horizon, int* length,
                                      const std::function<bool(int row)>& scored) {
  const int first = std::max(log.edge_samples, model.delay_samples);
  const int last = log.rows() - 1 - log.edge_samples;
  *length = horizon > 0 ? std::max(1, SamplesIn(horizon, log.sample_period)) : last - first;
  std::vector<int> starts;
  if (last - first < 2) return starts;
  if (!scored || horizon == 0) {
    for (int start = first; start + *length <= last; start += *length) starts.push_back(start);
    return starts;
  }
  // The runs of rows that pass, cut into whole windows from each run's start.
  int run = 0;  // rows that pass, ending at `row`
  for (int row = first; row <= last; ++row) {
    run = scored(row) ? run + 1 : 0;
    if (run == *length + 1) {
      starts.push_back(row - *length);
      run = 1;  // the window's last row may start the next
    }
  }
  return starts;
}

ArmSimulationScore ScoreArmSimulation(const ArmModel& model, const ArmLog& log,
                                      const ArmSimulationScoreOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError("simulation score: " + why);
  CheckArmLogMatchesModel(log, model);
  const ArmModel at = ArmModelAtLogPeriod(model, log.sample_period);
  ArmSimulationScore score;
  score.path = log.path;
  std::vector<double> horizons;
  for (double h : options.horizons) {
    int length = 0;
    if (!ArmSimulationWindows(at, log, h, &length, options.scored_rows).empty()) {
      horizons.push_back(h);
    } else if (!options.drop_long_horizons) {
      const int usable = std::max(0, log.rows() - 1 - 2 * log.edge_samples - at.delay_samples);
      throw InputError(SourceLocation{log.path, 1},
                       "the log's " + std::to_string(usable) + " usable rows (" +
                           FormatCsvNumber(usable * log.sample_period) + " s) are too few for a simulation window" +
                           (h > 0 ? " of " + FormatCsvNumber(h) + " s" : ""));
    }
  }
  if (horizons.empty()) return score;
  ArmSimulation sim(at, MakeArmBackend(options.backend, at, options.backend_options));
  for (double h : horizons) {
    const bool free = h == 0;
    score.horizons.push_back(ScoreHorizon(&sim, log, h, options.scored_rows, free ? &score.free_run : nullptr));
    if (free) {
      int length = 0;
      score.free_run_start = ArmSimulationWindows(at, log, 0, &length).front();
    }
  }
  return score;
}

namespace {

std::string HorizonName(double horizon) {
  if (horizon == 0) return "free run";
  char text[32];
  std::snprintf(text, sizeof text, "%g s", horizon);
  return text;
}

}  // namespace

std::string FormatArmSimulationScores(const std::vector<std::pair<std::string, ArmSimulationScore>>& scores) {
  // One table per log, the models side by side.
  std::vector<std::string> paths;
  std::map<std::string, std::vector<const std::pair<std::string, ArmSimulationScore>*>> by_log;
  for (const auto& s : scores) {
    if (!by_log.count(s.second.path)) paths.push_back(s.second.path);
    by_log[s.second.path].push_back(&s);
  }
  std::string text;
  char cell[160];
  for (const std::string& path : paths) {
    const auto& models = by_log[path];
    const ArmSimulationScore& first = models.front()->second;
    if (first.horizons.empty()) continue;
    text += "\nsimulated from its torques: " + path + " (position RMSE per joint, rad or m; fit in %)\n";
    std::snprintf(cell, sizeof cell, "%-10s %-5s", "horizon", "joint");
    text += cell;
    for (const auto* m : models) {
      std::snprintf(cell, sizeof cell, " %22s", m->first.c_str());
      text += cell;
    }
    std::snprintf(cell, sizeof cell, " %11s %11s\n", "hold", "const. vel.");
    text += cell;
    for (std::size_t h = 0; h < first.horizons.size(); ++h) {
      const ArmHorizonScore& base = first.horizons[h];
      for (Eigen::Index j = 0; j < base.rmse.size(); ++j) {
        std::snprintf(cell, sizeof cell, "%-10s %-5d", j == 0 ? HorizonName(base.horizon).c_str() : "",
                      static_cast<int>(j) + 1);
        text += cell;
        for (const auto* m : models) {
          const ArmHorizonScore& s = m->second.horizons.at(h);
          if (std::isfinite(s.fit[j])) {
            std::snprintf(cell, sizeof cell, " %11.4g (%7.1f%%)", s.rmse[j], s.fit[j]);
          } else {
            std::snprintf(cell, sizeof cell, " %11.4g (%8s)", s.rmse[j], "still");
          }
          text += cell;
        }
        std::snprintf(cell, sizeof cell, " %11.4g %11.4g\n", base.hold[j], base.constant_velocity[j]);
        text += cell;
      }
      // Said plainly: where a model predicts worse than no model at all.
      for (const auto* m : models) {
        const ArmHorizonScore& s = m->second.horizons.at(h);
        const int n = static_cast<int>(s.rmse.size());
        const int hold = static_cast<int>((s.rmse.array() < s.hold.array()).count());
        const int velocity = static_cast<int>((s.rmse.array() < s.constant_velocity.array()).count());
        std::snprintf(cell, sizeof cell, "  %s beats holding on %d of %d joints, constant velocity on %d of %d", m->first.c_str(),
                      hold, n, velocity, n);
        text += cell;
        if (s.diverged > 0) {
          std::snprintf(cell, sizeof cell, "; ran away in %d of %d windows", s.diverged, s.windows);
          text += cell;
        }
        if (s.left_range > 0) {
          std::snprintf(cell, sizeof cell,
                        "; left a joint's range in %d of %d windows, which a real arm cannot (first: joint %d at "
                        "t = %.3f s, at %.4g past its bound %.4g)",
                        s.left_range, s.windows, s.left_range_joint + 1, s.left_range_t, s.left_range_q,
                        s.left_range_limit);
          text += cell;
        }
        text += "\n";
      }
    }
  }
  return text;
}

std::string FormatArmSimulationScoresCsv(const std::vector<std::pair<std::string, ArmSimulationScore>>& scores) {
  std::string csv =
      "log,model,horizon,joint,windows,rows,diverged,rmse,fit,rmse_hold,rmse_constant_velocity,left_range\n";
  for (const auto& [name, score] : scores) {
    for (const ArmHorizonScore& s : score.horizons) {
      for (Eigen::Index j = 0; j < s.rmse.size(); ++j) {
        csv += score.path + "," + name + "," + FormatCsvNumber(s.horizon) + "," + std::to_string(j + 1) + "," +
               std::to_string(s.windows) + "," + std::to_string(s.rows) + "," + std::to_string(s.diverged) + "," +
               FormatCsvNumber(s.rmse[j]) + "," + (std::isfinite(s.fit[j]) ? FormatCsvNumber(s.fit[j]) : "") + "," + FormatCsvNumber(s.hold[j]) +
               "," + FormatCsvNumber(s.constant_velocity[j]) + "," + std::to_string(s.left_range) + "\n";
      }
    }
  }
  return csv;
}

}  // namespace twinsim

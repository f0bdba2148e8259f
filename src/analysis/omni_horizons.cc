#include "analysis/omni_horizons.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "analysis/omni_baselines.h"
#include "core/error.h"
#include "learning/omni_predictor.h"
#include "io/html_text.h"
#include "core/parallel.h"

namespace twinsim {

double HorizonSum::PositionRmse() const { return rows > 0 ? std::sqrt(xy / static_cast<double>(rows)) : 0; }
double HorizonSum::PoseRms() const {
  return rows > 0 ? std::sqrt((forward + sideways + turn) / static_cast<double>(rows)) : 0;
}
void HorizonSum::Add(const std::array<double, 3>& e) {
  xy += e[0] * e[0] + e[1] * e[1];
  forward += e[0] * e[0];
  sideways += e[1] * e[1];
  turn += e[2] * e[2];
  ++rows;
}
void HorizonSum::Add(const HorizonSum& o) {
  xy += o.xy, forward += o.forward, sideways += o.sideways, turn += o.turn;
  rows += o.rows;
}

std::vector<HorizonSum> ScoreHorizon(const std::vector<HorizonStretch>& stretches,
                                     const std::vector<HorizonPredictor>& predictors, int frames,
                                     const HorizonOptions& options) {
  std::vector<std::vector<HorizonSum>> sums(stretches.size(), std::vector<HorizonSum>(predictors.size()));
  ParallelFor(static_cast<int>(stretches.size()), options.threads, [&](int k) {
    const HorizonStretch& s = stretches[static_cast<std::size_t>(k)];
    const OmniLog& log = *s.log;
    std::vector<OmniReplayResult> results;
    for (const HorizonPredictor& p : predictors) {
      if (p.baseline == HorizonPredictor::kConstantVelocity) {
        results.push_back(ConstantVelocityPrediction(log, frames));
      } else if (p.baseline == HorizonPredictor::kIntegratedCommand) {
        results.push_back(IntegratedCommandPrediction(log, frames, options.delay));
      } else {
        OmniReplayOptions o;
        o.backend = options.backend;
        o.horizon = frames;
        o.state = options.state;
        o.stride = std::max(1, frames / 24);
        o.stride_origin = 0;  // every model predicts from the same frames
        if (p.learned) {
          o.backend = "learned";
          o.backend_options.predictor = p.learned;
        }
        results.push_back(ReplayOmniLog(*p.model, log, o));
      }
    }
    std::vector<bool> scored(log.rows.size(), false);
    for (std::size_t row = 0; row < scored.size(); ++row) {
      if (!s.scored[row]) continue;
      const int start = log.FrameIndex(row) - frames;
      if (start < s.min_start_frame) continue;
      std::size_t j = row;
      while (j > 0 && log.FrameIndex(j) > start) --j;
      if (log.FrameIndex(j) != start || j < s.first_start) continue;
      bool all = true;
      for (const OmniReplayResult& r : results) all = all && r.predicted[row];
      scored[row] = all;
    }
    for (std::size_t q = 0; q < predictors.size(); ++q) {
      OmniReplayResult& r = results[q];
      for (std::size_t row = 0; row < scored.size(); ++row) r.predicted[row] = scored[row];
      for (const auto& e : PoseErrorsInRobotFrame(log, r, options.radius).e) sums[static_cast<std::size_t>(k)][q].Add(e);
    }
  });
  std::vector<HorizonSum> out(predictors.size());
  for (const auto& per_stretch : sums)
    for (std::size_t q = 0; q < predictors.size(); ++q) out[q].Add(per_stretch[q]);
  return out;
}

std::shared_ptr<const OmniPredictor> TrainLinearBaseline(const OmniModel& model, const std::vector<OmniLog>& logs,
                                                         std::vector<std::vector<char>> rows,
                                                         std::vector<std::string>* notes) {
  OmniTrainOptions train;
  train.sample_rows = std::move(rows);
  try {
    return std::make_shared<const OmniPredictor>(TrainOmniPredictor(model, logs, train));
  } catch (const std::runtime_error& e) {  // InputError: too few windows in the marked rows
    notes->push_back(std::string("the seed's linear predictor is left out of the every-horizon table: ") + e.what());
    return nullptr;
  }
}

std::vector<HorizonSum> ScoreHorizonWithoutRunaway(const std::vector<HorizonStretch>& stretches,
                                                   std::vector<HorizonPredictor>* predictors, int frames,
                                                   const HorizonOptions& options, std::vector<std::string>* notes) {
  try {
    return ScoreHorizon(stretches, *predictors, frames, options);
  } catch (const CheckFailed& e) {  // the learned baseline ran away on a scored row
    if (predictors->empty() || !predictors->back().learned) throw;
    notes->push_back(std::string("the seed's linear predictor is left out of the every-horizon table: ") + e.what());
    predictors->pop_back();
    return ScoreHorizon(stretches, *predictors, frames, options);
  }
}

std::string LinearPredictorWinsNote(const std::string& trained_on, const std::string& scored_on,
                                    const std::string& model_name, const std::vector<std::string>& labels,
                                    const std::vector<int>& rows, const std::vector<double>& linear,
                                    const std::vector<double>& model) {
  std::string where;
  for (std::size_t h = 0; h < labels.size(); ++h) {
    if (rows[h] == 0 || linear[h] >= model[h]) continue;
    char cell[96];
    std::snprintf(cell, sizeof cell, "%s%s (%.3g against %.3g mm)", where.empty() ? "" : ", ", labels[h].c_str(),
                  1000 * linear[h], 1000 * model[h]);
    where += cell;
  }
  if (where.empty()) return "";
  return "the seed's linear predictor, trained on " + trained_on + ", predicts " + scored_on + " better than " +
         model_name + " at " + where + ": the physics misses something there (train --residual learns it on top)";
}

int HorizonTable::Best(std::size_t h) const {
  if (rows[h] <= 0 || mm[h].empty()) return -1;
  return static_cast<int>(std::min_element(mm[h].begin(), mm[h].end()) - mm[h].begin());
}

std::string FormatHorizonTable(const HorizonTable& t) {
  std::string out;
  char cell[64];
  std::snprintf(cell, sizeof cell, "  %-20s", "");
  out += cell;
  for (const std::string& h : t.horizons) {
    std::snprintf(cell, sizeof cell, " %11s", h.c_str());
    out += cell;
  }
  out += "\n";
  for (std::size_t p = 0; p < t.predictors.size(); ++p) {
    std::snprintf(cell, sizeof cell, "  %-20s", t.predictors[p].c_str());
    out += cell;
    for (std::size_t h = 0; h < t.horizons.size(); ++h) {
      if (t.rows[h] > 0) {
        std::snprintf(cell, sizeof cell, " %10.1f%s", t.mm[h][p], t.Best(h) == static_cast<int>(p) ? "*" : " ");
      } else {
        std::snprintf(cell, sizeof cell, " %10s ", "-");
      }
      out += cell;
    }
    out += "\n";
  }
  std::snprintf(cell, sizeof cell, "  %-20s", "rows");
  out += cell;
  for (int r : t.rows) {
    std::snprintf(cell, sizeof cell, " %10d ", r);
    out += cell;
  }
  return out + "\n";
}

std::string FormatHorizonTableHtml(const HorizonTable& t) {
  std::ostringstream h;
  h << "<table><tr><th>predictor</th>";
  for (const std::string& label : t.horizons) h << "<th>" << HtmlEscape(label) << "</th>";
  h << "</tr>\n";
  char cell[32];
  for (std::size_t p = 0; p < t.predictors.size(); ++p) {
    h << "<tr><td>" << HtmlEscape(t.predictors[p]) << "</td>";
    for (std::size_t k = 0; k < t.horizons.size(); ++k) {
      const bool best = t.Best(k) == static_cast<int>(p);
      std::snprintf(cell, sizeof cell, "%.1f", t.mm[k][p]);
      h << "<td class=n>" << (best ? "<b>" : "") << (t.rows[k] > 0 ? cell : "-") << (best ? "</b>" : "") << "</td>";
    }
    h << "</tr>\n";
  }
  h << "<tr><td class=small>rows</td>";
  for (int r : t.rows) h << "<td class=n>" << r << "</td>";
  h << "</tr>\n</table>\n";
  return h.str();
}

std::vector<std::pair<std::string, int>> ReportHorizons(int first, double frame_period) {
  std::vector<std::pair<std::string, int>> out;
  auto add = [&](const std::string& label, int frames) {
    if (frames < 1) return;
    for (const auto& h : out)
      if (h.second == frames) return;
    out.push_back({label, frames});
  };
  add(std::to_string(first) + (first == 1 ? " frame" : " frames"), first);
  add("0.25 s", static_cast<int>(std::lround(0.25 / frame_period)));
  add("1 s", static_cast<int>(std::lround(1 / frame_period)));
  add("3 s", static_cast<int>(std::lround(3 / frame_period)));
  return out;
}

}  // namespace twinsim

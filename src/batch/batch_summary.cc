#include "batch/batch_summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>

#include "io/html_text.h"
#include "render/plot.h"
#include "render/renderer.h"

namespace twinsim {
namespace {

using Json = nlohmann::ordered_json;

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v == 0 ? 0.0 : v);
  return buf;
}

// A CSV field, quoted when it holds a comma, a quote or a line break (RFC 4180).
std::string Field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::vector<std::string> MetricNames(const std::vector<JobResult>& results) {
  std::vector<std::string> names;
  for (const JobResult& r : results)
    for (const auto& [name, value] : r.metrics)
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  return names;
}

const double* FindMetric(const JobResult& r, const std::string& name) {
  for (const auto& [n, v] : r.metrics)
    if (n == name) return &v;
  return nullptr;
}

bool IsNumber(const std::string& s, double* out) {
  if (s.empty()) return false;
  char* end = nullptr;
  *out = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(*out);
}

}  // namespace

std::string FormatJobResultJson(const SweepJob& job, const JobResult& result) {
  Json j;
  j["job"] = job.id;
  j["seed"] = job.seed;
  Json params = Json::object();
  for (const auto& [name, value] : job.parameters) params[name] = value.text;
  j["parameters"] = params;
  j["status"] = result.status;
  j["error"] = result.error;
  Json metrics = Json::object();
  for (const auto& [name, value] : result.metrics) metrics[name] = value;
  j["metrics"] = metrics;
  j["wall_s"] = result.wall_s;
  return j.dump(2) + "\n";
}

std::optional<JobResult> ParseJobResultJson(const std::string& text, const SweepJob& job) {
  const Json j = Json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object() || !j.contains("job") || j["job"] != job.id || !j.contains("seed") || j["seed"] != job.seed)
    return std::nullopt;
  if (!j.contains("parameters") || !j["parameters"].is_object() || j["parameters"].size() != job.parameters.size())
    return std::nullopt;
  for (const auto& [name, value] : job.parameters)
    if (!j["parameters"].contains(name) || j["parameters"][name] != value.text) return std::nullopt;
  if (!j.contains("status") || !j["status"].is_string() || !j.contains("error") || !j["error"].is_string() ||
      !j.contains("metrics") || !j["metrics"].is_object() || !j.contains("wall_s") || !j["wall_s"].is_number())
    return std::nullopt;
  JobResult r;
  r.index = job.index;
  r.id = job.id;
  r.status = j["status"].get<std::string>();
  if (r.status != "ok" && r.status != "failed") return std::nullopt;
  r.error = j["error"].get<std::string>();
  r.wall_s = j["wall_s"].get<double>();
  for (const auto& [name, value] : j["metrics"].items()) {
    if (!value.is_number()) return std::nullopt;
    r.metrics.emplace_back(name, value.get<double>());
  }
  return r;
}

std::string FormatSummaryCsv(const Sweep& sweep, const std::vector<SweepJob>& jobs,
                             const std::vector<JobResult>& results) {
  const std::vector<std::string> swept = sweep.swept();
  const std::vector<std::string> metrics = MetricNames(results);
  std::string out = "job,seed";
  for (const std::string& s : swept) out += "," + Field(s);
  out += ",status,wall_s";
  for (const std::string& m : metrics) out += "," + Field(m);
  out += ",error\n";
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const SweepJob& job = jobs[i];
    const JobResult& r = results[i];
    out += job.id + "," + std::to_string(job.seed);
    for (const std::string& s : swept) {
      const SweepValue* v = job.Find(s);
      out += "," + Field(v ? v->text : "");
    }
    out += "," + r.status + "," + Number(r.wall_s);
    for (const std::string& m : metrics) {
      const double* v = FindMetric(r, m);
      out += "," + (v ? Number(*v) : std::string());
    }
    out += "," + Field(r.error) + "\n";
  }
  return out;
}

std::string FormatSummaryHtml(const Sweep& sweep, const std::vector<SweepJob>& jobs,
                              const std::vector<JobResult>& results) {
  const std::vector<std::string> swept = sweep.swept();
  const std::vector<std::string> metrics = MetricNames(results);
  int failed = 0;
  for (const JobResult& r : results) failed += r.status != "ok";
  std::string html =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" + HtmlEscape(sweep.name) +
      "</title>\n<style>body{font-family:sans-serif;max-width:1300px;margin:2em auto;}"
      "img{max-width:100%;}table{border-collapse:collapse;}td,th{border:1px solid #ccc;padding:2px 6px;}"
      "</style></head><body>\n<h1>Sweep " + HtmlEscape(sweep.name) + "</h1>\n<p>" + std::to_string(jobs.size()) +
      " jobs of <code>" + HtmlEscape(sweep.command) + "</code>, " + std::to_string(failed) +
      " failed. Swept: " + HtmlEscape(swept.empty() ? std::string("nothing") : [&] {
        std::string s;
        for (const std::string& n : swept) s += (s.empty() ? "" : ", ") + n;
        return s;
      }()) + ". The numbers are in summary.csv; each job's files in jobs/ID/.</p>\n";

  // Numeric swept parameters are x axes; the other swept parameters split the series.
  std::vector<std::string> numeric;
  for (const std::string& s : swept) {
    bool all = true;
    for (const SweepJob& job : jobs) {
      double x;
      const SweepValue* v = job.Find(s);
      if (!v || !IsNumber(v->text, &x)) all = false;
    }
    if (all) numeric.push_back(s);
  }
  if (RenderingCompiled() && !metrics.empty()) {
    std::unique_ptr<Renderer> renderer = MakeDefaultRenderer();
    const bool random = sweep.draws > 0;
    std::vector<std::string> axes = numeric;
    if (axes.empty()) axes.push_back("");  // against the job number
    // compare's metrics SOURCE_H_position_rmse share one plot per horizon, a series per source.
    const auto split = [&](const std::string& m) -> std::pair<std::string, std::string> {
      const std::size_t u = m.find('_');
      if (sweep.command != "compare" || u == std::string::npos) return {m, ""};
      return {m.substr(u + 1), m.substr(0, u)};
    };
    std::vector<std::string> groups;
    for (const std::string& m : metrics)
      if (std::find(groups.begin(), groups.end(), split(m).first) == groups.end()) groups.push_back(split(m).first);
    int drawn = 0;
    for (const std::string& group : groups) {
      for (const std::string& axis : axes) {
        if (drawn >= 48) break;  // a page a browser still opens quickly
        SeriesPlot plot;
        plot.title = group + (axis.empty() ? " by job" : " against " + axis);
        plot.x_label = axis.empty() ? "job" : axis;
        plot.y_label = group;
        plot.width = 900;
        plot.height = 560;
        std::map<std::string, std::vector<std::pair<double, double>>> series;
        for (const std::string& metric : metrics) {
          const auto [metric_group, source] = split(metric);
          if (metric_group != group) continue;
          for (std::size_t i = 0; i < jobs.size(); ++i) {
            const double* y = FindMetric(results[i], metric);
            if (!y) continue;
            double x = static_cast<double>(i);
            if (!axis.empty()) IsNumber(jobs[i].Find(axis)->text, &x);
            std::string label = source;
            for (const std::string& s : swept) {
              if (s == axis || std::find(numeric.begin(), numeric.end(), s) != numeric.end()) continue;
              label += (label.empty() ? "" : ", ") + s + "=" + jobs[i].Find(s)->text;
            }
            series[label.empty() ? metric : label].emplace_back(x, *y);
          }
        }
        if (series.empty()) continue;
        for (auto& [name, points] : series) {
          std::stable_sort(points.begin(), points.end());
          PlotSeries s{name, {}, {}};
          s.points = random || numeric.size() > 1 || axis.empty();
          for (const auto& [x, y] : points) {
            s.x.push_back(x);
            s.y.push_back(y);
          }
          plot.series.push_back(std::move(s));
        }
        html += HtmlImage(RenderSeriesPlot(plot, *renderer), plot.title) + "\n";
        ++drawn;
      }
    }
  } else if (!RenderingCompiled()) {
    html += "<p>(plots not drawn: " + HtmlEscape(kRenderingNotCompiled) + ")</p>\n";
  }
  if (failed > 0) {
    html += "<h2>Failed jobs</h2>\n<table><tr><th>job</th><th>error</th></tr>\n";
    for (std::size_t i = 0; i < jobs.size(); ++i)
      if (results[i].status != "ok")
        html += "<tr><td>" + jobs[i].id + "</td><td>" + HtmlEscape(results[i].error) + "</td></tr>\n";
    html += "</table>\n";
  }
  html += "</body></html>\n";
  return html;
}

}  // namespace twinsim

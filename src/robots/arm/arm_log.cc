#include "robots/arm/arm_log.h"

#include <algorithm>
#include <cmath>
#include <regex>
#include <sstream>

#include "core/error.h"
#include "io/atomic_file.h"
#include "io/csv_table.h"
#include "signal/butterworth.h"

namespace twinsim {
namespace {

// Every step within this fraction of the median step.
constexpr double kStepTolerance = 0.5;

std::string Range(const std::string& prefix, int n) {
  return n == 1 ? prefix + "1" : prefix + "1.." + prefix + std::to_string(n);
}

// The highest k of the columns `prefix`k, and a complaint about gaps (q1, q3 without q2).
int CountColumns(const CsvTable& table, const std::string& prefix) {
  const std::regex pattern(prefix + "([0-9]+)");
  int highest = 0;
  for (const auto& h : table.header) {
    std::smatch m;
    if (!std::regex_match(h, m, pattern)) continue;
    if (m[1].length() > 3 || std::stoi(m[1].str()) > kMaxArmJoints) {
      throw InputError(SourceLocation{table.path, 1}, "column '" + h + "': an arm has at most " +
                                                          std::to_string(kMaxArmJoints) + " joints");
    }
    highest = std::max(highest, std::stoi(m[1].str()));
  }
  for (int k = 1; k <= highest; ++k) {
    const std::string name = prefix + std::to_string(k);
    if (table.Column(name) < 0) {
      throw InputError(SourceLocation{table.path, 1}, "missing column '" + name + "': joint columns must run " +
                                                          Range(prefix, highest) + " without gaps");
    }
  }
  return highest;
}

// The columns prefix1..prefix<dof> as an N x dof matrix.
Eigen::MatrixXd Columns(const CsvTable& table, const std::string& prefix, int dof) {
  Eigen::MatrixXd m(table.rows.size(), dof);
  for (int j = 0; j < dof; ++j) {
    const int c = table.RequireColumn(prefix + std::to_string(j + 1));
    for (std::size_t r = 0; r < table.rows.size(); ++r) m(static_cast<Eigen::Index>(r), j) = table.rows[r][c];
  }
  return m;
}

// Refuses a value no joint produces (a unit mistake, a corrupted file), which would
// overflow the dynamics downstream: |prefixJ| <= most in every row.
void CheckMagnitude(const CsvTable& table, const Eigen::MatrixXd& m, const std::string& prefix, double most) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index r = 0; r < m.rows(); ++r) {
      if (std::abs(m(r, j)) > most) {
        std::ostringstream msg;
        msg << "column '" << prefix << j + 1 << "': " << m(r, j) << " is beyond what a joint reports (at most "
            << most << " in magnitude)";
        throw InputError(SourceLocation{table.path, table.line_of[static_cast<std::size_t>(r)]}, msg.str());
      }
    }
  }
}

}  // namespace

ArmLog ArmLogFromTable(const CsvTable& table, const ArmLogOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  ArmLog log;
  log.path = table.path;
  log.line_of = table.line_of;
  table.RequireColumn("t");
  const int nq = CountColumns(table, "q");
  if (nq == 0) table.RequireColumn("q1");
  const int ntau = CountColumns(table, "tau");
  if (ntau == 0) table.RequireColumn("tau1");
  if (ntau != nq) {
    throw InputError(SourceLocation{table.path, 1}, "the log has " + Range("q", nq) + " but " + Range("tau", ntau) +
                                                        ": every joint needs a position and a torque column");
  }
  log.dof = nq;
  // Optional groups: all of a group or none of it.
  auto optional_group = [&](const std::string& prefix) {
    const int k = CountColumns(table, prefix);
    if (k != 0 && k != nq) {
      throw InputError(SourceLocation{table.path, 1}, "the log has " + Range("q", nq) + " but " + Range(prefix, k) +
                                                          ": give " + Range(prefix, nq) + " or none of them");
    }
    return k != 0;
  };
  log.qd_logged = optional_group("qd");
  log.qdd_logged = optional_group("qdd");
  const bool has_qref = optional_group("qref");
  // Every column the log uses holds numbers (the first bad one in the file is named);
  // any other column is ignored, whatever it holds.
  std::vector<std::string> used = {"t"};
  for (const char* prefix : {"q", "tau", "qd", "qdd", "qref"}) {
    const std::string p = prefix;
    if ((p == "qd" && !log.qd_logged) || (p == "qdd" && !log.qdd_logged) || (p == "qref" && !has_qref)) continue;
    for (int j = 1; j <= nq; ++j) used.push_back(p + std::to_string(j));
  }
  table.RequireColumns(used);

  const int rows = static_cast<int>(table.rows.size());
  if (rows < 3) {
    throw InputError(SourceLocation{table.path, rows == 0 ? 1 : table.line_of[0]},
                     "an arm log needs at least 3 rows, got " + std::to_string(rows));
  }
  const int tc = table.RequireColumn("t");
  log.t.resize(rows);
  for (int r = 0; r < rows; ++r) log.t[r] = table.rows[static_cast<std::size_t>(r)][tc];
  std::vector<double> steps;
  for (int r = 1; r < rows; ++r) {
    const double dt = log.t[r] - log.t[r - 1];
    if (!(dt > 0)) {
      std::ostringstream msg;
      msg << "column 't': time goes backwards or stands still: t = " << log.t[r] << " after " << log.t[r - 1];
      throw InputError(SourceLocation{table.path, table.line_of[static_cast<std::size_t>(r)], 1}, msg.str());
    }
    steps.push_back(dt);
  }
  std::vector<double> sorted = steps;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  log.sample_period = sorted[sorted.size() / 2];
  if (!(log.sample_period >= 1e-6 && log.sample_period <= 1.0)) {
    std::ostringstream msg;
    msg << "column 't': the sample period (the median step) is " << log.sample_period
        << " s; an arm log has 1e-06 to 1 s between samples (is 't' in seconds?)";
    throw InputError(SourceLocation{table.path, table.line_of[0], 1}, msg.str());
  }
  for (std::size_t i = 0; i < steps.size(); ++i) {
    if (std::abs(steps[i] / log.sample_period - 1) > kStepTolerance) {
      std::ostringstream msg;
      msg << "column 't': irregular sampling: " << steps[i] << " s after the previous row, but the median step is "
          << log.sample_period << " s (an arm log must be nearly uniform: every step within 50 % of the median)";
      throw InputError(SourceLocation{table.path, table.line_of[i + 1], 1}, msg.str());
    }
  }

  log.q = Columns(table, "q", nq);
  CheckMagnitude(table, log.q, "q", 1e6);
  log.tau = Columns(table, "tau", nq);
  CheckMagnitude(table, log.tau, "tau", 1e9);
  if (has_qref) {
    log.qref = Columns(table, "qref", nq);
    CheckMagnitude(table, log.qref, "qref", 1e6);
  }
  if (log.qd_logged) {
    log.qd = Columns(table, "qd", nq);
    CheckMagnitude(table, log.qd, "qd", 1e6);
  }
  if (log.qdd_logged) {
    log.qdd = Columns(table, "qdd", nq);
    CheckMagnitude(table, log.qdd, "qdd", 1e9);
  }
  DeriveArmLog(options, &log);
  return log;
}

void DeriveArmLog(const ArmLogOptions& options, ArmLog* log) {
  std::string why;
  if (!options.IsValid(&why)) throw InputError(why);
  if (log->qd_logged && log->qdd_logged) return;
  const int rows = log->rows(), n = log->dof;
  // Stamps jitter around a fixed rate (the controller's); differentiate on the uniform
  // grid of the log's average step rather than on the stamps (signal/butterworth.h).
  const double step = (log->t[rows - 1] - log->t[0]) / (rows - 1);
  const double rate = 1 / step;
  log->derive_cutoff_hz = std::min(options.cutoff_hz, 0.25 * rate);
  const ButterworthFilter filter = DesignButterworthLowPass(options.filter_order, log->derive_cutoff_hz, rate);
  // Odd reflection keeps value and slope at the ends, not curvature: qdd is off there
  // for about four periods of the cut-off (the filter's slowest pole decays e^-10 by then).
  log->edge_samples = std::min(rows / 4, static_cast<int>(std::ceil(4 * rate / log->derive_cutoff_hz)));
  if (!log->qd_logged) log->qd.resize(rows, n);
  if (!log->qdd_logged) log->qdd.resize(rows, n);
  for (int j = 0; j < n; ++j) {
    if (log->qd_logged) {
      // Differentiate the logged velocity once rather than the position twice.
      log->qdd.col(j) = FilteredDerivatives(filter, step, log->qd.col(j)).first;
      continue;
    }
    const SignalDerivatives d = FilteredDerivatives(filter, step, log->q.col(j));
    log->qd.col(j) = d.first;
    if (!log->qdd_logged) log->qdd.col(j) = d.second;
  }
}

bool ArmLogOptions::IsValid(std::string* why) const {
  std::ostringstream s;
  if (!(cutoff_hz > 0 && cutoff_hz <= 1e6)) {
    s << "the cut-off for derived velocities must be positive and at most 1e6 Hz, got " << cutoff_hz << " Hz";
  } else if (filter_order < 1 || filter_order > 16) {
    s << "the filter order must be 1 to 16, got " << filter_order;
  }
  if (why) *why = s.str();
  return s.str().empty();
}

ArmLog ReadArmLog(const std::string& path, const ArmLogOptions& options) {
  return ArmLogFromTable(ReadCsvTable(path), options);
}

ArmLog ParseArmLog(const std::string& text, const std::string& path, const ArmLogOptions& options) {
  return ArmLogFromTable(ParseCsvTable(text, path), options);
}

void CheckArmLogMatchesModel(const ArmLog& log, const ArmModel& model) {
  if (log.dof == model.dof()) return;
  std::ostringstream s;
  s << "the log has " << log.dof << (log.dof == 1 ? " joint (" : " joints (") << Range("q", log.dof) << ", "
    << Range("tau", log.dof) << ") but the model '" << model.name << "'";
  if (!model.source_path.empty()) s << " (" << model.source_path << ")";
  s << " has " << model.dof();
  throw InputError(SourceLocation{log.path, 1}, s.str());
}

std::string FormatArmLog(const ArmLog& log, bool with_derivatives) {
  const int n = log.dof;
  const bool qref = log.qref.rows() == log.rows() && log.qref.cols() == n && n > 0;
  std::string out = "t";
  auto header = [&](const std::string& prefix) {
    for (int j = 1; j <= n; ++j) {
      out += ',';
      out += prefix;
      out += std::to_string(j);
    }
  };
  header("q");
  if (with_derivatives) {
    header("qd");
    header("qdd");
  }
  header("tau");
  if (qref) header("qref");
  out += '\n';
  for (int r = 0; r < log.rows(); ++r) {
    out += FormatCsvNumber(log.t[r]);
    auto row = [&](const Eigen::MatrixXd& m) {
      for (int j = 0; j < n; ++j) {
        out += ',';
        out += FormatCsvNumber(m(r, j));
      }
    };
    row(log.q);
    if (with_derivatives) {
      row(log.qd);
      row(log.qdd);
    }
    row(log.tau);
    if (qref) row(log.qref);
    out += '\n';
  }
  return out;
}

void WriteArmLog(const std::string& path, const ArmLog& log, bool with_derivatives) {
  WriteFileAtomically(path, FormatArmLog(log, with_derivatives));
}

void WriteArmTorqueCsv(const std::string& path, const Eigen::VectorXd& t, const Eigen::MatrixXd& tau) {
  std::string out = "t";
  for (Eigen::Index j = 1; j <= tau.cols(); ++j) {
    out += ",tau";
    out += std::to_string(j);
  }
  out += '\n';
  for (Eigen::Index r = 0; r < t.size(); ++r) {
    out += FormatCsvNumber(t[r]);
    for (Eigen::Index j = 0; j < tau.cols(); ++j) {
      out += ',';
      out += FormatCsvNumber(tau(r, j));
    }
    out += '\n';
  }
  WriteFileAtomically(path, out);
}

}  // namespace twinsim

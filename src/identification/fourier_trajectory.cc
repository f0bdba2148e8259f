#include "identification/fourier_trajectory.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "core/error.h"
#include "core/math_constants.h"
#include "io/atomic_file.h"
#include "io/csv_table.h"
#include "io/yaml_reader.h"
#include "robots/arm/arm_dynamics.h"

namespace twinsim {
namespace {

// The shortest of 15, 16 or 17 significant digits that reads back as the same double.
std::string Exact(double v) {
  if (v == 0) v = 0;  // no "-0"
  char buf[40];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

std::string ExactList(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (Eigen::Index k = 0; k < v.size(); ++k) s += (k ? ", " : "") + Exact(v[k]);
  return s + "]";
}

// A YAML scalar that reads back as the same text (quoted when it could be taken for
// something else).
std::string YamlText(const std::string& s) {
  bool plain = !s.empty();
  for (char c : s) plain = plain && (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.');
  if (plain && !std::isdigit(static_cast<unsigned char>(s[0])) && s[0] != '-' && s[0] != '.') return s;
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

}  // namespace

double FourierTrajectory::omega() const { return 2 * kPi * fundamental; }

std::string FourierTrajectory::Validate() const {
  std::ostringstream problems;
  if (!(fundamental > 0) || !std::isfinite(fundamental))
    problems << "fundamental frequency must be positive, got " << fundamental << "\n";
  if (dof() == 0) problems << "no joints\n";
  if (a.rows() != dof() || b.rows() != dof())
    problems << "coefficient rows (" << a.rows() << ", " << b.rows() << ") do not match " << dof() << " joints\n";
  if (a.cols() == 0) problems << "no harmonics\n";
  if (a.cols() != b.cols()) problems << "a has " << a.cols() << " harmonics but b has " << b.cols() << "\n";
  if (!joint_names.empty() && static_cast<int>(joint_names.size()) != dof())
    problems << joint_names.size() << " joint names for " << dof() << " joints\n";
  if (!q0.allFinite() || !a.allFinite() || !b.allFinite()) problems << "a coefficient is not finite\n";
  std::string s = problems.str();
  if (!s.empty()) s.pop_back();
  return s;
}

FourierTrajectory ZeroFourierTrajectory(int dof, int harmonics, double fundamental) {
  FourierTrajectory t;
  t.fundamental = fundamental;
  t.q0 = Eigen::VectorXd::Zero(dof);
  t.a = Eigen::MatrixXd::Zero(dof, harmonics);
  t.b = Eigen::MatrixXd::Zero(dof, harmonics);
  return t;
}

JointMotion EvaluateFourier(const FourierTrajectory& trajectory, double t) {
  const int n = trajectory.dof();
  const double w = trajectory.omega();
  JointMotion m{trajectory.q0, Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n)};
  for (int l = 1; l <= trajectory.harmonics(); ++l) {
    const double wl = w * l;
    const double s = std::sin(wl * t), c = std::cos(wl * t);
    const auto a = trajectory.a.col(l - 1), b = trajectory.b.col(l - 1);
    m.q += (a * s - b * c) / wl;
    m.qd += a * c + b * s;
    m.qdd += (b * c - a * s) * wl;
  }
  return m;
}

SampledMotion SampleFourier(const FourierTrajectory& trajectory, double sample_time, double duration) {
  if (!(sample_time > 0)) throw InputError("sample time must be positive, got " + std::to_string(sample_time));
  if (!(duration > 0)) throw InputError("duration must be positive, got " + std::to_string(duration));
  // Rounded so that a whole number of periods gives exactly period / sample_time rows.
  const long count = std::lround(std::ceil(duration / sample_time - 1e-9));
  const int n = trajectory.dof();
  SampledMotion s;
  s.q.resize(count, n);
  s.qd.resize(count, n);
  s.qdd.resize(count, n);
  for (long k = 0; k < count; ++k) {
    const double t = static_cast<double>(k) * sample_time;
    const JointMotion m = EvaluateFourier(trajectory, t);
    s.t.push_back(t);
    s.q.row(k) = m.q.transpose();
    s.qd.row(k) = m.qd.transpose();
    s.qdd.row(k) = m.qdd.transpose();
  }
  return s;
}

std::string FormatFourierTrajectoryYaml(const FourierTrajectory& trajectory) {
  std::ostringstream out;
  out << "# Excitation trajectory: a finite Fourier series per joint (docs/excitation.md)\n"
      << "#   q_i(t) = q0_i + sum_l a_il/(w l) sin(w l t) - b_il/(w l) cos(w l t),  w = 2 pi fundamental_hz\n"
      << "#   q0 in rad or m; a, b in rad/s or m/s (velocity amplitudes), one per harmonic\n";
  out << "fundamental_hz: " << Exact(trajectory.fundamental) << "\n";
  if (!trajectory.model.empty()) out << "model: " << YamlText(trajectory.model) << "\n";
  out << "joints:\n";
  for (int i = 0; i < trajectory.dof(); ++i) {
    const bool named = !trajectory.joint_names.empty() && !trajectory.joint_names[static_cast<std::size_t>(i)].empty();
    out << "  - ";
    if (named) out << "name: " << YamlText(trajectory.joint_names[static_cast<std::size_t>(i)]) << "\n    ";
    out << "q0: " << Exact(trajectory.q0[i]) << "\n";
    out << "    a: " << ExactList(trajectory.a.row(i).transpose()) << "\n";
    out << "    b: " << ExactList(trajectory.b.row(i).transpose()) << "\n";
  }
  return out.str();
}

void SaveFourierTrajectory(const FourierTrajectory& trajectory, const std::string& path) {
  const std::string problem = trajectory.Validate();
  if (!problem.empty()) throw InputError(path + ": cannot save an invalid trajectory: " + problem);
  WriteFileAtomically(path, FormatFourierTrajectoryYaml(trajectory));
}

namespace {

FourierTrajectory ReadTrajectory(const YAML::Node& root, const std::string& path) {
  ErrorList errors;
  YamlMap top(root, path, "", &errors);
  FourierTrajectory t;
  top.Require("fundamental_hz", &t.fundamental, Positive());
  top.Get("model", &t.model);
  const YAML::Node joints = top.Child("joints");
  if (!joints.IsDefined() || joints.IsNull()) {
    top.Missing("joints");
  } else if (!joints.IsSequence() || joints.size() == 0) {
    top.Error("joints", "expected a list with one entry per joint");
  } else {
    const int n = static_cast<int>(joints.size());
    std::vector<std::vector<double>> as(static_cast<std::size_t>(n)), bs(static_cast<std::size_t>(n));
    std::vector<double> q0(static_cast<std::size_t>(n), 0.0);
    bool shapes_ok = true;
    int harmonics = -1;
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      YamlMap j(joints[k], path, "joint " + std::to_string(i + 1), &errors);
      std::string name;
      j.Get("name", &name);
      t.joint_names.push_back(name);
      j.Require("q0", &q0[k]);
      const bool got_a = j.Require("a", &as[k]);
      const bool got_b = j.Require("b", &bs[k]);
      if (!got_a || !got_b) {
        shapes_ok = false;
      } else if (as[k].empty()) {
        j.Error("a", "expected at least one harmonic");
        shapes_ok = false;
      } else if (bs[k].size() != as[k].size()) {
        j.Error("b", "expected " + std::to_string(as[k].size()) + " numbers (as many as 'a'), got " +
                         std::to_string(bs[k].size()));
        shapes_ok = false;
      } else if (harmonics < 0) {
        harmonics = static_cast<int>(as[k].size());
      } else if (static_cast<int>(as[k].size()) != harmonics) {
        j.Error("a", "expected " + std::to_string(harmonics) + " harmonics (as joint 1), got " +
                         std::to_string(as[k].size()));
        shapes_ok = false;
      }
      j.Finish();
    }
    bool any_name = false;
    for (const auto& s : t.joint_names) any_name = any_name || !s.empty();
    if (!any_name) t.joint_names.clear();
    if (shapes_ok && harmonics > 0) {
      t.q0.resize(n);
      t.a.resize(n, harmonics);
      t.b.resize(n, harmonics);
      for (int i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        t.q0[i] = q0[k];
        for (int l = 0; l < harmonics; ++l) {
          t.a(i, l) = as[k][static_cast<std::size_t>(l)];
          t.b(i, l) = bs[k][static_cast<std::size_t>(l)];
        }
      }
    }
  }
  top.Finish();
  errors.ThrowIfAny();
  return t;
}

}  // namespace

FourierTrajectory LoadFourierTrajectory(const std::string& path) { return ReadTrajectory(LoadYamlFile(path), path); }

FourierTrajectory ParseFourierTrajectoryYaml(const std::string& text, const std::string& name) {
  const YAML::Node root = LoadYamlString(text, name);
  if (!root.IsMap()) throw InputError(SourceLocation{name, 1}, "expected a YAML mapping at the top level");
  return ReadTrajectory(root, name);
}

void CheckTrajectoryFitsModel(const FourierTrajectory& trajectory, const ArmModel& model, const std::string& where) {
  if (trajectory.dof() != model.dof())
    throw InputError(where + ": the trajectory has " + std::to_string(trajectory.dof()) + " joint(s) but model '" +
                     model.name + "' has " + std::to_string(model.dof()));
}

std::string FormatReferenceCsv(const ArmModel& model, const FourierTrajectory& trajectory, double sample_time,
                               int periods) {
  CheckTrajectoryFitsModel(trajectory, model, "reference");
  if (periods < 1) throw InputError("periods must be at least 1, got " + std::to_string(periods));
  const SampledMotion s = SampleFourier(trajectory, sample_time, periods * trajectory.period());
  const int n = model.dof();
  std::string out = "t";
  for (const char* prefix : {"q", "qd", "qdd", "qref", "tau"})
    for (int i = 1; i <= n; ++i) {
      out += ',';
      out += prefix;
      out += std::to_string(i);
    }
  out += "\n";
  for (std::size_t k = 0; k < s.t.size(); ++k) {
    const auto r = static_cast<Eigen::Index>(k);
    const Eigen::VectorXd q = s.q.row(r).transpose(), qd = s.qd.row(r).transpose(), qdd = s.qdd.row(r).transpose();
    const Eigen::VectorXd tau = InverseDynamics(model, q, qd, qdd);
    out += FormatCsvNumber(s.t[k]);
    for (const Eigen::VectorXd* v : {&q, &qd, &qdd, &q, &tau})
      for (int i = 0; i < n; ++i) {
        out += ',';
        out += FormatCsvNumber((*v)[i]);
      }
    out += "\n";
  }
  return out;
}

}  // namespace twinsim

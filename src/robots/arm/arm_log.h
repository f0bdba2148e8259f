// The arm log of CONTRACT.md: `t,q1..qn,tau1..taun`, optionally `qd1..qdn`,
// `qdd1..qddn` and `qref1..qrefn`, one row per sample, SI units, extra columns ignored.
// One module reads and writes it.
//
// Reading checks every value (file:line:column), that the joint columns are complete,
// and that t strictly increases and is nearly uniform (every step within 50 % of the
// median step: real controllers jitter, the KUKA logs by ±36 %). Where qd or qdd are
// absent they are derived from q by zero-phase filtered differentiation
// (signal/butterworth.h): a 4th-order Butterworth low-pass run forwards and backwards at
// the cut-off of ArmLogOptions, then central differences on the uniform grid of the
// log's average step (time stamps jitter, the controller's clock does not). Choose the cut-off well above the motion's bandwidth (the highest harmonic of
// an excitation, usually a few Hz) and well below where encoder quantisation and
// vibration live; docs/identification.md says more. The first and last
// `edge_samples` rows of derived values are less accurate (the filter's reach).
//
//   ArmLog log = ReadArmLog("run1.csv");
//   CheckArmLogMatchesModel(log, model);   // InputError when the joint counts differ
//   log.q.row(k), log.qd.row(k), log.tau.row(k)
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "robots/arm/arm_model.h"

namespace twinsim {

struct ArmLogOptions {
  double cutoff_hz = 10;   // Hz, cut-off for derived qd/qdd; lowered to a quarter of the sample rate if above it
  int filter_order = 4;    // poles of the Butterworth low-pass (run twice: zero phase)
  // Empty when usable, else what is wrong.
  bool IsValid(std::string* why) const;
};

struct CsvTable;

struct ArmLog {
  std::string path;
  int dof = 0;
  Eigen::VectorXd t;     // s, one per row (N)
  Eigen::MatrixXd q;     // N x dof, rad or m
  Eigen::MatrixXd qd;    // N x dof, per second (logged or derived)
  Eigen::MatrixXd qdd;   // N x dof, per second^2 (logged or derived)
  Eigen::MatrixXd tau;   // N x dof, N·m or N
  Eigen::MatrixXd qref;  // N x dof, or 0 x 0 when not logged
  bool qd_logged = false;
  bool qdd_logged = false;
  double sample_period = 0;    // s, the median step between rows
  double derive_cutoff_hz = 0; // Hz, the cut-off used to derive qd/qdd (0: both logged)
  int edge_samples = 0;        // rows at each end where derived qd/qdd are less accurate
  std::vector<int> line_of;    // file line of each row

  int rows() const { return static_cast<int>(t.size()); }
};

// Reads and checks a log; throws InputError "path:line:column: what is wrong" for a
// missing file, bad numbers, missing or incomplete joint columns, fewer than 3 rows,
// time that does not increase or is not nearly uniform, or invalid options.
ArmLog ReadArmLog(const std::string& path, const ArmLogOptions& options = {});
// The same checks on a table held in memory (TableFromRows in io/csv_table.h).
ArmLog ArmLogFromTable(const CsvTable& table, const ArmLogOptions& options = {});
ArmLog ParseArmLog(const std::string& text, const std::string& path, const ArmLogOptions& options = {});

// Derives (again) the velocities and accelerations `log` does not hold as logged, from
// its q at `options`' cut-off (ArmLogFromTable does this once): qd, qdd,
// derive_cutoff_hz and edge_samples change; a log with both logged is left as it is.
// Throws InputError for invalid options.
void DeriveArmLog(const ArmLogOptions& options, ArmLog* log);

// Throws InputError "path:1: the log has 3 joints (q1..q3, tau1..tau3) but the model
// 'kuka-lwr' has 7" when the counts differ.
void CheckArmLogMatchesModel(const ArmLog& log, const ArmModel& model);

// The CSV text of a log: t, q, then qd and qdd when `with_derivatives`, tau, and qref
// when present; numbers with FormatCsvNumber().
std::string FormatArmLog(const ArmLog& log, bool with_derivatives);
// Writes a log atomically.
void WriteArmLog(const std::string& path, const ArmLog& log, bool with_derivatives);

// Writes `t,tau1..taun` (a replay's output, `tau` N x n) atomically.
void WriteArmTorqueCsv(const std::string& path, const Eigen::VectorXd& t, const Eigen::MatrixXd& tau);

}  // namespace twinsim

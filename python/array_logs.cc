#include "python/array_logs.h"

#include <sstream>

#include "core/error.h"
#include "io/csv_table.h"

namespace twinsim {
namespace {

std::vector<std::vector<double>> Rows(const Array& a, int cols, const std::string& what) {
  if (a.ndim() != 2 || a.shape(1) != cols) {
    std::ostringstream msg;
    msg << what << ": expected an array of shape (N, " << cols << "), got shape (";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) msg << (i ? ", " : "") << a.shape(i);
    msg << ")";
    throw InputError(msg.str());
  }
  std::vector<std::vector<double>> rows(static_cast<std::size_t>(a.shape(0)), std::vector<double>(cols));
  auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i)
    for (int j = 0; j < cols; ++j) rows[static_cast<std::size_t>(i)][j] = r(i, j);
  return rows;
}

std::string LogName(int i) { return "log[" + std::to_string(i) + "]"; }

// One log (`single`) or a list of them, each read by `one(log, name)`.
template <typename Log, typename ReadOne>
std::vector<Log> ToLogs(const py::handle& logs, bool single, ReadOne one) {
  std::vector<Log> out;
  if (single) {
    out.push_back(one(logs, LogName(0)));
    return out;
  }
  int i = 0;
  for (const auto& log : logs) out.push_back(one(log, LogName(i++)));
  return out;
}

}  // namespace

// An omni log: a file path, or an (N, 7) array t,x,y,theta,vx_cmd,vy_cmd,omega_cmd.
OmniLog ToOmniLog(const py::handle& log, const std::string& name) {
  if (py::isinstance<py::str>(log)) return ReadOmniLog(log.cast<std::string>());
  return OmniLogFromTable(TableFromRows(name, {"t", "x", "y", "theta", "vx_cmd", "vy_cmd", "omega_cmd"},
                                        Rows(log.cast<Array>(), 7, name)));
}

// An arm log: a file path, or a dict of arrays t (N), q, tau and optionally qd, qdd,
// qref (N x n each).
ArmLog ToArmLog(const py::handle& log, const std::string& name) {
  if (py::isinstance<py::str>(log)) return ReadArmLog(log.cast<std::string>());
  if (!py::isinstance<py::dict>(log)) throw InputError(name + ": an arm log is a file path or a dict of arrays (t, q, tau)");
  const py::dict d = log.cast<py::dict>();
  for (const char* key : {"t", "q", "tau"}) {
    if (!d.contains(key)) throw InputError(name + ": missing '" + std::string(key) + "' (an arm log needs t, q and tau)");
  }
  const Array t = d["t"].cast<Array>();
  if (t.ndim() != 1) throw InputError(name + ": 't' must be one-dimensional");
  const py::ssize_t n = t.shape(0);
  std::vector<std::string> header{"t"};
  std::vector<Array> blocks;
  int dof = -1;
  for (const char* key : {"q", "qd", "qdd", "tau", "qref"}) {
    if (!d.contains(key)) continue;
    Array a = d[key].cast<Array>();
    if (a.ndim() == 1) a = a.reshape({a.shape(0), py::ssize_t{1}});
    if (a.ndim() != 2 || a.shape(0) != n) {
      throw InputError(name + ": '" + key + "' must have one row per time (" + std::to_string(n) + " rows)");
    }
    if (dof < 0) dof = static_cast<int>(a.shape(1));
    if (a.shape(1) != dof) throw InputError(name + ": '" + key + "' has another number of joints than 'q'");
    for (int j = 0; j < dof; ++j) header.push_back(key + std::to_string(j + 1));
    blocks.push_back(std::move(a));
  }
  std::vector<std::vector<double>> rows(static_cast<std::size_t>(n));
  auto tt = t.unchecked<1>();
  for (py::ssize_t i = 0; i < n; ++i) {
    auto& row = rows[static_cast<std::size_t>(i)];
    row.reserve(header.size());
    row.push_back(tt(i));
    for (const Array& b : blocks) {
      auto bb = b.unchecked<2>();
      for (py::ssize_t j = 0; j < b.shape(1); ++j) row.push_back(bb(i, j));
    }
  }
  return ArmLogFromTable(TableFromRows(name, std::move(header), std::move(rows)));
}

std::vector<OmniLog> ToOmniLogs(const py::handle& logs) {
  return ToLogs<OmniLog>(logs, py::isinstance<py::str>(logs) || py::isinstance<py::array>(logs), ToOmniLog);
}

std::vector<ArmLog> ToArmLogs(const py::handle& logs) {
  return ToLogs<ArmLog>(logs, py::isinstance<py::str>(logs) || py::isinstance<py::dict>(logs), ToArmLog);
}

// A new (rows, cols) float64 array.
Array NewArray(py::ssize_t rows, py::ssize_t cols) { return Array({rows, cols}); }

std::shared_ptr<const OmniPredictor> OmniPredictorArg(const py::handle& p) {
  if (p.is_none()) return nullptr;
  if (py::isinstance<py::str>(p)) return std::make_shared<OmniPredictor>(OmniPredictor::Load(p.cast<std::string>()));
  return p.cast<std::shared_ptr<OmniPredictor>>();
}

std::shared_ptr<const ArmPredictor> ArmPredictorArg(const py::handle& p) {
  if (p.is_none()) return nullptr;
  if (py::isinstance<py::str>(p)) return std::make_shared<ArmPredictor>(ArmPredictor::Load(p.cast<std::string>()));
  return p.cast<std::shared_ptr<ArmPredictor>>();
}

}  // namespace twinsim

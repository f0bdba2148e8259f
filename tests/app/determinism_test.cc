// Issue 14: the same inputs and seed give byte-identical outputs, on every backend and
// for 1 and 2 threads. Each command that writes files runs twice into two folders (with
// --threads 1 / 2 or --jobs 1 / 2 where it has them) and every file must match byte for
// byte; only batch's wall-time fields are allowed to differ.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../diagnosis/diagnosis_plants.h"
#include "robots/arm/arm_log.h"
#include "robots/omni/omni_log.h"
#include "test_util.h"

namespace twinsim {
namespace {

namespace fs = std::filesystem;
using testing::RunTwinsim;
using testing::SourcePath;

// Relative path -> contents of every regular file under `dir`.
std::map<std::string, std::string> Contents(const std::string& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) files[fs::relative(e.path(), dir).string()] = testing::ReadText(e.path().string());
  }
  return files;
}

// Batch's wall times: the "wall_s" field of each job's result.json and the summary's
// wall_s column (dropped, with its header).
std::string WithoutWallTime(const std::string& name, std::string text) {
  if (name.ends_with(".json")) return std::regex_replace(text, std::regex(R"("wall_s"\s*:\s*[-+0-9.eE]+)"), "\"wall_s\":_");
  if (!name.ends_with("summary.csv")) return text;
  std::istringstream lines(text);
  std::string header, line, out;
  std::getline(lines, header);
  std::vector<std::string> columns;
  for (std::size_t start = 0;;) {
    const std::size_t comma = header.find(',', start);
    columns.push_back(header.substr(start, comma - start));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  auto keep = [&](const std::string& row) {
    std::string kept;
    std::size_t start = 0;
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const std::size_t comma = row.find(',', start);
      if (columns[c].find("wall") == std::string::npos) kept += row.substr(start, comma - start) + ",";
      start = comma == std::string::npos ? row.size() : comma + 1;
    }
    return kept + "\n";
  };
  out = keep(header);
  while (std::getline(lines, line)) out += keep(line);
  return out;
}

struct Case {
  const char* name;
  std::string args;         // {out}: the output folder (or file stem); {d}: the case's inputs
  std::string first = "";   // appended to the first run (e.g. --threads 1)
  std::string second = "";  // appended to the second run
  bool candidate = false;   // regress: a copy of the candidate run in {out}/candidate first
};

std::string Fill(std::string s, const std::string& key, const std::string& value) {
  for (std::size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + value.size()))
    s.replace(at, key.size(), value);
  return s;
}

// The inputs every case may use, written once: an omni log, two arm logs, a predictor,
// a golden run folder and a small sweep.
const std::string& Inputs() {
  static const std::string d = [] {
    const std::string dir = testing::TempDir("determinism_inputs");
    OmniModel plant = testing::Omni4();
    plant.effects.motor_lag = 0.06;
    WriteOmniLog(dir + "/omni.csv", testing::RecordOmniPlant(plant, 20, 5).rows);
    const ArmModel nominal = testing::RrrWith("");
    const ArmModel arm = testing::RrrWith("  - {name: viscous_friction, joint: 2, b: 0.4}\n");
    WriteArmLog(dir + "/arm_a.csv", testing::RecordArmPlant(arm, nominal, 1, 8), false);
    WriteArmLog(dir + "/arm_b.csv", testing::RecordArmPlant(arm, nominal, 2, 8), false);
    for (const auto& [folder, seed] : {std::pair{"golden", "1"}, std::pair{"candidate", "2"}}) {
      EXPECT_EQ(RunTwinsim("run --quiet " + SourcePath("scenes/drive45.yaml") + " --backend analytic --seed " + seed +
                           " --out " + dir + "/" + folder)
                    .exit_code,
                0);
    }
    // A 1-frame predictor for the learned backend, trained on that log.
    EXPECT_EQ(RunTwinsim("train --quiet --model " + SourcePath("models/omni4.yaml") + " --log " + dir +
                         "/omni.csv --kind linear --horizon 1 --out " + dir + "/h1.pred")
                  .exit_code,
              0);
    testing::WriteText(dir + "/sweep.yaml", "name: det\nseed: 4\ncommand: run\nfixed:\n  scene: " +
                                                SourcePath("scenes/drive45.yaml") +
                                                "\n  scene.duration: 1.5\n"
                                                "grid:\n  scene.seed: [1, 2, 3, 4]\n  backend: [analytic, ode]\n");
    return dir;
  }();
  return d;
}

// Readable test names in failure messages.
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

class SameBytes : public ::testing::TestWithParam<Case> {};

TEST_P(SameBytes, TwiceGivesIdenticalFiles) {
  const Case& c = GetParam();
  const std::string d = Inputs();
  const std::string base = testing::TempDir(std::string("determinism_") + c.name);
  std::map<std::string, std::string> runs[2];
  for (int k = 0; k < 2; ++k) {
    const std::string out = base + "/" + std::to_string(k);
    fs::create_directories(out);
    if (c.candidate) fs::copy(d + "/candidate", out + "/candidate", fs::copy_options::recursive);
    const auto r = RunTwinsim(Fill(Fill(c.args, "{out}", out), "{d}", d) + " " + (k == 0 ? c.first : c.second));
    ASSERT_EQ(r.exit_code, c.candidate ? 1 : 0) << r.err;  // regress: the seeds' noise moved the path
    runs[k] = Contents(out);
  }
  ASSERT_FALSE(runs[0].empty());
  ASSERT_EQ(runs[0].size(), runs[1].size());
  for (const auto& [name, text] : runs[0]) {
    ASSERT_TRUE(runs[1].count(name)) << name;
    EXPECT_TRUE(WithoutWallTime(name, text) == WithoutWallTime(name, runs[1][name]))
        << c.name << ": " << name << " differs between the two runs";
  }
}

const std::string kOmni = SourcePath("models/omni4.yaml");
const std::string kRrr = SourcePath("models/rrr.yaml");

INSTANTIATE_TEST_SUITE_P(
    Commands, SameBytes,
    ::testing::Values(
        Case{"run_omni_analytic", "run " + SourcePath("scenes/drive45.yaml") + " --backend analytic --out {out}"},
        Case{"run_omni_ode", "run " + SourcePath("scenes/drive45.yaml") + " --backend ode --out {out}"},
        Case{"run_omni_bullet", "run " + SourcePath("scenes/drive45.yaml") + " --backend bullet --out {out}"},
        Case{"run_omni_learned", "run " + SourcePath("scenes/drive45.yaml") + " --backend learned --predictor {d}/h1.pred --out {out}"},
        Case{"run_arm_analytic", "run " + SourcePath("scenes/rrr_writing.yaml") + " --backend analytic --out {out}"},
        Case{"run_arm_ode", "run " + SourcePath("scenes/rrr_writing.yaml") + " --backend ode --out {out}"},
        Case{"run_arm_bullet", "run " + SourcePath("scenes/rrr_writing.yaml") + " --backend bullet --out {out}"},
        Case{"replay_omni_ode", "replay --model " + kOmni + " --log {d}/omni.csv --backend ode --out {out}/r.csv"},
        Case{"replay_omni_bullet", "replay --model " + kOmni + " --log {d}/omni.csv --backend bullet --out {out}/r.csv"},
        Case{"replay_omni_analytic",
             "replay --model " + kOmni + " --log {d}/omni.csv --backend analytic --out {out}/r.csv"},
        Case{"replay_omni_learned", "replay --model " + kOmni +
                                        " --log {d}/omni.csv --backend learned --predictor {d}/h1.pred --out {out}/r.csv"},
        Case{"replay_arm", "replay --model " + kRrr + " --log {d}/arm_a.csv --out {out}/tau.csv"},
        Case{"train_linear", "train --model " + kOmni + " --log {d}/omni.csv --kind linear --horizon 4 --out {out}/p.pred"},
        Case{"train_mlp", "train --model " + kOmni + " --log {d}/omni.csv --kind mlp --horizon 1 --epochs 3 --out {out}/p.pred"},
        Case{"train_residual", "train --model " + kOmni + " --log {d}/omni.csv --kind linear --residual --out {out}/p.pred"},
        Case{"identify", "identify --model " + kRrr + " --log {d}/arm_a.csv --log {d}/arm_b.csv --out {out}/m.yaml"},
        Case{"compare", "compare --model " + kOmni + " --log {d}/omni.csv --out {out}"},
        Case{"identify_omni", "identify --model " + kOmni + " --log {d}/omni.csv --out {out}/o --max-delay 0.2 --stride 8",
             "--threads 1", "--threads 2"},
        Case{"diagnose_omni", "diagnose --model " + kOmni + " --log {d}/omni.csv --out {out}/o --max-effects 1",
             "--threads 1", "--threads 2"},
        Case{"diagnose_arm", "diagnose --model " + kRrr + " --log {d}/arm_a.csv --log {d}/arm_b.csv --out {out}/o --max-effects 1",
             "--threads 1", "--threads 2"},
        Case{"excite", "excite --model " + kRrr + " --out {out}/o --harmonics 3 --fundamental 0.5 --samples 40 --starts 3"
                       " --iterations 15 --periods 2",
             "--threads 1", "--threads 2"},
        Case{"tune_pid", "tune-pid " + SourcePath("scenes/tune_pid_zeros.yaml") + " --out {out}/o --iterations 2",
             "--threads 1", "--threads 2"},
        Case{"ilc", "ilc " + SourcePath("scenes/rrr_writing_ilc.yaml") + " --out {out}/o --trials 2"},
        Case{"regress", "regress --golden {d}/golden --candidate {out}/candidate --tolerance 1e-4", "", "", true},
        Case{"batch", "batch {d}/sweep.yaml --out {out}/o", "--jobs 1", "--jobs 2"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace twinsim

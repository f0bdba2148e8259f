// `twinsim diagnose` through the binary: the files the contract names, their content,
// and the contract's errors with nothing written.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "diagnosis/diagnosis_plants.h"
#include "robots/arm/arm_log.h"
#include "robots/arm/arm_model.h"
#include "robots/omni/omni_log.h"
#include "robots/omni/omni_model.h"
#include "test_util.h"

namespace twinsim {
namespace {

using nlohmann::json;
using testing::RunTwinsim;
using testing::SourcePath;

void ExpectContractReport(const json& r, const std::string& robot) {
  EXPECT_EQ(r.at("robot"), robot);
  EXPECT_TRUE(r.at("metric").is_string());
  EXPECT_TRUE(r.at("gap_before").is_number());
  EXPECT_TRUE(r.at("gap_after").is_number());
  EXPECT_LE(r.at("gap_after").get<double>(), r.at("gap_before").get<double>());
  ASSERT_TRUE(r.at("effects").is_array());
  // CONTRACT.md: the changes part way through a log, an empty list when none.
  ASSERT_TRUE(r.at("changes").is_array());
  for (const json& c : r.at("changes")) {
    EXPECT_TRUE(c.at("log").is_string());
    EXPECT_TRUE(c.at("t").is_number());
    EXPECT_FALSE(c.at("what").get<std::string>().empty());
  }
  for (const json& e : r.at("effects")) {
    EXPECT_TRUE(e.at("name").is_string());
    EXPECT_TRUE(e.at("joint").is_null() || e.at("joint").is_number_integer());
    EXPECT_TRUE(e.at("parameters").is_object());
    EXPECT_TRUE(e.at("gap_reduction").is_number());
    EXPECT_FALSE(e.at("evidence").get<std::string>().empty());
  }
}

TEST(DiagnoseCli, OmniRobotWithAHiddenMotorLag) {
  const std::string dir = testing::TempDir("diagnose_omni");
  OmniModel plant = testing::Omni4();
  plant.effects.motor_lag = 0.08;
  WriteOmniLog(dir + "/log.csv", testing::RecordOmniPlant(plant, 30, 3).rows);
  const auto r = RunTwinsim("diagnose --model " + SourcePath("models/omni4.yaml") + " --log " + dir + "/log.csv --out " +
                            dir + "/out");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Missing: motor_lag"), std::string::npos) << r.out;
  const json report = json::parse(testing::ReadText(dir + "/out/report.json"));
  ExpectContractReport(report, "omni");
  ASSERT_EQ(report.at("effects").size(), 1u);
  EXPECT_EQ(report["effects"][0]["name"], "motor_lag");
  EXPECT_TRUE(report["effects"][0]["joint"].is_null());
  EXPECT_NEAR(report["effects"][0]["parameters"]["time_constant"].get<double>(), 0.08, 0.012);
  // The repaired model loads and carries the effect.
  const OmniModel repaired = LoadOmniModel(dir + "/out/model.yaml");
  EXPECT_NEAR(repaired.effects.motor_lag, 0.08, 0.012);
  // The HTML is one file that needs no network.
  const std::string html = testing::ReadText(dir + "/out/report.html");
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  EXPECT_NE(html.find("Every candidate tried"), std::string::npos);
  // The repaired model replays the log with the contract's replay command.
  const auto replay = RunTwinsim("replay --model " + dir + "/out/model.yaml --log " + dir + "/log.csv --out " + dir +
                                 "/replay.csv --backend analytic");
  EXPECT_EQ(replay.exit_code, 0) << replay.err;
}

TEST(DiagnoseCli, ArmWithAHiddenPayloadWritesJointNullAndLoads) {
  const std::string dir = testing::TempDir("diagnose_arm");
  const ArmModel nominal = testing::RrrWith("");
  const ArmModel plant = testing::RrrWith("  - {name: payload, joint: null, mass: 1.0, x: 0.35}\n"
                                          "  - {name: torque_offset, joint: 3, tau0: 0.8}\n");
  WriteArmLog(dir + "/a.csv", testing::RecordArmPlant(plant, nominal, 1, 15), false);
  WriteArmLog(dir + "/b.csv", testing::RecordArmPlant(plant, nominal, 2, 15), false);
  const auto r = RunTwinsim("diagnose --model " + SourcePath("models/rrr.yaml") + " --log " + dir + "/a.csv --log " + dir +
                            "/b.csv --out " + dir + "/out --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  const json report = json::parse(testing::ReadText(dir + "/out/report.json"));
  ExpectContractReport(report, "arm");
  bool payload = false, offset = false;
  for (const json& e : report["effects"]) {
    if (e["name"] == "payload") payload = e["joint"].is_null();
    if (e["name"] == "torque_offset") offset = e["joint"] == 3;  // 1-based, as in model files
  }
  EXPECT_TRUE(payload) << report.dump(1);
  EXPECT_TRUE(offset) << report.dump(1);
  const ArmModel repaired = LoadArmModel(dir + "/out/model.yaml");
  EXPECT_NEAR(repaired.effects.payload_mass, 1.0, 0.15);
  EXPECT_NEAR(repaired.effects.joint(2).torque_offset, 0.8, 0.12);
  // The derivatives' cut-off, chosen from the logs by default, is said in the report and the model.
  ASSERT_FALSE(report["notes"].empty());
  EXPECT_EQ(report["notes"][0].get<std::string>().rfind("The logs' derivative cut-off ", 0), 0u) << report["notes"];
  EXPECT_NE(testing::ReadText(dir + "/out/model.yaml").find("derivative cut-off "), std::string::npos);
}

TEST(DiagnoseCli, BadInputExitsTwoAndWritesNothing) {
  const std::string dir = testing::TempDir("diagnose_bad");
  const std::string rrr = SourcePath("models/rrr.yaml");
  auto expect_bad = [&](const std::string& args, const std::string& message) {
    const std::string out = dir + "/out";
    std::filesystem::remove_all(out);
    const auto r = RunTwinsim("diagnose " + args + " --out " + out);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(out + "/report.json"));
    EXPECT_FALSE(std::filesystem::exists(out + "/model.yaml"));
  };
  // A log whose columns do not match the model.
  testing::WriteText(dir + "/two.csv", "t,q1,q2,tau1,tau2\n0,0,0,0,0\n0.001,0,0,0,0\n0.002,0,0,0,0\n");
  expect_bad("--model " + rrr + " --log " + dir + "/two.csv", dir + "/two.csv:1:");
  // Too short to hold anything out.
  const ArmModel nominal = testing::RrrWith("");
  WriteArmLog(dir + "/short.csv", testing::RecordArmPlant(nominal, nominal, 1, 0.5), false);
  expect_bad("--model " + rrr + " --log " + dir + "/short.csv", "too short");
  // NaN in the data.
  testing::WriteText(dir + "/nan.csv", "t,q1,q2,q3,tau1,tau2,tau3\n0,0,0,0,0,0,0\n0.001,0,nan,0,0,0,0\n0.002,0,0,0,0,0,0\n");
  expect_bad("--model " + rrr + " --log " + dir + "/nan.csv", dir + "/nan.csv:3:");
  // A model without joints.
  testing::WriteText(dir + "/empty.yaml", "robot: arm\nname: nothing\ndh: standard\njoints: []\n");
  expect_bad("--model " + dir + "/empty.yaml --log " + dir + "/two.csv", "empty.yaml");
  // Options out of range.
  expect_bad("--model " + rrr + " --log " + dir + "/short.csv --held-out 1.5", "--held-out");
  // An omni log for an omni model, too short.
  OmniModel omni = testing::Omni4();
  WriteOmniLog(dir + "/omni_short.csv", testing::RecordOmniPlant(omni, 1.5, 1).rows);
  expect_bad("--model " + SourcePath("models/omni4.yaml") + " --log " + dir + "/omni_short.csv", "too short");
}

}  // namespace
}  // namespace twinsim

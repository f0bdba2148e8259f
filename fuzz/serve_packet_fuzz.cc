// Fuzzes the served field's packet readers (twinsim serve, docs/serve.md): a team's
// RobotControl, the simulator's SimulatorCommand and grSim's packet. The first byte
// picks the reader (blue RobotControl without a ball, yellow with one and yellow robot
// 3 off the field, SimulatorCommand without a ball, with one and yellow robot 3 off the
// field, a grSim_Packet whose translation is then read as the field reads it); the rest
// is the datagram. Every reader promises never to throw for any bytes, so any
// exception is a crash here.
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_util.h"
#include "robots/omni/omni_model.h"
#include "serve/grsim_packet.h"
#include "serve/robot_control.h"
#include "serve/simulator_control.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace twinsim;
  if (size == 0) return 0;
  static const TeamRoster roster = [] {
    const std::optional<ProtocolWheelMap> wheels =
        WheelMapFor(LoadOmniModel(std::string(TWINSIM_SOURCE_DIR) + "/models/omni4.yaml"));
    return TeamRoster({TeamRobot{TeamColor::kBlue, 0, wheels}, TeamRobot{TeamColor::kBlue, 1},
                       TeamRobot{TeamColor::kYellow, 0, wheels}, TeamRobot{TeamColor::kYellow, 3}});
  }();
  static const FieldModel field;
  static const std::vector<bool> contact = {true, false, false, true};
  static const std::vector<bool> present = {true, true, true, false};
  const std::string bytes = fuzz::AsString(data + 1, size - 1);
  switch (data[0] % 5) {
    case 0: ReadRobotControl(bytes, TeamColor::kBlue, roster); break;
    case 1: ReadRobotControl(bytes, TeamColor::kYellow, roster, &contact, &present); break;
    case 2: ReadSimulatorCommand(bytes, roster, field, false); break;
    case 3: ReadSimulatorCommand(bytes, roster, field, true, &present); break;
    default: {
      const GrSimPacket packet = ReadGrSimPacket(bytes, [](TeamColor, unsigned id) { return id < 2 ? 0.027 : 0.0; });
      if (packet.commands)
        ReadRobotControl(packet.commands->SerializeAsString(), packet.team, roster, &contact, &present);
      if (packet.replacement) ReadSimulatorCommand(packet.replacement->SerializeAsString(), roster, field, true, &present);
      break;
    }
  }
  return 0;
}

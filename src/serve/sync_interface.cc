// LiveField's synchronous interface (serve/live_field.h; docs/serve.md "The synchronous
// interface"): one TCP client at a time, each SimulationSyncRequest applied and stepped,
// each answered with the vision of the frame the field then stands at.
#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <thread>

#include "serve/live_field.h"
#include "ssl_simulation_synchronous.pb.h"

namespace twinsim {
namespace {

using Clock = std::chrono::steady_clock;

// The longest request read, and the longest step a request may ask for.
constexpr std::size_t kMaxSyncMessage = 1 << 20;  // bytes
constexpr double kMaxSyncStep = 60;               // s
// Requests answered before the loop looks for a stop, a status and more bytes again.
constexpr int kRequestsPerPass = 64;

}  // namespace

ServeSummary LiveField::RunSync(const std::function<bool()>& stop, const std::function<void(const ServeSummary&)>& status) {
  start_ = Clock::now();
  Clock::time_point next_status = start_;
  std::vector<FrameRecord> records = OpenFrame();
  std::optional<TcpConnection> client;
  while (!stop() && (options_.max_frames == 0 || counters_.frames < options_.max_frames)) {
    if (status && Clock::now() >= next_status) {
      status(Summary());
      next_status = Clock::now() + std::chrono::milliseconds(100);
    }
    if (!client) {
      // One client at a time; the field waits, frame open, for the next. A listener that
      // cannot accept (out of descriptors) is not spun on.
      if (WaitReadableFd(sync_->fd(), kPollPeriod) && !(client = sync_->Accept()))
        std::this_thread::sleep_for(std::chrono::duration<double>(kPollPeriod));
      continue;
    }
    const bool open = client->ReadAvailable();
    int handled = 0;
    bool written = true;
    while (handled < kRequestsPerPass && written && !stop()) {
      std::optional<std::string> request = client->NextMessage(kMaxSyncMessage);
      if (!request) break;
      written = HandleSyncRequest(*request, &records, &*client);
      ++handled;
      if (options_.max_frames > 0 && counters_.frames >= options_.max_frames) break;
    }
    if (client->bad()) ++counters_.malformed;  // a length no message can have: the stream is lost
    // Closed, unreadable, or an answer that did not go out whole (a client that does not
    // read): the connection is dropped; the field waits for the next.
    if (!open || client->bad() || !written) {
      client.reset();
      continue;
    }
    if (handled == 0) WaitReadableFd(client->fd(), kPollPeriod);
  }
  return Summary();
}

bool LiveField::HandleSyncRequest(const std::string& bytes, std::vector<FrameRecord>* records, TcpConnection* client) {
  SimulationSyncRequest request;
  SimulationSyncResponse response;
  RobotControlResponse* answer = response.mutable_robot_control_response();
  int steps = 0;
  if (!request.ParseFromString(bytes)) {
    ++counters_.malformed;
    AddError(answer, "TWINSIM_MALFORMED", "the message is not a SimulationSyncRequest");
  } else {
    ++counters_.sync_requests;
    // The official response has no SimulatorResponse: a simulator command's errors are
    // listed with the robot control's.
    if (request.has_simulator_command()) {
      if (options_.tournament) {
        ++counters_.refused;
        AddError(answer, "TWINSIM_TOURNAMENT", "tournament mode: simulator control is refused");
      } else {
        const SimulatorCommandResult read = TakeSimulatorCommand(request.simulator_command().SerializeAsString());
        for (const SimulatorError& e : read.response.errors()) AddError(answer, e.code(), e.message());
      }
    }
    if (request.has_robot_control()) {
      const RobotControlResult read =
          TakeRobotControl(teams_[options_.sync_team == "yellow" ? 1 : 0], request.robot_control().SerializeAsString());
      for (const SimulatorError& e : read.response.errors()) AddError(answer, e.code(), e.message());
      *answer->mutable_feedback() = read.response.feedback();
    }
    const double step = request.sim_step(), dt = result_.timing.frame_dt();
    if (!(std::isfinite(step) && step >= 0 && step <= kMaxSyncStep)) {
      ++counters_.refused;
      AddError(answer, "TWINSIM_BAD_VALUE",
               "sim_step " + std::to_string(step) + " s is not in 0.." + std::to_string(kMaxSyncStep) + " s");
    } else {
      // Whole frames: a step of half a frame or more runs one.
      steps = static_cast<int>(std::lround(step / dt));
      if (options_.max_frames > 0) steps = static_cast<int>(std::min<long long>(steps, options_.max_frames - counters_.frames));
    }
  }
  for (int j = 0; j < steps; ++j) {
    FinishFrame(records);
    *records = OpenFrame();
  }
  for (const SSL_WrapperPacket& p : VisionPackets(*records)) *response.add_detection() = p.detection();
  counters_.vision_packets += response.detection_size();
  if (client->WriteMessage(response.SerializeAsString())) return true;
  ++counters_.failed_sends;
  last_send_error_ = "the synchronous client's connection failed or stalled (it is dropped)";
  return false;
}

}  // namespace twinsim

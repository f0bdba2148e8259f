// The serve summary's one-line brief and full report (serve/live_field.h).
#include <sstream>

#include "serve/live_field.h"

namespace twinsim {

std::string ServeTiming::Stall::Brief() const {
  if (frame < 0) return "none";
  std::ostringstream s;
  s << seconds * 1e3 << " ms at frame " << frame << " (";
  if (vision > 0) s << vision * 1e3 << " ms of it the vision; ";
  if (woke_late > 0) s << "the last wait woke " << woke_late * 1e3 << " ms late; ";
  s << "page faults " << minor_faults << " minor, " << major_faults << " major; context switches " << voluntary
    << " voluntary, " << involuntary << " involuntary";
  if (stolen >= 0) s << "; CPU stolen " << stolen * 1e3 << " ms, in interrupts " << interrupts * 1e3 << " ms";
  s << ")";
  return s.str();
}

std::string ServeSummary::Brief() const {
  std::ostringstream s;
  s << counters.frames << " frames (" << simulated << " s simulated) in " << wall << " s wall; blue "
    << (clients[0].empty() ? "-" : clients[0]) << ", yellow " << (clients[1].empty() ? "-" : clients[1]) << "; "
    << counters.refused << " refused, " << counters.malformed + counters.oversized + counters.rate_dropped
    << " bad datagrams";
  if (counters.kernel_dropped > 0) s << ", " << counters.kernel_dropped << " dropped by the kernel";
  if (counters.failed_sends > 0) s << ", " << counters.failed_sends << " sends failed (" << last_send_error << ")";
  return s.str();
}

std::string ServeSummary::Report() const {
  std::ostringstream s;
  s << "frames " << counters.frames << " (" << simulated << " s simulated, " << wall << " s wall)\n"
    << "vision packets sent " << counters.vision_packets << "\n"
    << "robot controls " << counters.robot_controls << ", simulator commands " << counters.simulator_commands
    << ", grSim packets " << counters.grsim_packets << "\n"
    << "refused " << counters.refused << ", malformed " << counters.malformed << ", oversized " << counters.oversized
    << ", over the rate limit " << counters.rate_dropped << "\n"
    << "late frames " << counters.late_frames << "\n"
    << "dropped by the kernel (receive buffer full) " << counters.kernel_dropped << "; receive buffer "
    << receive_buffer << " bytes per port of " << receive_buffer_asked << " asked"
    << (receive_buffer < receive_buffer_asked ? " (raise net.core.rmem_max, or run with CAP_NET_ADMIN)" : "") << "\n"
    << "failed sends " << counters.failed_sends << (last_send_error.empty() ? "" : " (last: " + last_send_error + ")")
    << "\n"
    << "frame work " << timing.frame_work.Brief() << "\n"
    << "slowest frame " << timing.slowest.Brief() << "\n"
    << "frame start lateness " << timing.start_lateness.Brief() << "\n"
    << "latest start " << timing.latest_start.Brief() << "\n"
    << "command latency (arrival to delay line) " << timing.command_latency.Brief() << "\n"
    << "  of which after the read " << timing.command_handling.Brief() << "\n"
    << "blue client " << (clients[0].empty() ? "-" : clients[0]) << ", yellow client "
    << (clients[1].empty() ? "-" : clients[1]) << "\n";
  return s.str();
}

}  // namespace twinsim

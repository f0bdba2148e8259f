// SSL-Vision packets (ssl_vision_wrapper.proto) of a served field: one detection frame
// per camera frame with what the observer receives (robots in mm and rad, from a single
// camera, id 0), and the field's geometry.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/pose.h"
#include "engines/omni_engine.h"
#include "serve/team_roster.h"
#include "ssl_vision_wrapper.pb.h"

namespace twinsim {

// One robot seen in a frame.
struct Sighting {
  TeamRobot robot;
  Pose2 pose;  // field frame, m and rad
};

// The detection of camera frame `frame_number`: captured at `t_capture`, sent at
// `t_sent` (s), with the ball's centre at `ball` (m, field frame; z its height) when
// the camera saw one.
SSL_WrapperPacket DetectionPacket(const std::vector<Sighting>& seen, std::uint32_t frame_number, double t_capture,
                                  double t_sent, const std::optional<Eigen::Vector3d>& ball = std::nullopt);

// The geometry of `field` (walls, m) with a boundary of `boundary` m between the walls
// and the field lines: the field lines, goals of the league's size, the penalty areas
// and centre circle of division B, and the one camera's calibration.
SSL_WrapperPacket GeometryPacket(const FieldModel& field, double boundary);

}  // namespace twinsim

// SSL-Vision packets (ssl_vision_wrapper.proto) of a served field: one detection frame
// per camera and camera frame (robots in mm and rad; with one camera, id 0, what the
// observer receives; with several, scene/camera_layout.h, what each camera sees), and
// the field's geometry with each camera's calibration.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/pose.h"
#include "engines/omni_engine.h"
#include "scene/camera_layout.h"
#include "serve/team_roster.h"
#include "ssl_vision_wrapper.pb.h"

namespace twinsim {

// One robot seen in a frame.
struct Sighting {
  TeamRobot robot;
  Pose2 pose;  // field frame, m and rad
};

// The detection of frame `frame_number` of `camera` (null: the one camera, id 0, above
// the centre): captured at `t_capture`, sent at `t_sent` (s), with the ball's centre at
// `ball` (m, field frame; z its height) when the camera saw one. Pixels are a nominal
// pinhole projection from the camera's position.
SSL_WrapperPacket DetectionPacket(const std::vector<Sighting>& seen, std::uint32_t frame_number, double t_capture,
                                  double t_sent, const std::optional<Eigen::Vector3d>& ball = std::nullopt,
                                  const CameraView* camera = nullptr);

// The geometry of `field` (walls, m) with a boundary of `boundary` m between the walls
// and the field lines: the field lines, goals of the league's size, the penalty areas
// and centre circle of division B, and a nominal calibration of each of `cameras`
// (none: the one camera above the centre).
SSL_WrapperPacket GeometryPacket(const FieldModel& field, double boundary, const std::vector<CameraView>& cameras = {});

}  // namespace twinsim

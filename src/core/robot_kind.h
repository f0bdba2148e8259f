// The two kinds of robot twinsim simulates: what a model, scene or log is for.
#pragma once

namespace twinsim {

enum class RobotKind { kOmni, kArm };

// The word model and scene files use for it (`robot: arm`; omni is the default).
inline const char* RobotKindName(RobotKind kind) { return kind == RobotKind::kArm ? "arm" : "omni"; }

}  // namespace twinsim

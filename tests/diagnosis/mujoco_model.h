// A MuJoCo model and its data, freed together, loaded from text (the tests' plants from
// another engine: diagnosis/mujoco_arm_plant.h, analysis/emps_like_plant.h). Only where
// MuJoCo was found at configure time (TWINSIM_HAVE_MUJOCO).
#pragma once

#ifdef TWINSIM_HAVE_MUJOCO
#include <mujoco/mujoco.h>

#include <memory>
#include <string>

namespace twinsim {
namespace testing {

struct MujocoModel {
  mjModel* model = nullptr;
  mjData* data = nullptr;
  MujocoModel() = default;
  MujocoModel(const MujocoModel&) = delete;
  MujocoModel& operator=(const MujocoModel&) = delete;
  ~MujocoModel();
};

// `text` (MJCF, or URDF with extension ".urdf") through a temporary file of this process,
// as MuJoCo 2.2 reads only files; the data made for it. Throws std::runtime_error with
// MuJoCo's message, naming `what`.
std::unique_ptr<MujocoModel> LoadMujocoText(const std::string& text, const std::string& extension,
                                            const std::string& what);

}  // namespace testing
}  // namespace twinsim
#endif

// Keys set from outside a scene file (a batch sweep's `scene.*` and `plant.*`
// parameters, io/yaml_overrides.h): `scene` is laid over the scene file, `plant` over
// the model file(s) of the simulated robot (omni: every robot's model; arm: the plant's
// `model:`, never the controller's model, which keeps believing the file).
#pragma once

#include "io/yaml_overrides.h"

namespace twinsim {

struct SceneOverrides {
  YamlOverrides scene;
  YamlOverrides plant;

  bool empty() const { return scene.empty() && plant.empty(); }
};

}  // namespace twinsim

// The Python view of twinsim's models (python/model_binding.cc): an omni or arm model
// whose parameters read and write as dotted keys of its YAML form, checked by the
// model's own reader on every write; and the module's model classes and loaders.
#pragma once

#include <pybind11/pybind11.h>

#include <string>

#include <yaml-cpp/yaml.h>

#include "io/yaml_overrides.h"
#include "robots/arm/arm_model.h"
#include "robots/omni/omni_model.h"

namespace py = pybind11;

namespace twinsim {

// Python value -> YAML node (numbers, bools, strings, lists and dicts of them).
YAML::Node ToYaml(const py::handle& value);
// A YAML node -> the Python number, bool, string, list or dict it spells.
py::object NodeToPython(const YAML::Node& node);
// Every leaf of a document as "a.b.0.c" -> value into *out; lists of scalars are one value.
void Flatten(const YAML::Node& node, const std::string& prefix, py::dict* out);
// The node at a dotted key, or an invalid node.
YAML::Node Find(YAML::Node node, const std::string& key);

// A model as Python sees it: the struct and its YAML text, kept in step. Keys are read
// from and written to the YAML, which is then read back by the model's own reader, so
// a bad value gets the file's checks and messages.
template <typename Model>
struct PyModel {
  Model model;
  std::string Yaml() const;
  static Model Parse(const std::string& yaml, const std::string& name);

  py::object Get(const std::string& key) const {
    const YAML::Node node = Find(YAML::Load(Yaml()), key);
    if (!node.IsDefined()) throw py::key_error(key);
    return NodeToPython(node);
  }
  void Set(const std::string& key, const py::handle& value) {
    const YAML::Node root = ApplyYamlOverrides(YAML::Load(Yaml()), {{key, ToYaml(value)}}, model.name);
    YAML::Emitter out;
    out << root;
    model = Parse(out.c_str(), model.name + " (set " + key + ")");
  }
  py::dict Dict() const {
    py::dict flat;
    Flatten(YAML::Load(Yaml()), "", &flat);
    return flat;
  }
};

template <>
std::string PyModel<OmniModel>::Yaml() const;
template <>
OmniModel PyModel<OmniModel>::Parse(const std::string& yaml, const std::string& name);
template <>
std::string PyModel<ArmModel>::Yaml() const;
template <>
ArmModel PyModel<ArmModel>::Parse(const std::string& yaml, const std::string& name);

using PyOmniModel = PyModel<OmniModel>;
using PyArmModel = PyModel<ArmModel>;

// Binds OmniModel and ArmModel with their loaders (load_omni_model, load_arm_model,
// omni_model_from_yaml, arm_model_from_yaml, arm_model_from_urdf).
void BindModels(py::module_& m);

}  // namespace twinsim

#include "python/model_binding.h"

#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include <string>
#include <vector>

#include "core/error.h"
#include "robots/arm/arm_model_yaml_writer.h"
#include "robots/omni/omni_model_yaml_writer.h"

namespace twinsim {
namespace {

// YAML scalar -> the Python number, bool or string it spells.
py::object ScalarToPython(const YAML::Node& node) {
  const std::string text = node.Scalar();
  if (node.Tag() != "!") {  // unquoted: a number or bool where it spells one
    long long i = 0;
    double d = 0;
    if (YAML::convert<long long>::decode(node, i) && text.find_first_of(".eE") == std::string::npos) return py::int_(i);
    if (YAML::convert<double>::decode(node, d)) return py::float_(d);
    bool b = false;
    if (YAML::convert<bool>::decode(node, b)) return py::bool_(b);
  }
  return py::str(text);
}


template <typename Model>
void BindModelView(py::class_<PyModel<Model>>& cls) {
  cls.def_property_readonly("name", [](const PyModel<Model>& m) { return m.model.name; })
      .def("__getitem__", &PyModel<Model>::Get, py::arg("key"))
      .def("__setitem__", &PyModel<Model>::Set, py::arg("key"), py::arg("value"))
      .def("__contains__", [](const PyModel<Model>& m, const std::string& key) {
        return Find(YAML::Load(m.Yaml()), key).IsDefined();
      })
      .def("keys", [](const PyModel<Model>& m) { return m.Dict().attr("keys")(); })
      .def("to_dict", &PyModel<Model>::Dict, "Every parameter as a flat dict of dotted keys")
      .def("to_yaml", &PyModel<Model>::Yaml, "The model file's text (loads in every command)")
      .def("copy", [](const PyModel<Model>& m) { return PyModel<Model>(m); })
      .def("__copy__", [](const PyModel<Model>& m) { return PyModel<Model>(m); })
      .def("__deepcopy__", [](const PyModel<Model>& m, py::dict) { return PyModel<Model>(m); });
}

}  // namespace

// Python value -> YAML node (numbers, bools, strings, lists and dicts of them).
YAML::Node ToYaml(const py::handle& value) {
  if (value.is_none()) return YAML::Node(YAML::NodeType::Null);
  if (py::isinstance<py::bool_>(value)) return YAML::Node(value.cast<bool>());
  if (py::isinstance<py::int_>(value)) return YAML::Node(value.cast<long long>());
  if (py::isinstance<py::float_>(value)) return YAML::Node(value.cast<double>());
  if (py::isinstance<py::str>(value)) return YAML::Node(value.cast<std::string>());
  if (py::isinstance<py::dict>(value)) {
    YAML::Node map(YAML::NodeType::Map);
    for (const auto& [k, v] : value.cast<py::dict>()) map[py::str(k).cast<std::string>()] = ToYaml(v);
    return map;
  }
  if (py::isinstance<py::sequence>(value) || py::isinstance<py::array>(value)) {
    YAML::Node list(YAML::NodeType::Sequence);
    for (const auto& v : value) list.push_back(ToYaml(v));
    return list;
  }
  // NumPy scalars and anything else with __float__.
  if (py::hasattr(value, "__float__")) return YAML::Node(value.cast<double>());
  throw InputError("cannot set a model key to a value of type " + py::str(value.get_type()).cast<std::string>());
}

py::object NodeToPython(const YAML::Node& node) {
  if (node.IsScalar()) return ScalarToPython(node);
  if (node.IsSequence()) {
    py::list list;
    for (const auto& v : node) list.append(NodeToPython(v));
    return list;
  }
  if (node.IsMap()) {
    py::dict dict;
    for (const auto& kv : node) dict[py::str(kv.first.Scalar())] = NodeToPython(kv.second);
    return dict;
  }
  return py::none();
}

// Every leaf of a document as "a.b.0.c" -> value; lists of scalars are one value.
void Flatten(const YAML::Node& node, const std::string& prefix, py::dict* out) {
  if (node.IsMap()) {
    for (const auto& kv : node) {
      Flatten(kv.second, prefix.empty() ? kv.first.Scalar() : prefix + "." + kv.first.Scalar(), out);
    }
    return;
  }
  if (node.IsSequence()) {
    bool scalars = true;
    for (const auto& v : node) scalars = scalars && v.IsScalar();
    if (!scalars) {
      for (std::size_t i = 0; i < node.size(); ++i) Flatten(node[i], prefix + "." + std::to_string(i), out);
      return;
    }
  }
  (*out)[py::str(prefix)] = NodeToPython(node);
}

// The node at a dotted key, or an invalid node.
YAML::Node Find(YAML::Node node, const std::string& key) {
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = key.find('.', start);
    const std::string step = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (node.IsMap()) {
      node = node[step];
    } else if (node.IsSequence()) {
      std::size_t index = 0;
      try {
        index = std::stoul(step);
      } catch (const std::exception&) {
        return YAML::Node(YAML::NodeType::Undefined);
      }
      if (index >= node.size()) return YAML::Node(YAML::NodeType::Undefined);
      node = node[index];
    } else {
      return YAML::Node(YAML::NodeType::Undefined);
    }
    if (!node.IsDefined()) return node;
    if (dot == std::string::npos) return node;
    start = dot + 1;
  }
}


template <>
std::string PyModel<OmniModel>::Yaml() const { return FormatOmniModelYaml(model); }
template <>
OmniModel PyModel<OmniModel>::Parse(const std::string& yaml, const std::string& name) {
  return LoadOmniModelFromString(yaml, name);
}
template <>
std::string PyModel<ArmModel>::Yaml() const { return FormatArmModelYaml(model); }
template <>
ArmModel PyModel<ArmModel>::Parse(const std::string& yaml, const std::string& name) {
  return LoadArmModelFromYamlString(yaml, name);
}


void BindModels(py::module_& m) {
  py::class_<PyOmniModel> omni_model(m, "OmniModel", "An omni robot model (docs/models.md); keys as in its YAML");
  BindModelView(omni_model);
  omni_model.def_property_readonly("delay_frames", [](const PyOmniModel& m) {
    return m.model.command_delay_frames + m.model.vision_delay_frames;
  });
  py::class_<PyArmModel> arm_model(m, "ArmModel", "An arm model (URDF or YAML); keys as in its YAML form");
  BindModelView(arm_model);
  arm_model.def_property_readonly("dof", [](const PyArmModel& m) { return m.model.dof(); })
      .def_property_readonly("sample_time", [](const PyArmModel& m) { return m.model.sample_time; })
      .def_property_readonly("joint_names", [](const PyArmModel& m) {
        std::vector<std::string> names;
        for (const auto& j : m.model.joints) names.push_back(j.name);
        return names;
      });

  m.def("load_omni_model", [](const std::string& path) { return PyOmniModel{LoadOmniModel(path)}; }, py::arg("path"));
  m.def("load_arm_model", [](const std::string& path) { return PyArmModel{LoadArmModel(path)}; }, py::arg("path"));
  m.def("omni_model_from_yaml", [](const std::string& text, const std::string& name) {
    return PyOmniModel{LoadOmniModelFromString(text, name)};
  }, py::arg("text"), py::arg("name") = "(python)");
  m.def("arm_model_from_yaml", [](const std::string& text, const std::string& name) {
    return PyArmModel{LoadArmModelFromYamlString(text, name)};
  }, py::arg("text"), py::arg("name") = "(python)");
  m.def("arm_model_from_urdf", [](const std::string& text, const std::string& name) {
    return PyArmModel{LoadArmModelFromUrdfString(text, name)};
  }, py::arg("text"), py::arg("name") = "(python)");
}

}  // namespace twinsim

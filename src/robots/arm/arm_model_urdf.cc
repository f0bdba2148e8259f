// Reading an ArmModel from URDF through urdfdom. The chain is walked from the root link:
// the root is the fixed base; each revolute, continuous or prismatic joint adds one
// ArmJoint; fixed joints are lumped into the link before them (the lumped link keeps
// that link's frame). What urdfdom does not report (branches, loops, floating joints,
// missing inertials) is found here and reported with the line of the offending element.
#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <regex>
#include <string_view>
#include <vector>
#include <sstream>

#include "core/error.h"
#include "io/input_file.h"
#include "robots/arm/arm_model.h"
#include "robots/arm/arm_model_internal.h"

namespace twinsim {
namespace {

using arm_internal::AddBody;
using arm_internal::TransformBody;

// urdfdom reports its own parse errors through console_bridge; collect them instead of
// letting them reach the terminal. console_bridge's handler is global, hence the lock.
class ConsoleCapture : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors += (errors.empty() ? "" : "; ") + text;
  }
  std::string errors;
};

urdf::ModelInterfaceSharedPtr ParseQuietly(const std::string& xml, std::string* console) {
  static std::mutex mutex;
  std::lock_guard<std::mutex> lock(mutex);
  ConsoleCapture capture;
  console_bridge::useOutputHandler(&capture);
  urdf::ModelInterfaceSharedPtr model;
  try {
    // TinyXML (under urdfdom) steps over a UTF-8 sequence by its lead byte's length and
    // can step past the text's end; CheckUtf8 refuses such text first, and the padding
    // keeps any step it still takes inside this string.
    model = urdf::parseURDF(xml + std::string(8, '\0'));
  } catch (const std::exception& e) {
    capture.errors += (capture.errors.empty() ? "" : "; ") + std::string(e.what());
  }
  console_bridge::restorePreviousOutputHandler();
  *console = capture.errors;
  return model;
}

// The 1-based line of byte `offset` in `text`.
int LineAt(std::string_view text, std::size_t offset) {
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(offset), '\n'));
}

// Throws InputError "path:line: ..." at the first byte that does not start or continue a
// well-formed UTF-8 sequence (XML text is UTF-8 here; the fuzzer found that TinyXML reads
// past the end of text that ends inside a sequence).
void CheckUtf8(std::string_view text, const std::string& path) {
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    const int length = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    bool ok = length > 0 && i + static_cast<std::size_t>(length) <= text.size();
    for (int k = 1; ok && k < length; ++k) ok = (static_cast<unsigned char>(text[i + static_cast<std::size_t>(k)]) >> 6) == 0x2;
    if (!ok) {
      char byte[8];
      std::snprintf(byte, sizeof byte, "0x%02X", c);
      throw InputError(SourceLocation{path, LineAt(text, i)},
                       std::string("not UTF-8 text: byte ") + byte + " does not start a complete UTF-8 character");
    }
    i += static_cast<std::size_t>(length);
  }
}

// Finds where elements are defined, since urdfdom keeps no line numbers.
class LineFinder {
 public:
  explicit LineFinder(const std::string& xml) : text_(xml) {
    // Blank out comments (keeping line breaks) so that commented-out elements never match.
    for (std::size_t at = text_.find("<!--"); at != std::string::npos; at = text_.find("<!--", at)) {
      std::size_t end = text_.find("-->", at);
      end = end == std::string::npos ? text_.size() : end + 3;
      for (std::size_t k = at; k < end; ++k)
        if (text_[k] != '\n') text_[k] = ' ';
      at = end;
    }
  }

  // The line of the first `<sub` after the element `<tag name="name"` (a link's <mass>),
  // else the element's own line.
  int SubLine(const std::string& tag, const std::string& name, const std::string& sub) const {
    const int line = Line(tag, name);
    if (line == 0) return 0;
    std::size_t at = 0;
    for (int l = 1; l < line && at != std::string::npos; ++l) at = text_.find('\n', at) + 1;
    const std::size_t close = text_.find("</" + tag, at);
    const std::string open = "<" + sub;
    for (std::size_t found = text_.find(open, at); found != std::string::npos && found < close;
         found = text_.find(open, found + 1)) {
      const char next = found + open.size() < text_.size() ? text_[found + open.size()] : '>';
      if (std::isspace(static_cast<unsigned char>(next)) || next == '/' || next == '>') return LineOf(found);
    }
    return line;
  }

  // The 1-based line of `<tag ... name="name"`; for joints the definition (with a type
  // attribute) is preferred over references in transmissions. 0 when not found.
  int Line(const std::string& tag, const std::string& name) const {
    static const std::regex kName(R"re(\bname\s*=\s*(["'])(.*?)\1)re");
    static const std::regex kType(R"re(\btype\s*=)re");
    std::size_t fallback = std::string::npos;
    const std::string open = "<" + tag;
    for (std::size_t at = text_.find(open); at != std::string::npos; at = text_.find(open, at + 1)) {
      const std::size_t after = at + open.size();
      if (after >= text_.size() || !std::isspace(static_cast<unsigned char>(text_[after]))) continue;
      const std::size_t close = text_.find('>', after);
      const std::string element = text_.substr(after, close == std::string::npos ? std::string::npos : close - after);
      std::smatch m;
      if (!std::regex_search(element, m, kName) || m[2].str() != name) continue;
      if (tag != "joint" || std::regex_search(element, kType)) return LineOf(at);
      if (fallback == std::string::npos) fallback = at;
    }
    return fallback == std::string::npos ? 0 : LineOf(fallback);
  }

  // The file's text with comments blanked out (same lines and offsets).
  const std::string& text() const { return text_; }

 private:
  int LineOf(std::size_t offset) const { return LineAt(text_, offset); }
  std::string text_;
};

Eigen::Isometry3d ToEigen(const urdf::Pose& pose) {
  double x, y, z, w;
  pose.rotation.getQuaternion(x, y, z, w);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
  t.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  return t;
}

// A link's <inertial> expressed in the link's own frame.
ArmLink ReadInertial(const urdf::Link& link) {
  const urdf::Inertial& in = *link.inertial;
  ArmLink body;
  body.name = link.name;
  body.mass = in.mass;
  body.inertia << in.ixx, in.ixy, in.ixz,
                  in.ixy, in.iyy, in.iyz,
                  in.ixz, in.iyz, in.izz;
  body.com = Eigen::Vector3d::Zero();
  body = TransformBody(body, ToEigen(in.origin));
  return body;
}

std::string JointTypeName(int type) {
  switch (type) {
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    case urdf::Joint::FIXED: return "fixed";
    default: return "unknown";
  }
}

// urdfdom reads "nan" and "inf" as numbers (or as 0 where it gives up), so they are
// found in the text first, with their line.
void CheckFiniteAttributes(const std::string& xml, const std::string& path) {
  static const std::regex kBad(R"re(=\s*(["'])[^"']*?\b[-+]?(nan|inf|infinity)\b[^"']*\1)re", std::regex::icase);
  ErrorList errors;
  auto begin = std::sregex_iterator(xml.begin(), xml.end(), kBad);
  int count = 0;
  for (auto it = begin; it != std::sregex_iterator() && count < 10; ++it, ++count) {
    const int line = LineAt(xml, static_cast<std::size_t>(it->position()));
    errors.Add(SourceLocation{path, line}, "attribute value " + it->str().substr(it->str().find_first_of("\"'")) +
                                               " is not a finite number");
  }
  // urdfdom reads a mass it cannot parse ("heavy") as 0 without a word.
  static const std::regex kMass(R"re(<mass\s+value\s*=\s*(["'])([^"']*)\1)re");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), kMass); it != std::sregex_iterator(); ++it) {
    const std::string text = (*it)[2].str();
    char* end = nullptr;
    std::strtod(text.c_str(), &end);
    if (text.empty() || end == text.c_str() || *end != '\0') {
      const int line = LineAt(xml, static_cast<std::size_t>(it->position()));
      errors.Add(SourceLocation{path, line}, "mass value '" + text + "' is not a number");
    }
  }
  errors.ThrowIfAny();
}

// The value of attribute `name` in the element text `tag` ("" when absent). Plain string
// search: std::regex recurses per character and a long attribute would exhaust the stack.
std::string Attribute(std::string_view tag, std::string_view name) {
  for (std::size_t at = tag.find(name); at != std::string_view::npos; at = tag.find(name, at + 1)) {
    if (at > 0 && !std::isspace(static_cast<unsigned char>(tag[at - 1]))) continue;
    std::size_t k = at + name.size();
    while (k < tag.size() && std::isspace(static_cast<unsigned char>(tag[k]))) ++k;
    if (k >= tag.size() || tag[k] != '=') continue;
    ++k;
    while (k < tag.size() && std::isspace(static_cast<unsigned char>(tag[k]))) ++k;
    if (k >= tag.size() || (tag[k] != '"' && tag[k] != '\'')) continue;
    const std::size_t end = tag.find(tag[k], k + 1);
    if (end == std::string_view::npos) return "";
    return std::string(tag.substr(k + 1, end - k - 1));
  }
  return "";
}

// urdfdom refuses a closed loop of joints only as "no root link" (and leaks the links it
// built), so loops are found in the text first: each <joint>'s parent and child link,
// then a walk from every link up its parents. Reported at the joint that closes the loop.
// `text` is the file with comments blanked (LineFinder::text()): a commented-out joint
// closes nothing.
void CheckJointLoops(const std::string& text_in, const std::string& path) {
  struct Edge {
    std::string joint, parent;
    int line = 0;
  };
  std::map<std::string, Edge> up;  // child link -> the joint naming it and its parent
  const std::string_view text(text_in);
  auto element = [&](std::size_t from, std::size_t until, std::string_view open) -> std::string_view {
    const std::size_t at = text.find(open, from);
    if (at == std::string_view::npos || at >= until) return {};
    const std::size_t close = text.find('>', at);
    return text.substr(at, close == std::string_view::npos ? std::string_view::npos : close - at);
  };
  for (std::size_t at = text.find("<joint"); at != std::string_view::npos; at = text.find("<joint", at + 1)) {
    if (at + 6 >= text.size() || !std::isspace(static_cast<unsigned char>(text[at + 6]))) continue;
    const std::size_t tag_end = text.find('>', at);
    if (tag_end == std::string_view::npos) break;
    const std::size_t end = text.find("</joint", tag_end);
    if (end == std::string_view::npos) break;
    const std::string parent = Attribute(element(tag_end, end, "<parent"), "link");
    const std::string child = Attribute(element(tag_end, end, "<child"), "link");
    if (parent.empty() || child.empty()) continue;
    const int line = LineAt(text, at);
    up.emplace(child, Edge{Attribute(text.substr(at, tag_end - at), "name"), parent, line});
  }
  for (const auto& [start, first] : up) {
    std::vector<std::string> chain{start};
    std::string link = start;
    for (std::size_t steps = 0; steps <= up.size(); ++steps) {
      const auto next = up.find(link);
      if (next == up.end()) break;
      link = next->second.parent;
      chain.push_back(link);
      if (link != start) continue;
      std::string loop;
      for (auto l = chain.rbegin(); l != chain.rend(); ++l) loop += (loop.empty() ? "" : " -> ") + *l;
      throw InputError(SourceLocation{path, first.line},
                       "joint '" + first.joint + "' closes a loop of links (" + loop +
                           "): an arm is a serial chain from a root link");
    }
  }
}

// A link's mass and inertia, checked as the YAML reader checks them.
void CheckInertial(const urdf::Link& link, const LineFinder& lines, const std::string& path, ErrorList* errors) {
  const urdf::Inertial& in = *link.inertial;
  if (!(in.mass > 0 && in.mass <= 1e5)) {
    std::ostringstream s;
    s << "link '" << link.name << "': mass must be positive and at most 1e+05 kg, got " << in.mass;
    errors->Add(SourceLocation{path, lines.SubLine("link", link.name, "mass")}, s.str());
  }
  const SourceLocation where{path, lines.SubLine("link", link.name, "inertia")};
  for (const double v : {in.ixx, in.iyy, in.izz, in.ixy, in.ixz, in.iyz}) {
    if (!(std::abs(v) <= 1e5)) {
      std::ostringstream s;
      s << "link '" << link.name << "': inertia entries must be within +-1e+05 kg m^2, got " << v;
      errors->Add(where, s.str());
      break;
    }
  }
}

ArmModel ReadUrdf(const std::string& xml, const std::string& path) {
  // urdfdom takes seconds over a file of 100,000 joints; an arm has a few.
  constexpr int kMaxJointElements = 1000;  // fixed ones (tool frames, sensors) included
  int joint_elements = 0;
  for (std::size_t at = xml.find("<joint"); at != std::string::npos; at = xml.find("<joint", at + 1)) {
    if (++joint_elements > kMaxJointElements) {
      throw InputError(SourceLocation{path}, "the URDF has more than " + std::to_string(kMaxJointElements) +
                                                 " joint elements; an arm has at most " +
                                                 std::to_string(kMaxArmJoints) + " moving joints");
    }
  }
  CheckUtf8(xml, path);
  CheckFiniteAttributes(xml, path);
  const LineFinder lines(xml);
  CheckJointLoops(lines.text(), path);
  std::string console;
  const urdf::ModelInterfaceSharedPtr urdf = ParseQuietly(xml, &console);
  if (!urdf) {
    std::string message = "not a valid URDF";
    if (!console.empty()) message += ": " + console;
    if (console.find("root") != std::string::npos)
      message += " (a closed loop of joints has no root link; an arm must be a serial chain)";
    throw InputError(SourceLocation{path}, message);
  }
  auto at_joint = [&](const std::string& name) { return SourceLocation{path, lines.Line("joint", name)}; };
  auto at_link = [&](const std::string& name) { return SourceLocation{path, lines.Line("link", name)}; };

  // Problems anywhere in the file, whether or not the walk below would reach them.
  ErrorList errors;
  std::map<std::string, std::vector<std::string>> parents;  // child link -> joints naming it
  for (const auto& [name, joint] : urdf->joints_) {
    parents[joint->child_link_name].push_back(name);
    const int type = joint->type;
    if (type != urdf::Joint::REVOLUTE && type != urdf::Joint::CONTINUOUS && type != urdf::Joint::PRISMATIC &&
        type != urdf::Joint::FIXED) {
      errors.Add(at_joint(name), "joint '" + name + "' is " + JointTypeName(type) +
                                     "; an arm is a fixed-base serial chain of revolute, continuous, "
                                     "prismatic and fixed joints");
    }
    if (joint->mimic) errors.Add(at_joint(name), "joint '" + name + "' mimics another joint; mimic joints are not supported");
  }
  for (const auto& [child, joints] : parents) {
    if (joints.size() < 2) continue;
    std::string list;
    for (const auto& j : joints) list += (list.empty() ? "'" : ", '") + j + "'";
    errors.Add(at_link(child), "link '" + child + "' is the child of " + std::to_string(joints.size()) +
                                   " joints (" + list + "): a closed loop, which a serial chain cannot express");
  }
  if (urdf->joints_.size() > static_cast<std::size_t>(kMaxArmJoints)) {
    errors.Add(SourceLocation{path}, "the URDF has " + std::to_string(urdf->joints_.size()) + " joints; at most " +
                                         std::to_string(kMaxArmJoints) + " are supported");
  }
  for (const auto& [name, link] : urdf->links_) {
    if (link->inertial) CheckInertial(*link, lines, path, &errors);
  }
  errors.ThrowIfAny();

  ArmModel model;
  model.name = urdf->getName();
  model.source_path = path;
  // From the frame of the last moving link (or the base) to the current URDF link.
  Eigen::Isometry3d pending = Eigen::Isometry3d::Identity();
  urdf::LinkConstSharedPtr link = urdf->getRoot();
  while (link && !link->child_joints.empty()) {
    if (link->child_joints.size() > 1) {
      std::string list;
      for (const auto& j : link->child_joints) list += (list.empty() ? "'" : ", '") + j->name + "'";
      errors.Add(at_link(link->name), "link '" + link->name + "' has " + std::to_string(link->child_joints.size()) +
                                          " child joints (" + list + "): a branch; an arm must be a single serial chain");
      break;
    }
    const urdf::JointSharedPtr joint = link->child_joints.front();
    const urdf::LinkConstSharedPtr child = urdf->getLink(joint->child_link_name);
    const Eigen::Isometry3d to_joint = pending * ToEigen(joint->parent_to_joint_origin_transform);

    if (joint->type == urdf::Joint::FIXED) {
      // Rigidly attached: lump its mass into the moving link before it (the base's
      // attachments carry no load the joints feel). A massless attachment, such as a
      // flange or tool frame at the tip, is fine.
      if (!model.joints.empty() && child->inertial) {
        AddBody(&model.joints.back().child, TransformBody(ReadInertial(*child), to_joint));
      }
      pending = to_joint;
      link = child;
      continue;
    }

    ArmJoint j;
    j.name = joint->name;
    j.type = joint->type == urdf::Joint::PRISMATIC ? JointType::kPrismatic : JointType::kRevolute;
    j.origin = to_joint;
    const Eigen::Vector3d axis(joint->axis.x, joint->axis.y, joint->axis.z);
    if (axis.norm() < 1e-9) {
      errors.Add(at_joint(joint->name), "joint '" + joint->name + "' has a zero axis");
    } else {
      j.axis = axis.normalized();
    }
    if (joint->limits) {
      if (joint->type != urdf::Joint::CONTINUOUS) {
        j.lower = joint->limits->lower;
        j.upper = joint->limits->upper;
        if (!(j.lower < j.upper)) {
          std::ostringstream s;
          s << "joint '" << joint->name << "': lower limit " << j.lower << " must be below upper limit " << j.upper;
          errors.Add(at_joint(joint->name), s.str());
        }
      }
      j.velocity_limit = joint->limits->velocity;
      j.effort_limit = joint->limits->effort;
    }
    if (joint->dynamics) {
      j.viscous = joint->dynamics->damping;
      j.coulomb = joint->dynamics->friction;
    }
    if (child->inertial) {
      j.child = ReadInertial(*child);
    } else {
      errors.Add(at_link(child->name), "link '" + child->name + "', moved by joint '" + joint->name +
                                           "', has no <inertial>; every moving link needs a mass and inertia");
    }
    j.child.name = child->name;
    model.joints.push_back(j);
    pending = Eigen::Isometry3d::Identity();
    link = child;
  }
  errors.ThrowIfAny();
  if (model.joints.empty()) throw InputError(SourceLocation{path}, "the URDF has no revolute, continuous or prismatic joint");
  // The model's own checks, each with the line of the link or joint element it names.
  const std::string problems = model.Validate();
  if (!problems.empty()) {
    static const std::regex kLink(R"re(link '([^']*)')re");
    static const std::regex kJoint(R"re(^joint \d+ '([^']*)')re");
    std::istringstream text(problems);
    std::string line;
    while (std::getline(text, line)) {
      std::smatch m;
      // A link's problem ("joint 1 'j1', link 'l1': ...") at the link's element.
      if (!std::regex_search(line, kLink) && std::regex_search(line, m, kJoint)) {
        const char* sub = line.find("limit") != std::string::npos      ? "limit"
                          : line.find("axis") != std::string::npos     ? "axis"
                          : line.find("origin") != std::string::npos   ? "origin"
                          : line.find("friction") != std::string::npos ? "dynamics"
                                                                       : "joint";
        errors.Add(SourceLocation{path, lines.SubLine("joint", m[1].str(), sub)}, line);
        continue;
      }
      if (!std::regex_search(line, m, kLink)) {
        errors.Add(SourceLocation{path}, line);
        continue;
      }
      const char* sub = line.find("inertia") != std::string::npos ? "inertia"
                        : line.find("mass") != std::string::npos ? "mass" : "inertial";
      errors.Add(SourceLocation{path, lines.SubLine("link", m[1].str(), sub)}, line);
    }
    errors.ThrowIfAny();
  }
  return model;
}

}  // namespace

namespace arm_internal {

ArmModel LoadArmUrdfFile(const std::string& path) {
  constexpr std::uintmax_t kMaxUrdfBytes = std::uintmax_t{64} << 20;
  return ReadUrdf(ReadInputFile(path, "URDF", kMaxUrdfBytes), path);
}

}  // namespace arm_internal

ArmModel LoadArmModelFromUrdfString(const std::string& xml, const std::string& name) { return ReadUrdf(xml, name); }

}  // namespace twinsim

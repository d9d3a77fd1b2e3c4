// URDF loader (urdfdom). Maps a serial chain onto robot_model.hpp's conventions: every movable
// joint's frame is rotated so that its axis is local z; fixed joints are merged.
#include <fmt/format.h>
#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "twinwatch/core/error.hpp"
#include "twinwatch/core/file_io.hpp"
#include "twinwatch/model/description_io.hpp"

namespace twinwatch::model {

namespace {

Eigen::Isometry3d to_iso(const urdf::Pose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  return T;
}

// inertial block of a link, expressed in the link frame (zero body if absent)
RigidBodyInertia link_inertia(const urdf::Link& link) {
  RigidBodyInertia b;
  if (!link.inertial) return b;
  const urdf::Inertial& in = *link.inertial;
  RigidBodyInertia local;
  local.mass = in.mass;
  local.inertia_com << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  // inertial frame -> link frame
  return local.expressed_in(to_iso(in.origin));
}

// 1-based line of the first byte that is not part of a valid UTF-8 sequence, 0 if all are.
// TinyXML 2.6 (under urdfdom) skips a multi-byte sequence by its lead byte's length without looking
// for the end of the text, so a file ending in a truncated sequence made it read past its buffer
// (found by fuzzing: fuzz/regressions/description_urdf).
int first_invalid_utf8_line(const std::string& text) {
  int line = 1;
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    const std::size_t len = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    if (len == 0 || i + len > text.size()) return line;
    for (std::size_t k = 1; k < len; ++k)
      if ((static_cast<unsigned char>(text[i + k]) >> 6) != 0x2) return line;
    if (c == '\n') ++line;
    i += len;
  }
  return 0;
}

// urdfdom reports what it could not read through console_bridge and goes on: a link whose
// <mass value="abc"/> is not a number loses its whole <inertial> block and loads as a massless
// link, with only a line on stderr. While parsing, this handler collects those reports so that the
// loader can refuse the file instead; console_bridge's handler is process-wide, hence the mutex.
class CollectUrdfdomErrors : public console_bridge::OutputHandler {
 public:
  CollectUrdfdomErrors() : lock_(mutex()), previous_(console_bridge::getOutputHandler()) { console_bridge::useOutputHandler(this); }
  ~CollectUrdfdomErrors() override { console_bridge::useOutputHandler(previous_); }
  CollectUrdfdomErrors(const CollectUrdfdomErrors&) = delete;
  CollectUrdfdomErrors& operator=(const CollectUrdfdomErrors&) = delete;

  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors_.push_back(text);
  }
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  std::lock_guard<std::mutex> lock_;
  console_bridge::OutputHandler* previous_;
  std::vector<std::string> errors_;
};

// urdfdom's messages quote the offending value in brackets ("mass [abc] is not a float"): the
// 1-based line of the first attribute holding one of those values, 0 if none is found
int line_of_quoted_value(const std::string& text, const std::vector<std::string>& messages) {
  for (const std::string& m : messages) {
    for (std::size_t open = m.find('['); open != std::string::npos; open = m.find('[', open + 1)) {
      const std::size_t close = m.find(']', open);
      if (close == std::string::npos) break;
      const std::string needle = "\"" + m.substr(open + 1, close - open - 1) + "\"";
      const std::size_t at = text.find(needle);
      if (close > open + 1 && at != std::string::npos)
        return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
    }
  }
  return 0;
}

// 1-based line of the element `<TAG name="NAME"` in the text (0 if not found)
int line_of_element(const std::string& text, const std::string& tag, const std::string& name) {
  for (const char q : {'"', '\''}) {
    const std::string needle = std::string("name=") + q + name + q;
    for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) {
      const size_t open = text.rfind('<', at);
      if (open != std::string::npos && text.compare(open + 1, tag.size(), tag) == 0)
        return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(open), '\n'));
    }
  }
  return 0;
}

// rotation taking z onto the unit axis a
Eigen::Matrix3d z_onto(const Eigen::Vector3d& a) {
  return Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), a).toRotationMatrix();
}

}  // namespace

RobotDescription load_description_urdf(const std::string& path, const std::string& base_link, const std::string& tip_link) {
  const std::string text = read_text_file(path);
  if (const int line = first_invalid_utf8_line(text))
    throw ParseError(path, line, "", "not valid UTF-8 text (a URDF file is XML in UTF-8)");
  // (a file that is no XML at all was said as urdfdom's "Error document empty ... (urdfdom would load
  // the rest and leave this part out)": audit of session 56)
  if (text.find("<robot") == std::string::npos)
    throw ParseError(path, 0, "", "not a URDF: no <robot> element (a URDF is an XML file whose root is <robot name=\"...\">)");
  urdf::ModelInterfaceSharedPtr urdf_model;
  {
    CollectUrdfdomErrors collect;
    try {
      urdf_model = urdf::parseURDF(text);
    } catch (const std::exception& e) {
      throw ParseError(path, 0, "", fmt::format("not a valid URDF: {}", e.what()));
    }
    if (!collect.errors().empty()) {
      std::string what;
      for (const std::string& e : collect.errors()) what += (what.empty() ? "" : "; ") + e;
      throw ParseError(path, line_of_quoted_value(text, collect.errors()), "",
                       fmt::format("not a valid URDF: {} (urdfdom would load the rest and leave this part out)", what));
    }
  }
  if (!urdf_model) throw ParseError(path, 0, "", "not a valid URDF (urdfdom could not parse it: check the XML and that every joint names existing links)");

  // a joint whose child is its own parent, or joints that lead back to a link above them: urdfdom
  // takes both, and every walk up the tree below went round for ever (found by fuzzing: a joint's
  // parent and child both 'link2', session 57)
  // a link that two joints name as their child: urdfdom keeps one of them and drops the other
  // without a word (review of session 57: base->l1 and l2->l1 loaded as three joints of four)
  std::map<std::string, std::string> parent_joint_of;
  for (const auto& [name, joint] : urdf_model->joints_)
    if (const auto [at, fresh] = parent_joint_of.emplace(joint->child_link_name, name); !fresh)
      throw ParseError(path, std::max(line_of_element(text, "joint", at->second), line_of_element(text, "joint", name)), "joint",
                       fmt::format("link '{}' is the child of two joints, '{}' and '{}', expected a tree (each link the child of "
                                   "one joint, none below itself)",
                                   joint->child_link_name, at->second, name));
  for (const auto& [first, joint] : urdf_model->joints_) {
    std::set<std::string> seen;
    for (urdf::LinkConstSharedPtr l = urdf_model->getLink(joint->child_link_name); l && l->parent_joint;
         l = urdf_model->getLink(l->parent_joint->parent_link_name)) {
      seen.insert(l->name);
      // the joint that leads up to a link already passed is the one that closes the loop
      const urdf::JointConstSharedPtr& up = l->parent_joint;
      if (seen.count(up->parent_link_name))
        throw ParseError(path, line_of_element(text, "joint", up->name), "joint",
                         fmt::format("joint '{}' (parent '{}', child '{}') closes a loop: {}, expected a tree (each link the "
                                     "child of one joint, none below itself)",
                                     up->name, up->parent_link_name, up->child_link_name,
                                     up->parent_link_name == up->child_link_name ? "its child is its own parent"
                                                                                 : "the links above its child lead back to it"));
    }
  }
  // chain ends: root (or base_link) and the single leaf (or tip_link)
  const std::string base = base_link.empty() ? urdf_model->getRoot()->name : base_link;
  if (!urdf_model->getLink(base)) throw ParseError(path, 0, "link", fmt::format("base link '{}' does not exist", base));
  std::string tip = tip_link;
  if (tip.empty()) {
    // the leaf below the most revolute/continuous joints: a description with frames beside the
    // chain (a massless 'base' or 'tool0', a sensor frame) has several leaves, but one arm
    std::vector<std::string> leaves;
    for (const auto& [name, link] : urdf_model->links_)
      if (link->child_links.empty()) leaves.push_back(name);
    auto movable = [&](const std::string& leaf) {
      int count = 0;
      for (urdf::LinkConstSharedPtr l = urdf_model->getLink(leaf); l && l->parent_joint && l->name != base;
           l = urdf_model->getLink(l->parent_joint->parent_link_name))
        count += l->parent_joint->type == urdf::Joint::REVOLUTE || l->parent_joint->type == urdf::Joint::CONTINUOUS ? 1 : 0;
      return count;
    };
    int most = -1;
    std::vector<std::string> best;
    for (const auto& l : leaves) {
      const int c = movable(l);
      if (c > most) best.clear();
      if (c >= most) {
        most = c;
        best.push_back(l);
      }
    }
    if (best.size() != 1) {
      std::string list;
      for (const auto& l : best) list += (list.empty() ? "" : ", ") + l;
      throw ParseError(path, 0, "link",
                       fmt::format("the tree has {} leaves below {} revolute joints ({}), expected one: name the tip link "
                                   "after the file, e.g. --robot {}#{}",
                                   best.size(), most, list, path, best.front()));
    }
    tip = best.front();
  }
  if (!urdf_model->getLink(tip)) throw ParseError(path, 0, "link", fmt::format("tip link '{}' does not exist", tip));

  // joints from tip up to base, then reversed
  std::vector<urdf::JointConstSharedPtr> chain;
  for (urdf::LinkConstSharedPtr l = urdf_model->getLink(tip); l->name != base;) {
    if (!l->parent_joint)
      throw ParseError(path, 0, "link", fmt::format("link '{}' is not below base link '{}'", tip, base));
    chain.push_back(l->parent_joint);
    l = urdf_model->getLink(l->parent_joint->parent_link_name);
  }
  std::reverse(chain.begin(), chain.end());

  RobotDescription d;
  d.name = urdf_model->getName();
  d.source = path;
  // T_acc: from the current body frame (or the base) to the frame reached so far
  Eigen::Isometry3d T_acc = Eigen::Isometry3d::Identity();
  bool have_body = false;
  for (const auto& j : chain) {
    const Eigen::Isometry3d origin = to_iso(j->parent_to_joint_origin_transform);
    // unit slips the JSON reader refuses too (description_io.cpp): an origin in mm, a negative
    // limit (urdfdom reads them; velocity="-1" left the joint without a speed limit, audit of session 56)
    const int line = line_of_element(text, "joint", j->name);
    if (!(origin.translation().norm() <= kMaxDescriptionLength))
      throw ParseError(path, line, fmt::format("joint '{}'.origin", j->name),
                       fmt::format("expected an offset within {:g} m, got one of {:.4g} m (in mm? give metres)", kMaxDescriptionLength,
                                   origin.translation().norm()));
    if (j->limits)
      for (const auto& [key, v] : {std::pair{"velocity", j->limits->velocity}, std::pair{"effort", j->limits->effort}})
        if (!(v >= 0.0))
          throw ParseError(path, line, fmt::format("joint '{}'.limit.{}", j->name, key),
                           fmt::format("expected a limit >= 0 (0: not published), got {}", v));
    if (const urdf::Link& child = *urdf_model->getLink(j->child_link_name); child.inertial) {
      const urdf::Vector3& c = child.inertial->origin.position;
      if (!(std::sqrt(c.x * c.x + c.y * c.y + c.z * c.z) <= kMaxDescriptionLength))
        throw ParseError(path, line_of_element(text, "link", child.name), fmt::format("link '{}'.inertial.origin", child.name),
                         fmt::format("expected a centre of mass within {:g} m of the link's frame (in mm? give metres)", kMaxDescriptionLength));
    }
    const urdf::Link& child = *urdf_model->getLink(j->child_link_name);
    if (j->type == urdf::Joint::FIXED) {
      T_acc = T_acc * origin;
      if (have_body) {
        Joint& last = d.joints.back();
        last.body = last.body + link_inertia(child).expressed_in(T_acc);
      }
      continue;
    }
    if (j->type != urdf::Joint::REVOLUTE && j->type != urdf::Joint::CONTINUOUS)
      throw ParseError(path, 0, fmt::format("joint '{}'", j->name), "only revolute, continuous and fixed joints are supported");
    const Eigen::Vector3d axis(j->axis.x, j->axis.y, j->axis.z);
    if (!(axis.norm() > 0.0)) throw ParseError(path, 0, fmt::format("joint '{}'.axis", j->name), "axis is zero");
    Eigen::Isometry3d R_axis = Eigen::Isometry3d::Identity();
    R_axis.linear() = z_onto(axis.normalized());
    Joint jt;
    jt.name = j->name;
    jt.placement = T_acc * origin * R_axis;
    // the child link frame seen from the body frame is R_axis^-1
    const Eigen::Isometry3d body_T_link = R_axis.inverse();
    jt.body = link_inertia(child).expressed_in(body_T_link);
    if (j->type == urdf::Joint::REVOLUTE && j->limits) {
      jt.limits.q_min = j->limits->lower;
      jt.limits.q_max = j->limits->upper;
    }
    if (j->limits) {
      if (j->limits->velocity > 0.0) jt.limits.qd_max = j->limits->velocity;
      if (j->limits->effort > 0.0) jt.limits.torque_max = j->limits->effort;
    }
    d.joints.push_back(jt);
    T_acc = body_T_link;
    have_body = true;
  }
  if (d.joints.empty()) throw ParseError(path, 0, "joint", fmt::format("no movable joint between '{}' and '{}'", base, tip));
  d.flange = T_acc;
  try {
    RobotModel check(d);
  } catch (const InvalidArgument& e) {
    throw ParseError(path, 0, "joints", e.what());
  }
  check_holds_itself(d, path);
  return d;
}

}  // namespace twinwatch::model

// Reading a command's inputs: knobs, shape specs, poses, pose sequences.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "rtcd/config.hpp"
#include "rtcd/geometry.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::app {

// The accuracy knobs a command was given (the command line's --NAME and
// --no-NAME options, Python's keyword arguments), in order.
struct Knobs {
  std::vector<std::pair<const Knob*, KnobValue>> set;
  void apply(Config& config) const;  // sets what these knobs set, leaves the rest
  Config config() const;             // the default Config with these knobs set
};
// A knob's name as the command line spells it: distance-extension.
std::string option_name(const Knob& knob);

// "sphere:R", "box:HX,HY,HZ", a mesh file (.obj .off .ply .stl), or a body of a
// validation family, "family:NAME:a" or "family:NAME:b" (to replay its cases).
// Warns on stderr, once, when a mesh crosses itself.
std::shared_ptr<const Shape> parse_shape(const std::string& spec, double sampling, const MeshOptions& options);

// Prints the warning of self_intersection_warning() for a shape's mesh.
void warn_if_self_intersecting(const Shape& shape, const std::string& name);

// Seven numbers tx ty tz qw qx qy qz as a checked pose; UsageError naming
// `what` when the quaternion is not a rotation.
Pose pose_from(const double* v, const std::string& what);
// "tx ty tz qw qx qy qz" (spaces or commas).
Pose parse_pose(const std::string& text, const std::string& what);

struct SequenceStep {
  Pose a, b;
};
// A JSON array of {"pose_a": [7 numbers], "pose_b": [7 numbers]}.
std::vector<SequenceStep> read_sequence(const std::string& path);

}  // namespace rtcd::app

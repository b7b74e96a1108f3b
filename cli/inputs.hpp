// Reading the command line's inputs: shape specs, poses, pose sequences.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "rtcd/geometry.hpp"
#include "rtcd/shape.hpp"

namespace rtcd::cli {

// "sphere:R", "box:HX,HY,HZ" or a mesh file (.obj .off .ply .stl).
std::shared_ptr<const Shape> parse_shape(const std::string& spec, double sampling, bool allow_zero_area);

// "tx ty tz qw qx qy qz" (spaces or commas).
Pose parse_pose(const std::string& text, const std::string& what);

struct SequenceStep {
  Pose a, b;
};
// A JSON array of {"pose_a": [7 numbers], "pose_b": [7 numbers]}.
std::vector<SequenceStep> read_sequence(const std::string& path);

}  // namespace rtcd::cli

// The mesh checker behind `rtcd check`: what a mesh file holds and which of
// its defects change what "inside" means for the method (section 1.3: a
// vertex is inside when its inward ray leaves the other surface through a
// back face, which holds only for a closed, consistently oriented surface
// that does not cross itself).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rtcd/export.hpp"
#include "rtcd/geometry.hpp"
#include "rtcd/mesh.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

// One kind of finding: how many there are and the first few, by file id.
struct MeshFinding {
  std::string name;         // snake_case key, e.g. "self_intersections"
  std::string element;      // what one example lists: "edge", "vertex", "triangle", "triangle pair", ...
  bool defect = false;      // changes inside/outside answers: the mesh is not fit for the method
  std::string meaning;      // one line: what it is and what it does to the method
  size_t count = 0;
  std::vector<std::vector<uint32_t>> examples;  // the first kMaxExamples, in file order
};

struct MeshCheck {
  static constexpr size_t kMaxExamples = 10;
  size_t vertices = 0, triangles = 0;
  size_t components = 0;  // of triangles joined through shared vertices
  bool closed = false;    // no boundary edge
  double signed_volume = 0;
  Aabb bounds;
  std::vector<MeshFinding> findings;  // every kind, always in the same order

  bool fit() const;  // no finding that is a defect has a count
  const MeshFinding& finding(std::string_view name) const;  // throws std::out_of_range
};

// Checks positions and triangles as given (file ids); never throws on a
// defect, only reports it.
MeshCheck check_mesh(std::span<const Eigen::Vector3f> positions, std::span<const Mesh::Triangle> triangles);

// Pairs of triangles (lower id first, sorted) whose surfaces cross away from
// the vertices and edges they share; vertices at identical positions count
// as shared. A bounding-volume tree over the triangles finds the candidates;
// the test runs in double. Stops after `limit` pairs.
std::vector<std::array<uint32_t, 2>> self_intersections(std::span<const Eigen::Vector3f> positions,
                                                        std::span<const Mesh::Triangle> triangles,
                                                        size_t limit = SIZE_MAX);

// What a host says once when a body it loads crosses itself: the name, the
// count and the first crossing triangle pairs, and what that does to the
// contacts. Empty when the surface does not cross itself.
std::string self_intersection_warning(const Mesh& mesh, const std::string& name);

RTCD_PUBLIC_END
}  // namespace rtcd

// The committed mesh set: file name and how the generator makes it. Shared
// by the generator and by the test that holds the files to it.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "rtcd/mesh_gen.hpp"

namespace rtcd::data {

struct MeshRecipe {
  std::string file;
  std::function<Mesh()> make;
};

inline std::vector<MeshRecipe> committed_meshes() {
  return {
      // The thesis' concave class (453 vertices, 902 triangles) and the
      // stream scene's four meshes.
      {"blob_902.obj", [] { return gen::concave_blob(902, 1); }},
      {"stream_902.obj", [] { return gen::concave_blob(902, 2); }},
      {"stream_2130.obj", [] { return gen::concave_blob(2130, 3); }},
      {"stream_3456.obj", [] { return gen::concave_blob(3456, 4); }},
      {"stream_3458.obj", [] { return gen::concave_blob(3458, 5); }},
      {"torus.obj", [] { return gen::torus(1.0, 0.35, 48, 24); }},
      {"open_sheet.obj", [] { return gen::open_sheet(16, 2.0, 0.1); }},
      {"box.obj", [] { return gen::box({0.5, 0.5, 0.5}); }},
      {"icosphere.obj", [] { return gen::icosphere(1.0, 3); }},
      {"u_shape.obj", [] { return gen::u_shape(); }},
  };
}

}  // namespace rtcd::data

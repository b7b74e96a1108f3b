// Writes the committed meshes (data/meshes/) from their generators.
#include <cstdio>
#include <filesystem>

#include "meshes.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: rtcd_make_meshes OUTPUT_DIR\n");
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);
  for (const auto& recipe : rtcd::data::committed_meshes()) {
    const rtcd::Mesh mesh = recipe.make();
    rtcd::save_obj(mesh, dir / recipe.file);
    std::printf("%-18s %6zu vertices %6zu triangles%s\n", recipe.file.c_str(), mesh.vertex_count(),
                mesh.triangle_count(), mesh.report().open() ? " (open)" : "");
  }
  return 0;
}

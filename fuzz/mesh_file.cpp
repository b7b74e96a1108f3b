// libFuzzer harness: mesh files through rtcd::read_mesh_file, the mesh
// checker (rtcd check) and validation. The first byte picks the extension
// (.obj .off .ply .stl), MeshOptions::allow_zero_area and ::weld; the rest is
// the file. MeshError is the one accepted failure; the checker never throws
// and agrees with validation; a loaded mesh must hold together (indices,
// adjacency, unit normals).
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <fuzzer/FuzzedDataProvider.h>
#include <unistd.h>

#include "invariants.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh.hpp"
#include "rtcd/mesh_check.hpp"

namespace {

using rtcd::fuzz::require;

// The checker's report holds together, and a mesh it finds fit (zero-area
// triangles aside, which validation takes only when allowed) validates.
void check_report(const rtcd::MeshData& d, const rtcd::MeshCheck& c, const rtcd::MeshOptions& options) {
  require(c.vertices == d.positions.size() && c.triangles == d.triangles.size(), "checker miscounted");
  for (const auto& f : c.findings) {
    require(f.examples.size() <= f.count && f.examples.size() <= rtcd::MeshCheck::kMaxExamples, "bad examples");
    const size_t limit = f.element == "triangle" || f.element == "triangle pair" ? d.triangles.size()
                                                                                  : d.positions.size();
    for (const auto& e : f.examples)
      for (uint32_t id : e) require(f.element == "mesh" || id < limit, "example id out of range");
  }
  const bool zero_area_ok = options.allow_zero_area || c.finding("zero_area_triangles").count == 0;
  if (c.fit() && zero_area_ok) {
    try {
      rtcd::Mesh(d.positions, d.triangles, options);
    } catch (const rtcd::MeshError& e) {
      require(false, (std::string("checker found the mesh fit, validation refused it: ") + e.what()).c_str());
    }
  }
}

void check_mesh(const rtcd::Mesh& m) {
  require(m.vertex_count() > 0 && m.triangle_count() > 0, "loaded an empty mesh");
  const auto tris = m.triangles();
  const auto neighbors = m.neighbors();
  for (size_t t = 0; t < tris.size(); ++t) {
    for (uint32_t v : tris[t]) require(v < m.vertex_count(), "triangle index out of range");
    for (int e = 0; e < 3; ++e) {
      const int32_t n = neighbors[t][e];
      if (n == rtcd::Mesh::no_neighbor) continue;
      require(n >= 0 && size_t(n) < tris.size() && size_t(n) != t, "neighbour out of range");
      // Adjacency is symmetric: the neighbour names this triangle back.
      const auto& back = neighbors[n];
      require(back[0] == int32_t(t) || back[1] == int32_t(t) || back[2] == int32_t(t), "adjacency not symmetric");
    }
    const Eigen::Vector3f& n = m.triangle_normals()[t];
    require(m.zero_area()[t] ? n.isZero() : rtcd::fuzz::unit(n.cast<double>()), "triangle normal not unit");
  }
  for (const Eigen::Vector3f& n : m.vertex_normals())
    require(n.isZero() || rtcd::fuzz::unit(n.cast<double>()), "vertex normal neither zero nor unit");
  require(std::isfinite(m.radius()) && m.radius() >= 0, "radius not finite");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  const auto head = in.ConsumeBytes<uint8_t>(1);  // the first byte (integers would come from the end)
  const uint8_t selector = head.empty() ? 0 : head[0];
  static const char* const extensions[] = {".obj", ".off", ".ply", ".stl"};
  // One file per process: parallel fuzzing jobs must not share it.
  static const std::filesystem::path base =
      std::filesystem::temp_directory_path() / ("rtcd_fuzz_mesh_file_" + std::to_string(::getpid()));
  std::filesystem::path path = base;
  path += extensions[selector % 4];
  {
    const auto body = in.ConsumeRemainingBytes<char>();
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(body.data(), std::streamsize(body.size()));
  }
  rtcd::MeshOptions options;
  options.allow_zero_area = (selector >> 2) & 1;
  const bool weld = (selector >> 3) & 1;
  static const bool verbose = std::getenv("RTCD_FUZZ_VERBOSE") != nullptr;
  try {
    rtcd::MeshData data = rtcd::read_mesh_file(path);
    if (weld) rtcd::weld_coincident(data.positions, data.triangles);
    check_report(data, rtcd::check_mesh(data.positions, data.triangles), options);
    const rtcd::Mesh mesh(std::move(data.positions), std::move(data.triangles), options);
    check_mesh(mesh);
    if (verbose) std::fprintf(stderr, "loaded %zu vertices, %zu triangles\n", mesh.vertex_count(), mesh.triangle_count());
  } catch (const rtcd::MeshError& e) {
    // Unreadable or invalid files are rejected by design.
    if (verbose) std::fprintf(stderr, "MeshError: %s\n", e.what());
  }
  std::error_code ec;
  std::filesystem::remove(path, ec);
  return 0;
}

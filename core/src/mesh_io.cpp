// Mesh files: OBJ, OFF, PLY and STL read through assimp; OBJ written.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <unordered_map>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "rtcd/error.hpp"
#include "rtcd/mesh.hpp"

namespace rtcd {
namespace {

[[noreturn]] void file_error(const std::filesystem::path& path, const std::string& what) {
  throw MeshError(MeshErrorKind::file, {}, {}, path.string() + ": " + what);
}

struct PositionKey {
  uint32_t bits[3];
  bool operator==(const PositionKey& o) const { return std::memcmp(bits, o.bits, sizeof bits) == 0; }
};
struct PositionHash {
  size_t operator()(const PositionKey& k) const {
    return (size_t(k.bits[0]) * 73856093u) ^ (size_t(k.bits[1]) * 19349663u) ^ (size_t(k.bits[2]) * 83492791u);
  }
};

}  // namespace

Mesh Mesh::load(const std::filesystem::path& path, MeshOptions options) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    file_error(path, "unsupported mesh format '" + ext + "' (expected .obj, .off, .ply or .stl)");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) file_error(path, "no such file");

  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path.string(), 0);
  if (scene == nullptr) file_error(path, std::string("cannot read: ") + importer.GetErrorString());
  // Points and lines are no surface. Rejected before post-processing: a face
  // of no corners (a truncated OFF file) gets flagged a polygon, and
  // triangulating it fails an assertion that aborts the process (Debian's
  // assimp 5.2 is built with ai_assert on).
  for (unsigned m = 0; m < scene->mNumMeshes; ++m)
    for (unsigned f = 0; f < scene->mMeshes[m]->mNumFaces; ++f)
      if (const unsigned n = scene->mMeshes[m]->mFaces[f].mNumIndices; n < 3)
        file_error(path, "face " + std::to_string(f) + " of mesh " + std::to_string(m) + " has " + std::to_string(n) +
                             " corners; only polygons of three or more are surfaces");
  // Triangulate polygons; keep every triangle as written (no degenerate
  // removal, no vertex joining: validation must see the file as it is).
  scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_PreTransformVertices);
  if (scene == nullptr) file_error(path, std::string("cannot read: ") + importer.GetErrorString());
  if (scene->mNumMeshes == 0) file_error(path, "file holds no mesh");

  std::vector<Eigen::Vector3f> positions;
  std::vector<Triangle> triangles;
  std::unordered_map<PositionKey, uint32_t, PositionHash> index_of;
  size_t face_number = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    for (unsigned f = 0; f < mesh->mNumFaces; ++f, ++face_number) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3)
        file_error(path, "face " + std::to_string(face_number) + " has " + std::to_string(face.mNumIndices) +
                             " corners; only polygons of three or more are surfaces");
      Triangle tri;
      for (int k = 0; k < 3; ++k) {
        const unsigned i = face.mIndices[k];
        if (i >= mesh->mNumVertices) file_error(path, "face " + std::to_string(face_number) + " has a bad index");
        const aiVector3D& p = mesh->mVertices[i];
        PositionKey key;
        const float xyz[3] = {p.x, p.y, p.z};
        std::memcpy(key.bits, xyz, sizeof xyz);
        auto [it, inserted] = index_of.try_emplace(key, uint32_t(positions.size()));
        if (inserted) positions.emplace_back(p.x, p.y, p.z);
        tri[k] = it->second;
      }
      triangles.push_back(tri);
    }
  }
  try {
    return Mesh(std::move(positions), std::move(triangles), options);
  } catch (const MeshError& e) {
    throw MeshError(e.kind(), e.vertex(), e.triangle(), path.string() + ": " + e.what());
  }
}

void save_obj(const Mesh& mesh, const std::filesystem::path& path) {
  std::ofstream out(path);
  if (!out) throw MeshError(MeshErrorKind::file, {}, {}, path.string() + ": cannot open for writing");
  char line[128];
  out << "# " << mesh.vertex_count() << " vertices, " << mesh.triangle_count() << " triangles\n";
  for (const auto& p : mesh.positions()) {
    std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", p.x(), p.y(), p.z());
    out << line;
  }
  for (const auto& t : mesh.triangles()) out << "f " << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << '\n';
  if (!out) throw MeshError(MeshErrorKind::file, {}, {}, path.string() + ": write failed");
}

}  // namespace rtcd

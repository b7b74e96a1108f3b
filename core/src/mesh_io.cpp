// Mesh files: OBJ, OFF, PLY and STL read through assimp; OBJ written.
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
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

// Debian's assimp 5.2 crashes on OFF files whose lines do not match their
// header's counts and loops forever on a PLY header with no end_header; such
// files are rejected here, before assimp reads them, naming the line.
void check_off(const std::filesystem::path& path, std::istream& in) {
  std::vector<std::vector<std::string>> lines;  // tokens of each non-empty, non-comment line
  std::vector<size_t> numbers;                   // their line numbers in the file
  std::string line;
  for (size_t n = 1; std::getline(in, line); ++n) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::vector<std::string> tokens;
    for (std::string w; words >> w;) tokens.push_back(w);
    if (tokens.empty()) continue;
    lines.push_back(std::move(tokens));
    numbers.push_back(n);
  }
  auto bad = [&](size_t i, const std::string& what) {
    const size_t line_number = i < numbers.size() ? numbers[i] : (numbers.empty() ? 1 : numbers.back() + 1);
    file_error(path, "line " + std::to_string(line_number) + ": " + what);
  };
  auto integer = [](const std::string& t, long long& v) {
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && end == t.data() + t.size();
  };
  auto real = [](const std::string& t) {
    char* end = nullptr;
    std::strtod(t.c_str(), &end);
    return !t.empty() && end == t.c_str() + t.size();
  };
  if (lines.empty() || lines[0][0].find("OFF") == std::string::npos) bad(0, "an OFF file starts with OFF");
  // The counts follow the keyword on its line or on the next.
  size_t i = lines[0].size() > 1 ? 0 : 1;
  const size_t first_count = lines[0].size() > 1 ? 1 : 0;
  if (i >= lines.size() || lines[i].size() < first_count + 2) bad(i, "expected the counts: vertices faces [edges]");
  long long vertices = 0, faces = 0;
  if (!integer(lines[i][first_count], vertices) || !integer(lines[i][first_count + 1], faces) || vertices < 0 ||
      faces < 0)
    bad(i, "the vertex and face counts must be integers >= 0");
  ++i;
  if (lines.size() - i < size_t(vertices) + size_t(faces))
    bad(lines.size(), "the header declares " + std::to_string(vertices) + " vertices and " + std::to_string(faces) +
                          " faces; the file has " + std::to_string(lines.size() - i) + " lines after it");
  for (long long v = 0; v < vertices; ++v, ++i)
    if (lines[i].size() < 3 || !real(lines[i][0]) || !real(lines[i][1]) || !real(lines[i][2]))
      bad(i, "vertex " + std::to_string(v) + ": expected three numbers");
  for (long long f = 0; f < faces; ++f, ++i) {
    long long corners = 0;
    if (!integer(lines[i][0], corners) || corners < 3 || lines[i].size() < size_t(corners) + 1)
      bad(i, "face " + std::to_string(f) + ": expected a corner count >= 3 and that many vertex indices");
    for (long long k = 1; k <= corners; ++k) {
      long long index = 0;
      if (!integer(lines[i][size_t(k)], index) || index < 0 || index >= vertices)
        bad(i, "face " + std::to_string(f) + ": '" + lines[i][size_t(k)] + "' is not a vertex index below " +
                   std::to_string(vertices));
    }
  }
}

void check_ply(const std::filesystem::path& path, std::istream& in) {
  std::string line;
  for (size_t n = 1; n <= 10000 && std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == "end_header") return;
  }
  file_error(path, "PLY header has no end_header line");
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

  if (ext == ".off" || ext == ".ply") {
    std::ifstream in(path, std::ios::binary);
    if (!in) file_error(path, "cannot open");
    ext == ".off" ? check_off(path, in) : check_ply(path, in);
  }

  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path.string(), 0);
  if (scene == nullptr) file_error(path, std::string("cannot read: ") + importer.GetErrorString());
  // Points and lines are no surface, and an index past the vertex array (a
  // corrupt binary PLY) is no face. Both are rejected before
  // post-processing, which aborts on the first (an assertion Debian's
  // assimp 5.2 keeps on) and reads out of bounds on the second.
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      const std::string where = "face " + std::to_string(f) + " of mesh " + std::to_string(m);
      if (face.mNumIndices < 3)
        file_error(path, where + " has " + std::to_string(face.mNumIndices) +
                             " corners; only polygons of three or more are surfaces");
      for (unsigned k = 0; k < face.mNumIndices; ++k)
        if (face.mIndices[k] >= mesh->mNumVertices)
          file_error(path, where + " uses vertex " + std::to_string(face.mIndices[k]) + " of " +
                               std::to_string(mesh->mNumVertices));
    }
  }
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

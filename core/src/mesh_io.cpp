// Mesh files as their authors wrote them: OBJ (tinyobjloader), OFF (read
// here), PLY and STL (assimp); OBJ written.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <sstream>
#include <vector>

#include <assimp/Importer.hpp>
#include <assimp/scene.h>
#include <tiny_obj_loader.h>

#include "rtcd/error.hpp"
#include "rtcd/mesh.hpp"

namespace rtcd {
namespace {

[[noreturn]] void file_error(const std::filesystem::path& path, const std::string& what) {
  throw MeshError(MeshErrorKind::file, {}, {}, path.string() + ": " + what);
}

// Tokens of each non-empty line with comments cut, and the line numbers.
struct Lines {
  std::vector<std::vector<std::string>> tokens;
  std::vector<size_t> numbers;
};

Lines read_lines(std::istream& in) {
  Lines out;
  std::string line;
  for (size_t n = 1; std::getline(in, line); ++n) {
    if (const auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::istringstream words(line);
    std::vector<std::string> tokens;
    for (std::string w; words >> w;) tokens.push_back(w);
    if (tokens.empty()) continue;
    out.tokens.push_back(std::move(tokens));
    out.numbers.push_back(n);
  }
  return out;
}

// Appends the fan of one face, (c0, ck, ck+1), to the triangle list.
void add_face(MeshData& data, std::span<const uint32_t> corners) {
  for (size_t k = 1; k + 1 < corners.size(); ++k) data.triangles.push_back({corners[0], corners[k], corners[k + 1]});
}

// OFF, read here: assimp 5.2 renumbers its vertices and crashes on files
// whose lines do not match the header. Every line is checked and named.
MeshData read_off(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) file_error(path, "cannot open");
  const Lines file = read_lines(in);
  const auto& lines = file.tokens;
  auto bad = [&](size_t i, const std::string& what) {
    const size_t line_number =
        i < file.numbers.size() ? file.numbers[i] : (file.numbers.empty() ? 1 : file.numbers.back() + 1);
    file_error(path, "line " + std::to_string(line_number) + ": " + what);
  };
  auto integer = [](const std::string& t, long long& v) {
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    return ec == std::errc() && end == t.data() + t.size();
  };
  auto real = [](const std::string& t, float& v) {
    char* end = nullptr;
    v = std::strtof(t.c_str(), &end);
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
  MeshData data;
  data.positions.reserve(size_t(vertices));
  for (long long v = 0; v < vertices; ++v, ++i) {
    Eigen::Vector3f p;
    if (lines[i].size() < 3 || !real(lines[i][0], p.x()) || !real(lines[i][1], p.y()) || !real(lines[i][2], p.z()))
      bad(i, "vertex " + std::to_string(v) + ": expected three numbers");
    data.positions.push_back(p);
  }
  std::vector<uint32_t> corners;
  for (long long f = 0; f < faces; ++f, ++i) {
    long long count = 0;
    if (!integer(lines[i][0], count) || count < 3 || lines[i].size() < size_t(count) + 1)
      bad(i, "face " + std::to_string(f) + ": expected a corner count >= 3 and that many vertex indices");
    corners.clear();
    for (long long k = 1; k <= count; ++k) {
      long long index = 0;
      if (!integer(lines[i][size_t(k)], index) || index < 0 || index >= vertices)
        bad(i, "face " + std::to_string(f) + ": '" + lines[i][size_t(k)] + "' is not a vertex index below " +
                   std::to_string(vertices));
      corners.push_back(uint32_t(index));
    }
    add_face(data, corners);
  }
  return data;
}

// OBJ through tinyobjloader, which keeps the file's vertex list and indices
// (assimp gives every face corner a vertex of its own).
MeshData read_obj(const std::filesystem::path& path) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;  // fanned below, the same way for every format
  config.vertex_color = false;
  config.mtl_search_path = path.parent_path().string();
  tinyobj::ObjReader reader;
  if (!reader.ParseFromFile(path.string(), config)) {
    std::string what = reader.Error();
    while (!what.empty() && (what.back() == '\n' || what.back() == '\r')) what.pop_back();
    file_error(path, "cannot read: " + (what.empty() ? std::string("not an OBJ file") : what));
  }
  MeshData data;
  const auto& v = reader.GetAttrib().vertices;
  data.positions.reserve(v.size() / 3);
  for (size_t i = 0; i + 2 < v.size(); i += 3) data.positions.emplace_back(v[i], v[i + 1], v[i + 2]);
  size_t face_number = 0;
  std::vector<uint32_t> corners;
  for (const auto& shape : reader.GetShapes()) {
    size_t next = 0;
    for (const unsigned char count : shape.mesh.num_face_vertices) {
      const std::string where = "face " + std::to_string(face_number++);
      if (count < 3 || next + count > shape.mesh.indices.size())
        file_error(path, where + " has " + std::to_string(count) + " corners; only polygons of three or more are surfaces");
      corners.clear();
      for (size_t k = 0; k < count; ++k) {
        const int index = shape.mesh.indices[next + k].vertex_index;
        if (index < 0 || size_t(index) >= data.positions.size())
          file_error(path, where + " uses vertex " + std::to_string(index) + " of " +
                               std::to_string(data.positions.size()));
        corners.push_back(uint32_t(index));
      }
      next += count;
      add_face(data, corners);
    }
  }
  return data;
}

// The size in bytes of a PLY scalar type, 0 for an unknown one.
int ply_type_size(const std::string& type) {
  static const std::map<std::string, int> sizes = {
      {"char", 1},  {"uchar", 1},  {"int8", 1},  {"uint8", 1},  {"short", 2},   {"ushort", 2},  {"int16", 2},  {"uint16", 2},
      {"int", 4},   {"uint", 4},   {"int32", 4}, {"uint32", 4}, {"float", 4},   {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = sizes.find(type);
  return it == sizes.end() ? 0 : it->second;
}

// A value of an ASCII PLY body as assimp reads one: a sign, then a digit or
// a point and a digit, and nothing left over (assimp throws on anything else
// and leaks the mesh it was building).
bool is_ply_number(const std::string& v) {
  const size_t d = v[0] == '+' || v[0] == '-' ? 1 : 0;
  const auto digit = [&](size_t i) { return i < v.size() && std::isdigit(static_cast<unsigned char>(v[i])); };
  if (!digit(d) && !(d < v.size() && v[d] == '.' && digit(d + 1))) return false;
  char* end = nullptr;
  std::strtod(v.c_str(), &end);
  return end == v.c_str() + v.size();
}

// The vertex count a PLY file declares. The header is checked line by line,
// and the body against it (an ASCII body line by line, a binary one by its
// sizes), before assimp reads the file: assimp 5.2 loops forever on a
// header that does not end or a body shorter than its counts, corrupts its
// heap on a malformed header (an unknown keyword or property type, an
// element declared twice), and allocates whatever count a body's list
// states.
size_t ply_vertex_count(const std::filesystem::path& path) {
  struct Property {
    int size = 0;        // bytes of a value
    int count_size = 0;  // lists: bytes of the count before the values; 0: a scalar
  };
  struct Element {
    std::string name;
    long long count = 0;
    std::vector<Property> properties;
  };
  std::ifstream in(path, std::ios::binary);
  if (!in) file_error(path, "cannot open");
  std::string line;
  long long vertices = -1;
  std::string format;
  std::vector<Element> elements;
  size_t n = 0;
  auto bad = [&](const std::string& part, const std::string& why) {
    std::string shown = line.substr(0, 60);
    for (char& c : shown)
      if (!std::isprint(static_cast<unsigned char>(c))) c = '?';  // the message stays one printable line
    file_error(path, "PLY " + part + " line " + std::to_string(n) + " (\"" + shown + "\"): " + why);
  };
  for (bool header = true; header;) {
    if (n == 10000 || !std::getline(in, line)) file_error(path, "PLY header has no end_header line");
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (n == 1) {
      if (line != "ply") bad("header", "expected \"ply\"");
    } else if (keyword == "end_header") {
      // A binary body starts right after this line; assimp reads a line
      // that goes on past the keyword otherwise than this check does.
      if (line != "end_header") bad("header", "end_header must stand alone on its line");
      if (vertices < 0) file_error(path, "PLY header declares no vertex element");
      header = false;
    } else if (keyword == "format") {
      words >> format;
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        bad("header", "unknown format (expected ascii, binary_little_endian or binary_big_endian)");
    } else if (keyword == "element") {
      Element e;
      if (!(words >> e.name >> e.count) || e.count < 0) bad("header", "expected \"element <name> <count>\"");
      if (std::any_of(elements.begin(), elements.end(), [&](const Element& o) { return o.name == e.name; }))
        bad("header", "element \"" + e.name + "\" is declared twice");
      if (e.name == "vertex") vertices = e.count;
      elements.push_back(e);
    } else if (keyword == "property") {
      if (elements.empty()) bad("header", "a property before any element");
      std::string type, count_type, name;
      words >> type;
      if (type == "list") words >> count_type >> type;
      Property p{ply_type_size(type), count_type.empty() ? 0 : ply_type_size(count_type)};
      if (p.size == 0 || (!count_type.empty() && p.count_size == 0))
        bad("header", "unknown property type (expected char, uchar, short, ushort, int, uint, float or double)");
      if (count_type == "float" || count_type == "float32" || count_type == "double" || count_type == "float64")
        bad("header", "a list count of a floating-point type");
      if (!(words >> name)) bad("header", "a property without a name");
      elements.back().properties.push_back(p);
    } else if (keyword != "comment" && keyword != "obj_info") {
      bad("header", "unknown header keyword \"" + keyword + "\"");
    }
  }
  if (format.empty()) file_error(path, "PLY header has no format line");
  if (format != "ascii") {
    // Element by element through the bytes, each list by its count.
    const std::string body{std::istreambuf_iterator<char>(in), {}};
    const bool big = format == "binary_big_endian";
    size_t at = 0;
    for (const Element& e : elements)
      for (long long i = 0; i < e.count; ++i)
        for (const Property& p : e.properties) {
          auto short_body = [&] {
            file_error(path, "PLY body ends at " + e.name + " " + std::to_string(i) + " of " + std::to_string(e.count));
          };
          long long values = 1;
          if (p.count_size > 0) {
            if (body.size() - at < size_t(p.count_size)) short_body();
            uint64_t count = 0;
            for (int b = 0; b < p.count_size; ++b) {
              const uint64_t byte = static_cast<unsigned char>(body[at + size_t(big ? b : p.count_size - 1 - b)]);
              count = (count << 8) | byte;
            }
            at += size_t(p.count_size);
            values = (long long)count;  // a signed count's negative values read as huge ones, which the body cannot hold
          }
          if (uint64_t(values) > (body.size() - at) / uint64_t(p.size)) short_body();
          at += size_t(values) * size_t(p.size);
        }
    return size_t(vertices);
  }
  // One element per line, its values as the header lays them out.
  for (const Element& e : elements)
    for (long long i = 0; i < e.count; ++i) {
      if (!std::getline(in, line))
        file_error(path, "PLY body ends at " + e.name + " " + std::to_string(i) + " of " + std::to_string(e.count));
      ++n;
      std::istringstream words(line);
      const std::vector<std::string> values{std::istream_iterator<std::string>(words), {}};
      size_t k = 0;
      for (const Property& p : e.properties) {
        if (k >= values.size()) bad("body", "fewer values than the header's " + e.name + " properties");
        long long count = -1;
        const std::string& v = values[k];
        if (p.count_size > 0 && (std::from_chars(v.data(), v.data() + v.size(), count).ptr != v.data() + v.size() ||
                                 count < 0 || size_t(count) >= values.size() - k))
          bad("body", "list count \"" + v.substr(0, 20) + "\" is not the number of values that follow it");
        const size_t next = p.count_size > 0 ? k + 1 + size_t(count) : k + 1;
        for (size_t j = p.count_size > 0 ? k + 1 : k; j < next; ++j)
          if (!is_ply_number(values[j])) bad("body", "\"" + values[j].substr(0, 20) + "\" is not a number");
        k = next;
      }
      if (k != values.size()) bad("body", "more values than the header's " + e.name + " properties");
    }
  return size_t(vertices);
}

// PLY and STL through assimp, without post-processing: assimp keeps a PLY's
// vertex list as written; an STL has one vertex per facet corner.
MeshData read_with_assimp(const std::filesystem::path& path, bool ply) {
  const size_t declared_vertices = ply ? ply_vertex_count(path) : 0;
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path.string(), 0);
  if (scene == nullptr) file_error(path, std::string("cannot read: ") + importer.GetErrorString());
  if (scene->mNumMeshes == 0) file_error(path, "file holds no mesh");
  MeshData data;
  std::vector<uint32_t> corners;
  size_t face_number = 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    const uint32_t offset = uint32_t(data.positions.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v)
      data.positions.emplace_back(mesh->mVertices[v].x, mesh->mVertices[v].y, mesh->mVertices[v].z);
    for (unsigned f = 0; f < mesh->mNumFaces; ++f, ++face_number) {
      const aiFace& face = mesh->mFaces[f];
      const std::string where = "face " + std::to_string(face_number);
      if (face.mNumIndices < 3)
        file_error(path, where + " has " + std::to_string(face.mNumIndices) +
                             " corners; only polygons of three or more are surfaces");
      corners.clear();
      for (unsigned k = 0; k < face.mNumIndices; ++k) {
        if (face.mIndices[k] >= mesh->mNumVertices)
          file_error(path, where + " uses vertex " + std::to_string(face.mIndices[k]) + " of " +
                               std::to_string(mesh->mNumVertices));
        corners.push_back(offset + face.mIndices[k]);
      }
      add_face(data, corners);
    }
  }
  if (ply && data.positions.size() != declared_vertices)
    file_error(path, "the header declares " + std::to_string(declared_vertices) + " vertices; " +
                         std::to_string(data.positions.size()) + " were read");
  if (!ply) weld_coincident(data.positions, data.triangles);
  return data;
}

}  // namespace

MeshData read_mesh_file(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    file_error(path, "unsupported mesh format '" + ext + "' (expected .obj, .off, .ply or .stl)");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) file_error(path, "no such file");
  MeshData data = ext == ".off" ? read_off(path) : ext == ".obj" ? read_obj(path) : read_with_assimp(path, ext == ".ply");
  if (data.triangles.empty()) file_error(path, "file holds no faces");
  return data;
}

Mesh Mesh::load(const std::filesystem::path& path, MeshOptions options) {
  MeshData data = read_mesh_file(path);
  try {
    return Mesh(std::move(data.positions), std::move(data.triangles), options);
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

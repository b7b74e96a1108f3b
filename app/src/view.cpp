// `rtcd view`: a recorded run to watch. A page (index.html, its script,
// Debian's three.js and the run's data as scripts, so it opens from file://)
// or one glTF 2.0 binary written by assimp's exporter.
#include "rtcd/app/view.hpp"

#include <assimp/Exporter.hpp>
#include <assimp/material.h>
#include <assimp/scene.h>
extern "C" {
#include <b64/cencode.h>  // a C header without extern "C" of its own
}
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <vector>

#include "rtcd/error.hpp"
#include "rtcd/experiments/replay.hpp"
#include "rtcd/sim/recording.hpp"
#include "rtcd/sim/render.hpp"
#include "rtcd/sim/simulation.hpp"

namespace fs = std::filesystem;

namespace rtcd::app {
namespace {

aiMesh* to_ai(const sim::RenderMesh& t, const std::string& name, unsigned material) {
  auto* m = new aiMesh;
  m->mName = name;
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  m->mMaterialIndex = material;
  m->mNumVertices = unsigned(t.positions.size());
  m->mVertices = new aiVector3D[m->mNumVertices];
  for (size_t i = 0; i < t.positions.size(); ++i)
    m->mVertices[i] = aiVector3D(t.positions[i].x(), t.positions[i].y(), t.positions[i].z());
  m->mNumFaces = unsigned(t.triangles.size());
  m->mFaces = new aiFace[m->mNumFaces];
  for (size_t f = 0; f < t.triangles.size(); ++f) {
    m->mFaces[f].mNumIndices = 3;
    m->mFaces[f].mIndices = new unsigned[3]{t.triangles[f][0], t.triangles[f][1], t.triangles[f][2]};
  }
  return m;
}

aiMaterial* material(const Eigen::Vector3f& rgb) {
  const aiColor4D colour(rgb.x(), rgb.y(), rgb.z(), 1);
  auto* m = new aiMaterial;
  m->AddProperty(&colour, 1, AI_MATKEY_COLOR_DIFFUSE);
  m->AddProperty(&colour, 1, AI_MATKEY_BASE_COLOR);
  return m;
}

// Every step's poses; a body not yet in the scene keeps its first pose
// until it appears at first_step.
struct Frames {
  std::vector<std::vector<Pose>> poses;
  std::vector<size_t> first_step;
  Aabb box;  // the bodies' positions over the run, the ground's apart
  size_t ground_body = SIZE_MAX;
};

Frames read_frames(const sim::Recording& recording) {
  const std::vector<uint32_t>& kinds = recording.kinds();
  Frames f;
  f.first_step.assign(kinds.size(), 0);
  sim::RecordedFrame frame;
  sim::Recording::Cursor cursor(recording);
  while (cursor.next(frame)) {
    for (size_t b = f.poses.empty() ? 0 : f.poses.back().size(); b < frame.poses.size(); ++b)
      f.first_step[b] = f.poses.size();
    f.poses.push_back(frame.poses);
    for (size_t b = 0; b < frame.poses.size(); ++b)
      if (kinds[b] != sim::Simulation::kGroundKind) f.box.extend(frame.poses[b].position);
  }
  if (f.box.empty()) f.box.extend(Eigen::Vector3d::Zero());
  for (size_t b = 0; b < kinds.size(); ++b)
    if (kinds[b] == sim::Simulation::kGroundKind) f.ground_body = b;
  return f;
}

// The ground's square in its own frame: around the bodies' centre seen from there.
sim::RenderMesh ground_look(const Frames& f) {
  const Eigen::Vector3d centre = 0.5 * (f.box.min + f.box.max);
  const double half = 0.75 * (f.box.max - f.box.min).norm() + 1.0;
  const Eigen::Vector3d local =
      f.ground_body != SIZE_MAX ? f.poses[f.first_step[f.ground_body]][f.ground_body].inverse().apply(centre) : centre;
  return sim::ground_square(local, half);
}

// Each body's label, as the simulation named it: the kind's, numbered
// when the kind has several bodies.
std::vector<std::string> body_labels(const sim::Recording& recording) {
  const sim::Scene& scene = recording.scene();
  std::vector<uint32_t> seen(scene.bodies.size(), 0);
  std::vector<std::string> labels;
  for (uint32_t kind : recording.kinds()) {
    if (kind == sim::Simulation::kGroundKind) {
      labels.push_back("ground");
      continue;
    }
    const sim::BodySpec& spec = scene.bodies[kind];
    const uint32_t n = seen[kind]++;
    labels.push_back(spec.count > 1 || spec.emitter ? spec.label + "#" + std::to_string(n) : spec.label);
  }
  return labels;
}

void write_gltf(const sim::Recording& recording, const std::string& path) {
  const std::vector<uint32_t>& kinds = recording.kinds();
  const sim::Scene& scene = recording.scene();
  const std::vector<std::shared_ptr<const Shape>> shapes = sim::make_shapes(scene);
  const Frames frames = read_frames(recording);
  const auto& poses = frames.poses;
  const auto& first_step = frames.first_step;
  auto out = std::make_unique<aiScene>();
  // One mesh and material per kind (the ground's last).
  const unsigned ground_mesh = unsigned(shapes.size());
  out->mNumMeshes = ground_mesh + 1;
  out->mMeshes = new aiMesh*[out->mNumMeshes]();
  out->mNumMaterials = out->mNumMeshes;
  out->mMaterials = new aiMaterial*[out->mNumMaterials]();
  for (unsigned k = 0; k < shapes.size(); ++k) {
    out->mMeshes[k] = to_ai(sim::look_of(*shapes[k]), scene.bodies[k].label, k);
    out->mMaterials[k] = material(scene.bodies[k].is_static ? sim::kStaticColour : sim::kind_colour(k));
  }
  out->mMeshes[ground_mesh] = to_ai(ground_look(frames), "ground", ground_mesh);
  out->mMaterials[ground_mesh] = material(sim::kGroundColour);

  out->mRootNode = new aiNode(scene.name);
  aiNode* root = out->mRootNode;
  root->mNumChildren = unsigned(kinds.size());
  root->mChildren = new aiNode*[root->mNumChildren]();
  auto* animation = new aiAnimation;
  out->mNumAnimations = 1;
  out->mAnimations = new aiAnimation*[1]{animation};
  animation->mName = "recording";
  animation->mTicksPerSecond = 1.0 / scene.time_step;
  animation->mDuration = double(poses.size() - 1);
  animation->mNumChannels = unsigned(kinds.size());
  animation->mChannels = new aiNodeAnim*[animation->mNumChannels]();
  for (size_t b = 0; b < kinds.size(); ++b) {
    const bool ground = kinds[b] == sim::Simulation::kGroundKind;
    const std::string name = "body " + std::to_string(b) + ": " + (ground ? std::string("ground") : scene.bodies[kinds[b]].label);
    const Pose& start = poses[first_step[b]][b];
    auto* node = new aiNode(name);
    node->mParent = root;
    node->mNumMeshes = 1;
    node->mMeshes = new unsigned[1]{ground ? ground_mesh : kinds[b]};
    const Eigen::Matrix3d r = start.orientation.toRotationMatrix();
    node->mTransformation = aiMatrix4x4(aiMatrix3x3(float(r(0, 0)), float(r(0, 1)), float(r(0, 2)), float(r(1, 0)),
                                                    float(r(1, 1)), float(r(1, 2)), float(r(2, 0)), float(r(2, 1)),
                                                    float(r(2, 2))));
    node->mTransformation.a4 = float(start.position.x());
    node->mTransformation.b4 = float(start.position.y());
    node->mTransformation.c4 = float(start.position.z());
    root->mChildren[b] = node;

    auto* channel = new aiNodeAnim;
    channel->mNodeName = name;
    channel->mNumPositionKeys = channel->mNumRotationKeys = channel->mNumScalingKeys = unsigned(poses.size());
    channel->mPositionKeys = new aiVectorKey[poses.size()];
    channel->mRotationKeys = new aiQuatKey[poses.size()];
    channel->mScalingKeys = new aiVectorKey[poses.size()];
    for (size_t s = 0; s < poses.size(); ++s) {
      const bool present = s >= first_step[b];
      const Pose& p = present ? poses[s][b] : start;
      channel->mPositionKeys[s] = {double(s), aiVector3D(float(p.position.x()), float(p.position.y()), float(p.position.z()))};
      channel->mRotationKeys[s] = {double(s), aiQuaternion(float(p.orientation.w()), float(p.orientation.x()),
                                                           float(p.orientation.y()), float(p.orientation.z()))};
      const float scale = present ? 1.0f : 0.0f;
      channel->mScalingKeys[s] = {double(s), aiVector3D(scale, scale, scale)};
    }
    animation->mChannels[b] = channel;
  }

  Assimp::Exporter exporter;
  if (exporter.Export(out.get(), "glb2", path) != aiReturn_SUCCESS) {
    std::error_code ignored;
    fs::remove(path, ignored);
    throw UsageError(path + ": cannot be written (" + exporter.GetErrorString() + ")");
  }
  size_t triangles = 0;
  for (unsigned m = 0; m < out->mNumMeshes; ++m) triangles += out->mMeshes[m]->mNumFaces;
  std::cout << "wrote " << path << ": " << kinds.size() << " bodies, " << out->mNumMeshes << " meshes (" << triangles
            << " triangles), " << poses.size() << " keyframes of " << scene.time_step << " s\n";
}

// Bytes as base64 (libb64: lines of 72 characters, which atob skips).
std::string base64(const void* data, size_t size) {
  std::string out(2 * size + 8, '\0');
  base64_encodestate state;
  base64_init_encodestate(&state);
  size_t n = 0;
  const char* bytes = static_cast<const char*>(data);
  for (size_t at = 0; at < size; at += 1 << 20) {
    const int chunk = int(std::min<size_t>(size - at, 1 << 20));
    n += size_t(base64_encode_block(bytes + at, chunk, out.data() + n, &state));
  }
  n += size_t(base64_encode_blockend(out.data() + n, &state));
  out.resize(n);
  return out;
}

template <class T>
std::string base64(const std::vector<T>& v) {
  return base64(v.data(), v.size() * sizeof(T));
}

// One data script: `RTCD_VIEW.<name> = <json>;` (the page's first script
// makes RTCD_VIEW).
size_t write_script(const fs::path& file, const std::string& name, const nlohmann::json& value) {
  std::ofstream out(file, std::ios::binary);
  out << "RTCD_VIEW." << name << " = " << value.dump() << ";\n";
  out.close();
  if (!out) throw UsageError(file.string() + ": cannot be written");
  return size_t(fs::file_size(file));
}

// Where the page's own files are: beside the command (install and build
// trees alike: bin/../share/rtcd/viewer), else the build tree's copy.
fs::path viewer_files() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = exe.parent_path().parent_path() / "share" / "rtcd" / "viewer";
    if (fs::exists(beside / "index.html")) return beside;
  }
  if (fs::exists(fs::path(RTCD_VIEWER_DIR) / "index.html")) return RTCD_VIEWER_DIR;
  throw UsageError("the page's files (share/rtcd/viewer, index.html and three.js) are not installed beside rtcd");
}

constexpr const char* kMarker = ".rtcd-view";  // names a folder `rtcd view` may replace

// What the page shows at each step: the recorded figures, and (replayed)
// every contact with its bodies, point, depth and push.
struct Contacts {
  std::vector<uint32_t> offsets{0};  // per step, into the arrays below
  std::vector<uint16_t> bodies;      // source, target
  std::vector<uint16_t> points;      // quantized in the page's box
  std::vector<int8_t> directions;    // the push's unit direction, times 127
  std::vector<float> depths, pushes; // the depth (colour) and the push's length (arrow)
  std::vector<uint8_t> kinds;        // ContactKind
};

Contacts replay_contacts(const sim::Recording& recording, const Aabb& box, const std::string& backend) {
  Contacts c;
  experiments::ReplayConfig config;
  config.label = "view";
  config.backend = backend;
  config.config = recording.scene().narrow;
  experiments::ReplayOptions options;
  const Eigen::Vector3d extent = (box.max - box.min).cwiseMax(1e-9);
  options.observe = [&](uint64_t step, const StepResult& result) {
    while (c.offsets.size() <= step + 1) c.offsets.push_back(uint32_t(c.depths.size()));
    for (const Contact& k : result.contacts) {
      c.bodies.insert(c.bodies.end(), {uint16_t(k.source_body), uint16_t(k.target_body)});
      for (int a = 0; a < 3; ++a) {
        const double u = std::clamp((k.origin[a] - box.min[a]) / extent[a], 0.0, 1.0);
        c.points.push_back(uint16_t(std::lround(u * 65535)));
      }
      const double length = k.push.norm();
      const Eigen::Vector3d dir = length > 0 ? Eigen::Vector3d(k.push / length) : Eigen::Vector3d::Zero();
      for (int a = 0; a < 3; ++a) c.directions.push_back(int8_t(std::lround(dir[a] * 127)));
      c.depths.push_back(float(k.depth));
      c.pushes.push_back(float(length));
      c.kinds.push_back(uint8_t(k.kind));
    }
    c.offsets[step + 1] = uint32_t(c.depths.size());
  };
  size_t last_percent = 0;
  options.progress = [&](uint64_t done, uint64_t total) {
    const size_t percent = size_t(100 * done / std::max<uint64_t>(total, 1));
    if (percent >= last_percent + 10 || done == total) {
      std::cout << "\rcontacts: step " << done << " of " << total << std::flush;
      last_percent = percent;
    }
  };
  experiments::replay(recording, {config}, options);
  std::cout << '\n';
  c.offsets.resize(recording.steps().size() + 1, uint32_t(c.depths.size()));
  return c;
}

}  // namespace

std::string view_recording_path(const std::string& input) {
  std::error_code ec;
  if (fs::is_directory(input, ec)) {
    const fs::path file = fs::path(input) / "recording.rtcdrec";
    if (!fs::exists(file))
      throw UsageError(input + " holds no recording.rtcdrec: run the scene with `rtcd run --view` (or --record " +
                       file.string() + ")");
    return file.string();
  }
  if (!fs::exists(input, ec)) throw UsageError(input + ": no such recording or run folder");
  return input;
}

size_t write_view_page(const sim::Recording& recording, const fs::path& folder, bool contacts,
                       const std::string& backend) {
  if (recording.steps().empty()) throw UsageError(recording.scene_path() + ": the recording holds no steps");
  std::error_code ec;
  if (fs::exists(folder, ec) && !fs::is_empty(folder, ec) && !fs::exists(folder / kMarker))
    throw UsageError(folder.string() + " exists and is not a page rtcd view wrote: nothing written");
  if (recording.kinds().size() > 65535) throw UsageError("the page draws at most 65535 bodies");
  const fs::path files = viewer_files();
  const sim::Scene& scene = recording.scene();
  const std::vector<uint32_t>& kinds = recording.kinds();
  const std::vector<std::shared_ptr<const Shape>> shapes = sim::make_shapes(scene);
  const Frames frames = read_frames(recording);
  double radius = 0;
  for (const auto& s : shapes) radius = std::max(radius, s->radius());
  const Aabb box = frames.box.grown(radius);

  // Written beside the folder, then moved into place: a failure leaves the old one.
  const fs::path partial = folder.string() + ".partial";
  fs::remove_all(partial, ec);
  fs::create_directories(partial / "data", ec);
  if (ec) throw UsageError("cannot create " + partial.string() + ": " + ec.message());
  try {
    for (const char* name : {"index.html", "viewer.js", "three.min.js", "OrbitControls.js"})
      fs::copy_file(files / name, partial / name);
    std::ofstream(partial / kMarker) << "written by rtcd view\n";

    nlohmann::json looks = nlohmann::json::array();
    const auto look = [&](const sim::RenderMesh& m, const std::string& label, const std::string& shape,
                          const Eigen::Vector3f& colour) {
      std::vector<float> positions;
      for (const auto& p : m.positions) positions.insert(positions.end(), {p.x(), p.y(), p.z()});
      std::vector<uint32_t> triangles;
      for (const auto& t : m.triangles) triangles.insert(triangles.end(), t.begin(), t.end());
      looks.push_back({{"label", label},
                       {"shape", shape},
                       {"colour", {colour.x(), colour.y(), colour.z()}},
                       {"positions", base64(positions)},
                       {"triangles", base64(triangles)}});
    };
    for (size_t k = 0; k < shapes.size(); ++k) {
      const Shape& shape = *shapes[k];
      std::string what = shape.mesh() ? "mesh, " + std::to_string(shape.mesh()->triangle_count()) + " triangles"
                         : std::get_if<Sphere>(&shape.geometry()) ? std::string("sphere")
                                                                  : std::string("box");
      look(sim::look_of(shape), scene.bodies[k].label, what,
           scene.bodies[k].is_static ? sim::kStaticColour : sim::kind_colour(k));
    }
    look(ground_look(frames), "ground", "half-space", sim::kGroundColour);

    const size_t steps = frames.poses.size(), bodies = kinds.size();
    std::vector<int32_t> body_look;
    for (uint32_t kind : kinds) body_look.push_back(kind == sim::Simulation::kGroundKind ? int32_t(shapes.size()) : int32_t(kind));
    nlohmann::json figures = {{"time", nlohmann::json::array()},   {"pairs", nlohmann::json::array()},
                              {"contacts", nlohmann::json::array()}, {"broad", nlohmann::json::array()},
                              {"narrow", nlohmann::json::array()},   {"solver", nlohmann::json::array()},
                              {"effects", nlohmann::json::array()},  {"total", nlohmann::json::array()}};
    for (const sim::RecordedStep& r : recording.steps()) {
      figures["time"].push_back(r.time);
      figures["pairs"].push_back(r.pairs);
      figures["contacts"].push_back(r.contacts);
      figures["broad"].push_back(r.seconds_broad);
      figures["narrow"].push_back(r.seconds_narrow);
      figures["solver"].push_back(r.seconds_solver);
      figures["effects"].push_back(r.seconds_effects);
      figures["total"].push_back(r.seconds_total);
    }
    nlohmann::json view = {{"name", scene.name},
                           {"steps", steps},
                           {"time_step", scene.time_step},
                           {"looks", looks},
                           {"body_look", body_look},
                           {"labels", body_labels(recording)},
                           {"first_step", frames.first_step},
                           {"box", {{box.min.x(), box.min.y(), box.min.z()}, {box.max.x(), box.max.y(), box.max.z()}}},
                           {"depth", scene.narrow.nearest_surface ? "true penetration (nearest surface)" : "ray depth"},
                           {"figures", figures}};
    if (scene.camera_eye) view["camera_eye"] = {scene.camera_eye->x(), scene.camera_eye->y(), scene.camera_eye->z()};
    if (scene.camera_target)
      view["camera_target"] = {scene.camera_target->x(), scene.camera_target->y(), scene.camera_target->z()};
    {
      std::ofstream out(partial / "data" / "scene.js", std::ios::binary);
      out << "var RTCD_VIEW = " << view.dump() << ";\n";
      if (!out) throw UsageError((partial / "data" / "scene.js").string() + ": cannot be written");
    }

    // Poses: x y z qx qy qz qw per body and step, NaN before it appears.
    std::vector<float> poses(steps * bodies * 7, std::numeric_limits<float>::quiet_NaN());
    for (size_t s = 0; s < steps; ++s)
      for (size_t b = 0; b < frames.poses[s].size(); ++b) {
        const Pose& p = frames.poses[s][b];
        float* q = &poses[(s * bodies + b) * 7];
        const float v[7] = {float(p.position.x()),    float(p.position.y()),    float(p.position.z()),
                            float(p.orientation.x()), float(p.orientation.y()), float(p.orientation.z()),
                            float(p.orientation.w())};
        std::copy(v, v + 7, q);
      }
    write_script(partial / "data" / "poses.js", "poses", base64(poses));

    nlohmann::json overlay = nullptr;
    if (contacts) {
      const Contacts c = replay_contacts(recording, box, backend);
      overlay = {{"offsets", base64(c.offsets)}, {"bodies", base64(c.bodies)},   {"points", base64(c.points)},
                 {"directions", base64(c.directions)}, {"depths", base64(c.depths)}, {"pushes", base64(c.pushes)},
                 {"kinds", base64(c.kinds)}};
    }
    write_script(partial / "data" / "contacts.js", "contacts", overlay);
  } catch (...) {
    fs::remove_all(partial, ec);
    throw;
  }
  fs::remove_all(folder, ec);
  fs::rename(partial, folder, ec);
  if (ec) throw UsageError("cannot move the page into " + folder.string() + ": " + ec.message());
  size_t bytes = 0;
  for (const auto& e : fs::recursive_directory_iterator(folder))
    if (e.is_regular_file()) bytes += size_t(e.file_size());
  return bytes;
}

int run_view(const ViewOptions& o) {
  const std::string path = view_recording_path(o.input);
  const sim::Recording recording = sim::Recording::read(path);
  if (recording.steps().empty()) throw UsageError(path + ": holds no steps");
  if (!o.gltf.empty()) {
    write_gltf(recording, o.gltf);
    if (o.out.empty() && !o.serve) return 0;
  }
  const fs::path folder = o.out.empty() ? fs::path(path).parent_path() / "view" : fs::path(o.out);
  const size_t bytes = write_view_page(recording, folder, o.contacts, o.backend);
  const fs::path index = fs::absolute(folder / "index.html");
  std::cout << "wrote " << folder.string() << " (" << (bytes + 500000) / 1000000 << " MB): open file://"
            << index.string() << "\n";
  if (o.serve) {
    const std::string command = "/usr/bin/python3 -m http.server --bind 127.0.0.1 --directory '" +
                                fs::absolute(folder).string() + "' " + std::to_string(*o.serve);
    std::cout << "serving it on http://127.0.0.1:" << *o.serve << "/ (Ctrl-C stops)\n" << std::flush;
    if (std::system(command.c_str()) != 0) throw UsageError("the server stopped: " + command);
  }
  return 0;
}

}  // namespace rtcd::app

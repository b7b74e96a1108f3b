// `rtcd view RECORDING --gltf FILE.glb`: the recording's scene and poses as
// an assimp scene (meshes, nodes, one animation), written by assimp's glTF
// 2.0 binary exporter.
#include "rtcd/app/view.hpp"

#include <assimp/Exporter.hpp>
#include <assimp/material.h>
#include <assimp/scene.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <vector>

#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/sim/recording.hpp"
#include "rtcd/sim/simulation.hpp"

namespace rtcd::app {
namespace {

struct Triangles {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Mesh::Triangle> triangles;
};

Triangles triangles_of(const Mesh& m) { return {{m.positions().begin(), m.positions().end()}, {m.triangles().begin(), m.triangles().end()}}; }

// What a kind looks like in its own frame: its mesh, a sphere or a box
// tessellated; the ground (z <= 0 in its frame) the square of half side
// `half` around `centre` in its plane.
Triangles look_of(const Shape& shape, const Eigen::Vector3d& centre, double half) {
  if (const Mesh* m = shape.mesh()) return triangles_of(*m);
  if (const auto* sphere = std::get_if<Sphere>(&shape.geometry())) return triangles_of(gen::icosphere(sphere->radius, 3));
  if (const auto* box = std::get_if<Box>(&shape.geometry())) return triangles_of(gen::box(box->half_extents));
  Triangles square;
  for (const auto& [x, y] : {std::pair{-1, -1}, std::pair{1, -1}, std::pair{1, 1}, std::pair{-1, 1}})
    square.positions.push_back(Eigen::Vector3f(float(centre.x() + x * half), float(centre.y() + y * half), 0.0f));
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  return square;
}

aiMesh* to_ai(const Triangles& t, const std::string& name, unsigned material) {
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

aiMaterial* material(const aiColor4D& colour) {
  auto* m = new aiMaterial;
  m->AddProperty(&colour, 1, AI_MATKEY_COLOR_DIFFUSE);
  m->AddProperty(&colour, 1, AI_MATKEY_BASE_COLOR);
  return m;
}

}  // namespace

int run_view(const ViewOptions& o) {
  if (o.gltf.empty()) throw UsageError("view: give --gltf FILE.glb (the file to write)");
  const sim::Recording recording = sim::Recording::read(o.recording);
  if (recording.steps().empty()) throw UsageError(o.recording + ": holds no steps");
  const std::vector<uint32_t>& kinds = recording.kinds();
  const sim::Scene& scene = recording.scene();
  const std::vector<std::shared_ptr<const Shape>> shapes = sim::make_shapes(scene);

  // Every step's poses; a body not yet in the scene keeps its first pose,
  // drawn at scale 0 until it appears.
  std::vector<std::vector<Pose>> poses;
  std::vector<size_t> first_step(kinds.size(), 0);
  sim::RecordedFrame frame;
  sim::Recording::Cursor cursor(recording);
  Aabb box;
  while (cursor.next(frame)) {
    for (size_t b = poses.empty() ? 0 : poses.back().size(); b < frame.poses.size(); ++b) first_step[b] = poses.size();
    poses.push_back(frame.poses);
    for (size_t b = 0; b < frame.poses.size(); ++b)
      if (kinds[b] != sim::Simulation::kGroundKind) box.extend(frame.poses[b].position);
  }
  if (box.empty()) box.extend(Eigen::Vector3d::Zero());
  const double half = 0.75 * (box.max - box.min).norm() + 1.0;
  const Eigen::Vector3d centre = 0.5 * (box.min + box.max);

  auto out = std::make_unique<aiScene>();
  // One mesh and material per kind (the ground's last).
  const unsigned ground_mesh = unsigned(shapes.size());
  out->mNumMeshes = ground_mesh + 1;
  out->mMeshes = new aiMesh*[out->mNumMeshes]();
  out->mNumMaterials = out->mNumMeshes;
  out->mMaterials = new aiMaterial*[out->mNumMaterials]();
  static const aiColor4D colours[] = {{0.85f, 0.55f, 0.25f, 1}, {0.35f, 0.6f, 0.85f, 1}, {0.5f, 0.75f, 0.4f, 1},
                                      {0.8f, 0.45f, 0.6f, 1},   {0.7f, 0.7f, 0.35f, 1},  {0.55f, 0.5f, 0.8f, 1}};
  for (unsigned k = 0; k < shapes.size(); ++k) {
    out->mMeshes[k] = to_ai(look_of(*shapes[k], centre, half), scene.bodies[k].label, k);
    out->mMaterials[k] = material(colours[k % std::size(colours)]);
  }
  // The ground's square lies in its own frame: around the bodies' centre seen from there.
  size_t ground_body = kinds.size();
  for (size_t b = 0; b < kinds.size(); ++b)
    if (kinds[b] == sim::Simulation::kGroundKind) ground_body = b;
  const Eigen::Vector3d ground_centre =
      ground_body < kinds.size() ? poses[first_step[ground_body]][ground_body].inverse().apply(centre) : centre;
  out->mMeshes[ground_mesh] = to_ai(look_of(Shape(HalfSpace{}), ground_centre, half), "ground", ground_mesh);
  out->mMaterials[ground_mesh] = material({0.82f, 0.82f, 0.78f, 1});

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
  if (exporter.Export(out.get(), "glb2", o.gltf) != aiReturn_SUCCESS) {
    std::error_code ignored;
    std::filesystem::remove(o.gltf, ignored);
    throw UsageError(o.gltf + ": cannot be written (" + exporter.GetErrorString() + ")");
  }
  size_t triangles = 0;
  for (unsigned m = 0; m < out->mNumMeshes; ++m) triangles += out->mMeshes[m]->mNumFaces;
  std::cout << "wrote " << o.gltf << ": " << kinds.size() << " bodies, " << out->mNumMeshes << " meshes (" << triangles
            << " triangles), " << poses.size() << " keyframes of " << scene.time_step << " s\n";
  return 0;
}

}  // namespace rtcd::app

// Snapshot renderer: one Embree scene per mesh, instanced per body, shaded
// per pixel in parallel over rows; lines are rasterised afterwards in input
// order so the output never depends on the thread count.
#include "rtcd/sim/render.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <numbers>
#include <utility>

#include <Eigen/Geometry>
#include <embree3/rtcore.h>
#include <stb/stb_image_write.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"

namespace rtcd::sim {
namespace {

constexpr int max_image_side = 16384;
constexpr float infinity = std::numeric_limits<float>::infinity();

// Front-right and above, slightly to the side of the default camera so the
// three faces of a box it sees get three different shades.
const Eigen::Vector3f light_direction = Eigen::Vector3f(0.45f, -0.3f, 1.0f).normalized();
const Eigen::Vector3d camera_direction = Eigen::Vector3d(1.0, -1.7, 1.1).normalized();

// Embree reports errors through a callback (possibly from its worker
// threads); the first message is kept so the exception can carry it.
class EmbreeDevice {
 public:
  EmbreeDevice() : device_(rtcNewDevice(nullptr)) {
    if (device_ == nullptr)
      throw UsageError("embree: cannot create a device (error " + std::to_string(int(rtcGetDeviceError(nullptr))) +
                       ")");
    rtcSetDeviceErrorFunction(device_, &EmbreeDevice::record, this);
  }
  ~EmbreeDevice() { rtcReleaseDevice(device_); }
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;

  RTCDevice get() const { return device_; }

  // Throws with Embree's message when anything since the last check failed.
  void check(const char* what) {
    const RTCError code = rtcGetDeviceError(device_);
    if (code == RTC_ERROR_NONE) return;
    std::lock_guard lock(mutex_);
    const std::string message = first_message_.empty() ? "error " + std::to_string(int(code)) : first_message_;
    throw UsageError(std::string("embree: ") + what + ": " + message);
  }

 private:
  static void record(void* self_pointer, RTCError, const char* message) {
    auto* self = static_cast<EmbreeDevice*>(self_pointer);
    std::lock_guard lock(self->mutex_);
    if (self->first_message_.empty() && message != nullptr) self->first_message_ = message;
  }

  RTCDevice device_;
  std::mutex mutex_;
  std::string first_message_;
};

class SceneHandle {
 public:
  explicit SceneHandle(RTCDevice device) : scene_(rtcNewScene(device)) {}
  ~SceneHandle() {
    if (scene_ != nullptr) rtcReleaseScene(scene_);
  }
  SceneHandle(SceneHandle&& other) noexcept : scene_(std::exchange(other.scene_, nullptr)) {}
  SceneHandle(const SceneHandle&) = delete;
  SceneHandle& operator=(const SceneHandle&) = delete;
  SceneHandle& operator=(SceneHandle&&) = delete;
  RTCScene get() const { return scene_; }

 private:
  RTCScene scene_;
};

// Attaching retains the geometry; this releases the creator's reference even
// when building throws halfway.
class GeometryHandle {
 public:
  GeometryHandle(RTCDevice device, RTCGeometryType type) : geometry_(rtcNewGeometry(device, type)) {}
  ~GeometryHandle() {
    if (geometry_ != nullptr) rtcReleaseGeometry(geometry_);
  }
  GeometryHandle(const GeometryHandle&) = delete;
  GeometryHandle& operator=(const GeometryHandle&) = delete;
  RTCGeometry get() const { return geometry_; }

 private:
  RTCGeometry geometry_;
};

// Pinhole camera with its orthonormal frame; pixel coordinates are
// continuous, (0, 0) the top-left corner of the image.
struct CameraFrame {
  Eigen::Vector3d eye, forward, right, up;
  double tan_half_x = 0, tan_half_y = 0;
  int width = 0, height = 0;

  CameraFrame(const Camera& camera, int image_width, int image_height) : width(image_width), height(image_height) {
    if (!camera.eye.allFinite() || !camera.target.allFinite() || !camera.up.allFinite())
      throw UsageError("render: camera has a non-finite component");
    if (!(camera.fov_degrees > 0 && camera.fov_degrees < 180))
      throw UsageError("render: camera fov_degrees " + std::to_string(camera.fov_degrees) +
                       " is outside (0, 180)");
    const Eigen::Vector3d view = camera.target - camera.eye;
    if (!(view.norm() > 0)) throw UsageError("render: camera eye and target coincide");
    eye = camera.eye;
    forward = view.normalized();
    // An up vector along the view direction says nothing about roll; any
    // other axis gives a usable picture.
    Eigen::Vector3d up_hint = camera.up;
    if (!(forward.cross(up_hint).norm() > 1e-9 * up_hint.norm()))
      up_hint = std::abs(forward.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitY();
    right = forward.cross(up_hint).normalized();
    up = right.cross(forward);
    tan_half_y = std::tan(camera.fov_degrees * std::numbers::pi / 360.0);
    tan_half_x = tan_half_y * width / height;
  }

  Eigen::Vector3d ray_direction(double px, double py) const {
    const double x = (2.0 * px / width - 1.0) * tan_half_x;
    const double y = (1.0 - 2.0 * py / height) * tan_half_y;
    return (forward + x * right + y * up).normalized();
  }
  // World point to camera coordinates (right, up, depth along the view).
  Eigen::Vector3d to_camera(const Eigen::Vector3d& world) const {
    const Eigen::Vector3d d = world - eye;
    return {d.dot(right), d.dot(up), d.dot(forward)};
  }
  Eigen::Vector2d to_pixel(const Eigen::Vector3d& in_camera) const {
    return {(in_camera.x() / in_camera.z() / tan_half_x + 1.0) * 0.5 * width,
            (1.0 - in_camera.y() / in_camera.z() / tan_half_y) * 0.5 * height};
  }
};

Eigen::Vector3f background(double py, int height) {
  const float v = float(py / height);
  const Eigen::Vector3f top(0.74f, 0.82f, 0.93f), bottom(0.95f, 0.95f, 0.96f);
  return (1.0f - v) * top + v * bottom;
}

Eigen::Vector3f clamped_color(const Eigen::Vector3f& color) {
  return color.array().isFinite().all() ? Eigen::Vector3f(color.cwiseMax(0.0f).cwiseMin(1.0f))
                                        : Eigen::Vector3f(1.0f, 0.0f, 1.0f);
}

// The scene to trace: a top-level scene of instances over per-mesh scenes.
struct BuiltScene {
  std::vector<SceneHandle> mesh_scenes;
  SceneHandle top;
  std::vector<Eigen::Matrix3f> rotations;  // per instance, for normals
  std::vector<Eigen::Vector3f> colors;     // per instance

  explicit BuiltScene(RTCDevice device) : top(device) {}
};

void build_mesh_scene(EmbreeDevice& device, const RenderMesh& mesh, size_t mesh_index, SceneHandle& scene) {
  const size_t vertex_count = mesh.positions.size();
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (const uint32_t v : mesh.triangles[t])
      if (v >= vertex_count)
        throw UsageError("render: mesh " + std::to_string(mesh_index) + " triangle " + std::to_string(t) +
                         " uses vertex " + std::to_string(v) + " of " + std::to_string(vertex_count));
  if (mesh.triangles.empty()) {
    rtcCommitScene(scene.get());
    device.check("mesh scene build");
    return;
  }
  GeometryHandle geometry(device.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
  device.check("triangle geometry");
  // rtcSetNewGeometryBuffer pads for Embree's 16-byte loads.
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry.get(), RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float), vertex_count));
  auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
      geometry.get(), RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), mesh.triangles.size()));
  device.check("geometry buffers");
  if (vertices == nullptr || indices == nullptr) throw UsageError("embree: cannot allocate geometry buffers");
  for (size_t i = 0; i < vertex_count; ++i) std::memcpy(vertices + 3 * i, mesh.positions[i].data(), 3 * sizeof(float));
  for (size_t i = 0; i < mesh.triangles.size(); ++i)
    std::memcpy(indices + 3 * i, mesh.triangles[i].data(), 3 * sizeof(uint32_t));
  rtcCommitGeometry(geometry.get());
  rtcAttachGeometry(scene.get(), geometry.get());
  rtcCommitScene(scene.get());
  device.check("mesh scene build");
}

void build_scene(EmbreeDevice& device, std::span<const RenderMesh> meshes, std::span<const RenderInstance> instances,
                 BuiltScene& built) {
  built.mesh_scenes.reserve(meshes.size());
  for (size_t m = 0; m < meshes.size(); ++m) {
    built.mesh_scenes.emplace_back(device.get());
    device.check("mesh scene");
    build_mesh_scene(device, meshes[m], m, built.mesh_scenes.back());
  }
  built.rotations.resize(instances.size());
  built.colors.resize(instances.size());
  for (size_t i = 0; i < instances.size(); ++i) {
    const RenderInstance& instance = instances[i];
    if (instance.mesh >= meshes.size())
      throw UsageError("render: instance " + std::to_string(i) + " names mesh " + std::to_string(instance.mesh) +
                       " of " + std::to_string(meshes.size()));
    const Pose pose = checked(instance.pose);
    const Eigen::Matrix3f rotation = pose.orientation.toRotationMatrix().cast<float>();
    built.rotations[i] = rotation;
    built.colors[i] = clamped_color(instance.color);
    if (meshes[instance.mesh].triangles.empty()) continue;  // nothing to hit

    // Column-major 3x4: the rotation's columns, then the translation.
    float transform[12];
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) transform[3 * c + r] = rotation(r, c);
    for (int r = 0; r < 3; ++r) transform[9 + r] = float(pose.position[r]);

    GeometryHandle geometry(device.get(), RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(geometry.get(), built.mesh_scenes[instance.mesh].get());
    rtcSetGeometryTimeStepCount(geometry.get(), 1);
    rtcSetGeometryTransform(geometry.get(), 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, transform);
    rtcCommitGeometry(geometry.get());
    // The geometry id is the instance's index, so a hit's instID finds its colour.
    rtcAttachGeometryByID(built.top.get(), geometry.get(), unsigned(i));
    device.check("instance geometry");
  }
  rtcCommitScene(built.top.get());
  device.check("scene build");
}

struct Sample {
  Eigen::Vector3f color;
  float distance;  // along the ray from the eye; infinity on a miss
};

Sample trace(const BuiltScene& scene, const Eigen::Vector3f& origin, const Eigen::Vector3f& direction,
             const Eigen::Vector3f& sky) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit ray_hit{};
  ray_hit.ray.org_x = origin.x();
  ray_hit.ray.org_y = origin.y();
  ray_hit.ray.org_z = origin.z();
  ray_hit.ray.dir_x = direction.x();
  ray_hit.ray.dir_y = direction.y();
  ray_hit.ray.dir_z = direction.z();
  ray_hit.ray.tnear = 0.0f;
  ray_hit.ray.tfar = infinity;
  ray_hit.ray.mask = 0xffffffffu;
  ray_hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  ray_hit.hit.primID = RTC_INVALID_GEOMETRY_ID;
  for (unsigned& id : ray_hit.hit.instID) id = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene.top.get(), &context, &ray_hit);
  const unsigned instance = ray_hit.hit.instID[0];
  if (ray_hit.hit.geomID == RTC_INVALID_GEOMETRY_ID || instance == RTC_INVALID_GEOMETRY_ID) return {sky, infinity};

  const float distance = ray_hit.ray.tfar;
  // Embree gives an instanced hit's normal in the mesh's local frame.
  Eigen::Vector3f normal =
      (scene.rotations[instance] * Eigen::Vector3f(ray_hit.hit.Ng_x, ray_hit.hit.Ng_y, ray_hit.hit.Ng_z))
          .normalized();
  if (!normal.allFinite()) normal = -direction;
  if (normal.dot(direction) > 0) normal = -normal;  // two-sided: face the viewer

  float diffuse = std::max(0.0f, normal.dot(light_direction));
  if (diffuse > 0) {
    // Offset grows with distance so float rounding of the hit point never
    // lets the shadow ray hit its own surface.
    const float offset = 1e-4f * std::max(1.0f, distance + origin.norm());
    const Eigen::Vector3f hit_point = origin + distance * direction + offset * normal;
    RTCRay shadow{};
    shadow.org_x = hit_point.x();
    shadow.org_y = hit_point.y();
    shadow.org_z = hit_point.z();
    shadow.dir_x = light_direction.x();
    shadow.dir_y = light_direction.y();
    shadow.dir_z = light_direction.z();
    shadow.tnear = 0.0f;
    shadow.tfar = infinity;
    shadow.mask = 0xffffffffu;
    RTCIntersectContext shadow_context;
    rtcInitIntersectContext(&shadow_context);
    rtcOccluded1(scene.top.get(), &shadow_context, &shadow);
    if (shadow.tfar < 0) diffuse = 0;  // Embree marks an occluded ray with tfar = -inf
  }
  // Faces turned to the sky get a little more ambient light, so surfaces in
  // shadow still show their shape.
  const float ambient = 0.22f + 0.10f * (0.5f + 0.5f * normal.z());
  return {scene.colors[instance] * (ambient + 0.70f * diffuse), distance};
}

// Line pixels: solid where the line is in front of the surfaces, dimmed
// where hidden; solid wins when both land on one pixel.
enum class LineMark : uint8_t { none, hidden, visible };

struct LineOverlay {
  std::vector<LineMark> marks;
  std::vector<Eigen::Vector3f> colors;
};

// Parameter range [s0, s1] of the 2-D segment a + s (b - a) inside the box
// [lo, hi]^2 (Liang–Barsky); false when it misses.
bool clip_to_box(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& lo,
                 const Eigen::Vector2d& hi, double& s0, double& s1) {
  s0 = 0;
  s1 = 1;
  const Eigen::Vector2d d = b - a;
  for (int axis = 0; axis < 2; ++axis) {
    const double p[2] = {-d[axis], d[axis]};
    const double q[2] = {a[axis] - lo[axis], hi[axis] - a[axis]};
    for (int k = 0; k < 2; ++k) {
      if (p[k] == 0) {
        if (q[k] < 0) return false;
        continue;
      }
      const double r = q[k] / p[k];
      if (p[k] < 0)
        s0 = std::max(s0, r);
      else
        s1 = std::min(s1, r);
    }
  }
  return s0 <= s1;
}

void draw_line(const RenderLine& line, const CameraFrame& frame, const std::vector<float>& depth,
               LineOverlay& overlay) {
  if (!line.from.allFinite() || !line.to.allFinite()) return;
  Eigen::Vector3d a = frame.to_camera(line.from), b = frame.to_camera(line.to);
  // Cut the part behind the eye: projection is undefined there.
  const double near = 1e-6 * std::max({1.0, a.norm(), b.norm()});
  if (a.z() < near && b.z() < near) return;
  if (a.z() < near) a += (b - a) * ((near - a.z()) / (b.z() - a.z()));
  if (b.z() < near) b += (a - b) * ((near - b.z()) / (a.z() - b.z()));

  const Eigen::Vector2d pa = frame.to_pixel(a), pb = frame.to_pixel(b);
  double s0 = 0, s1 = 1;
  if (!clip_to_box(pa, pb, {-2.0, -2.0}, {frame.width + 2.0, frame.height + 2.0}, s0, s1)) return;
  const int steps = std::max(1, int(std::ceil(2.0 * (pb - pa).norm() * (s1 - s0))));
  const Eigen::Vector3f color = clamped_color(line.color);
  constexpr double radius = 0.95;  // lines come out 1 to 2 pixels wide

  for (int k = 0; k <= steps; ++k) {
    const double s = s0 + (s1 - s0) * k / steps;
    const Eigen::Vector2d p = pa + (pb - pa) * s;
    // Screen-space s to the 3-D segment parameter: 1/depth is linear on screen.
    const double t = (s / b.z()) / ((1.0 - s) / a.z() + s / b.z());
    const double distance = (a + (b - a) * t).norm();
    for (int y = int(std::floor(p.y() - radius)); y <= int(std::floor(p.y() + radius)); ++y) {
      if (y < 0 || y >= frame.height) continue;
      for (int x = int(std::floor(p.x() - radius)); x <= int(std::floor(p.x() + radius)); ++x) {
        if (x < 0 || x >= frame.width) continue;
        if ((Eigen::Vector2d(x + 0.5, y + 0.5) - p).squaredNorm() > radius * radius) continue;
        const size_t pixel = size_t(y) * frame.width + x;
        // Tolerance so a line lying on a surface (a contact ray's origin)
        // counts as visible there.
        const bool visible = distance <= double(depth[pixel]) * (1.0 + 2e-3) + 1e-6;
        if (visible) {
          overlay.marks[pixel] = LineMark::visible;
          overlay.colors[pixel] = color;
        } else if (overlay.marks[pixel] != LineMark::visible) {
          overlay.marks[pixel] = LineMark::hidden;
          overlay.colors[pixel] = color;
        }
      }
    }
  }
}

uint8_t to_byte(float value) { return uint8_t(std::lround(std::clamp(value, 0.0f, 1.0f) * 255.0f)); }

RenderMesh render_mesh(const Mesh& m) {
  RenderMesh r;
  r.positions.assign(m.positions().begin(), m.positions().end());
  r.triangles.assign(m.triangles().begin(), m.triangles().end());
  return r;
}

}  // namespace

RenderMesh look_of(const Shape& shape) {
  if (const Mesh* m = shape.mesh()) return render_mesh(*m);
  if (const auto* sphere = std::get_if<Sphere>(&shape.geometry())) return render_mesh(gen::icosphere(sphere->radius, 3));
  if (const auto* box = std::get_if<Box>(&shape.geometry())) return render_mesh(gen::box(box->half_extents));
  throw UsageError("a half-space has no finite look: draw it as a ground_square");
}

RenderMesh ground_square(const Eigen::Vector3d& centre, double half) {
  RenderMesh square;
  for (const auto& [x, y] : {std::pair{-1, -1}, std::pair{1, -1}, std::pair{1, 1}, std::pair{-1, 1}})
    square.positions.push_back(Eigen::Vector3f(float(centre.x() + x * half), float(centre.y() + y * half), 0.0f));
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  return square;
}

Eigen::Vector3f kind_colour(size_t kind) {
  static const Eigen::Vector3f colours[] = {{0.85f, 0.55f, 0.25f}, {0.35f, 0.6f, 0.85f}, {0.5f, 0.75f, 0.4f},
                                            {0.8f, 0.45f, 0.6f},  {0.7f, 0.7f, 0.35f},  {0.55f, 0.5f, 0.8f}};
  return colours[kind % std::size(colours)];
}

Camera frame_camera(const Aabb& box) {
  Aabb framed = box;
  if (framed.empty() || !framed.min.allFinite() || !framed.max.allFinite())
    framed = Aabb{Eigen::Vector3d::Constant(-1.0), Eigen::Vector3d::Constant(1.0)};
  Camera camera;
  const Eigen::Vector3d centre = 0.5 * (framed.min + framed.max);
  // The bounding sphere fits the vertical field of view, with a margin.
  double radius = 0.5 * (framed.max - framed.min).norm();
  if (!(radius > 0)) radius = 1.0;
  const double distance = 1.1 * radius / std::sin(camera.fov_degrees * std::numbers::pi / 360.0);
  camera.target = centre;
  camera.eye = centre + distance * camera_direction;
  return camera;
}

Image render(std::span<const RenderMesh> meshes, std::span<const RenderInstance> instances,
             std::span<const RenderLine> lines, const Camera& camera, int width, int height) {
  if (width < 1 || height < 1 || width > max_image_side || height > max_image_side)
    throw UsageError("render: image size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is outside [1, " + std::to_string(max_image_side) + "]");
  const CameraFrame frame(camera, width, height);

  EmbreeDevice device;
  BuiltScene scene(device.get());
  device.check("scene");
  build_scene(device, meshes, instances, scene);

  const size_t pixel_count = size_t(width) * height;
  std::vector<Eigen::Vector3f> colors(pixel_count);
  std::vector<float> depth(pixel_count, infinity);
  const Eigen::Vector3f eye = frame.eye.cast<float>();
  // 2x2 samples per pixel smooth the edges; the nearest sample is the
  // pixel's depth for the line test.
  constexpr double sample_offsets[2] = {0.25, 0.75};
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < width; ++x) {
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        float nearest = infinity;
        for (const double dy : sample_offsets)
          for (const double dx : sample_offsets) {
            const double px = x + dx, py = y + dy;
            const Sample sample =
                trace(scene, eye, frame.ray_direction(px, py).cast<float>(), background(py, height));
            sum += sample.color;
            nearest = std::min(nearest, sample.distance);
          }
        const size_t pixel = size_t(y) * width + x;
        colors[pixel] = 0.25f * sum;
        depth[pixel] = nearest;
      }
  });
  device.check("tracing");

  LineOverlay overlay{std::vector<LineMark>(pixel_count, LineMark::none), std::vector<Eigen::Vector3f>(pixel_count)};
  for (const RenderLine& line : lines) draw_line(line, frame, depth, overlay);

  Image image;
  image.width = width;
  image.height = height;
  image.rgb.resize(pixel_count * 3);
  for (size_t pixel = 0; pixel < pixel_count; ++pixel) {
    Eigen::Vector3f color = colors[pixel];
    if (overlay.marks[pixel] == LineMark::visible)
      color = overlay.colors[pixel];
    else if (overlay.marks[pixel] == LineMark::hidden)
      color = 0.6f * color + 0.4f * overlay.colors[pixel];
    for (int c = 0; c < 3; ++c) image.rgb[3 * pixel + c] = to_byte(color[c]);
  }
  return image;
}

void write_png(const std::string& path, const Image& image) {
  if (image.width < 1 || image.height < 1 || image.rgb.size() != size_t(image.width) * image.height * 3)
    throw UsageError("write_png: cannot write '" + path + "': image of " + std::to_string(image.width) + "x" +
                     std::to_string(image.height) + " pixels holds " + std::to_string(image.rgb.size()) +
                     " bytes");
  errno = 0;
  if (stbi_write_png(path.c_str(), image.width, image.height, 3, image.rgb.data(), image.width * 3) == 0) {
    const int reason = errno;
    throw UsageError("write_png: cannot write '" + path + "'" +
                     (reason != 0 ? std::string(": ") + std::strerror(reason) : std::string()));
  }
}

std::vector<RenderLine> contact_lines(std::span<const Contact> contacts, bool full_rays) {
  std::vector<RenderLine> lines;
  lines.reserve(contacts.size());
  for (const Contact& c : contacts)
    lines.push_back({c.origin,
                     full_rays ? Eigen::Vector3d(c.origin + c.depth * c.direction) : Eigen::Vector3d(c.origin + c.push),
                     Eigen::Vector3f(0.9f, 0.1f, 0.1f)});
  return lines;
}

}  // namespace rtcd::sim

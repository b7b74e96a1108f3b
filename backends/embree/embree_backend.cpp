// Full ray tracing with Embree 3: one scene per mesh shape, built once in
// the shape's local frame (rays are cast in the target's frame, so a moving
// body never triggers a rebuild). Iterative and predictive logic come from
// the shared CPU pipeline and kernel code.
#include "embree_backend.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <embree3/rtcore.h>

#include "rtcd/error.hpp"
#include "rtcd/kernel/nearest.h"
#include "rtcd/kernel/tracer.h"

namespace rtcd {
namespace {

// The instruction sets an Embree device can be pinned to, by the name its
// configuration takes, and whether this CPU runs them.
struct Isa {
  const char* name;
  bool supported;
};

std::vector<Isa> isas() {
  __builtin_cpu_init();
  return {{"sse2", bool(__builtin_cpu_supports("sse2"))},
          {"sse4.2", bool(__builtin_cpu_supports("sse4.2"))},
          {"avx", bool(__builtin_cpu_supports("avx"))},
          {"avx2", bool(__builtin_cpu_supports("avx2"))},
          // Embree's AVX-512 kernels are Skylake-X's subset.
          {"avx512", __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
                         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
                         __builtin_cpu_supports("avx512cd")}};
}

// `isa` empty: Embree picks the widest set it was built for that the CPU runs.
struct DeviceHandle {
  RTCDevice device;
  explicit DeviceHandle(const std::string& isa)
      : device(rtcNewDevice(isa.empty() ? nullptr : ("isa=" + isa).c_str())) {
    if (device == nullptr) throw BackendError("embree: cannot create a device (error " + std::to_string(rtcGetDeviceError(nullptr)) + ")");
  }
  ~DeviceHandle() { rtcReleaseDevice(device); }
  DeviceHandle(const DeviceHandle&) = delete;
  DeviceHandle& operator=(const DeviceHandle&) = delete;
};

class EmbreeTracer final : public MeshTracer {
 public:
  EmbreeTracer(std::shared_ptr<DeviceHandle> device, const Mesh& mesh) : device_(std::move(device)), mesh_(mesh) {
    scene_ = rtcNewScene(device_->device);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(device_->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    // rtcSetNewGeometryBuffer pads for Embree's 16-byte loads.
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), mesh.vertex_count()));
    auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                   3 * sizeof(uint32_t), mesh.triangle_count()));
    std::memcpy(vertices, mesh.positions().data(), mesh.vertex_count() * 3 * sizeof(float));
    for (size_t i = 0; i < mesh.triangle_count(); ++i) {
      const auto& t = mesh.triangles()[i];
      // A kept zero-area triangle becomes a point: Embree never hits it, and
      // primitive ids stay the mesh's triangle ids.
      const bool keep = !mesh.zero_area()[i];
      indices[3 * i] = t[0];
      indices[3 * i + 1] = keep ? t[1] : t[0];
      indices[3 * i + 2] = keep ? t[2] : t[0];
    }
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_->device) != RTC_ERROR_NONE) throw BackendError("embree: scene build failed");
  }
  ~EmbreeTracer() override { rtcReleaseScene(scene_); }

  TraceHit first_hit(const rtcd_ray& ray, float t_max) const override {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    rh.ray.org_x = ray.origin.x;
    rh.ray.org_y = ray.origin.y;
    rh.ray.org_z = ray.origin.z;
    rh.ray.dir_x = ray.direction.x;
    rh.ray.dir_y = ray.direction.y;
    rh.ray.dir_z = ray.direction.z;
    rh.ray.tnear = 0.0f;
    rh.ray.tfar = t_max;
    rh.ray.time = 0.0f;
    rh.ray.mask = 0xffffffffu;
    rh.ray.id = 0;
    rh.ray.flags = 0;
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context, &rh);
    TraceHit hit;
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      hit.triangle = int32_t(rh.hit.primID);
      hit.t = rh.ray.tfar;
    }
    return hit;
  }

  int32_t nearest(const rtcd_vec3& point, float radius, float enough) const override {
    RTCPointQuery query;
    query.x = point.x;
    query.y = point.y;
    query.z = point.z;
    query.time = 0.0f;
    query.radius = radius;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    Nearest found{this, point, -1, radius * radius, enough * enough};
    rtcPointQuery(scene_, &query, &context, &EmbreeTracer::visit, &found);
    return found.triangle;
  }

 private:
  struct Nearest {
    const EmbreeTracer* tracer;
    rtcd_vec3 point;
    int32_t triangle;
    float best_d2;
    float enough_d2;  // a triangle this near ends the search
  };
  // Embree calls this for every triangle whose box meets the query sphere;
  // shrinking the radius prunes the rest. The tie rule of tracer.h (the
  // lowest id among equal distances, as the brute force and the device's
  // BVH): the radius shrinks to just past the best distance, so a triangle
  // as near is still visited, whatever order the instruction set visits in.
  static bool visit(RTCPointQueryFunctionArguments* args) {
    auto* found = static_cast<Nearest*>(args->userPtr);
    const Mesh& mesh = found->tracer->mesh_;
    if (mesh.zero_area()[args->primID]) return false;
    const auto& tri = mesh.triangles()[args->primID];
    auto v = [&](uint32_t i) {
      const Eigen::Vector3f& p = mesh.positions()[i];
      return rtcd_v3(p.x(), p.y(), p.z());
    };
    const float d2 = rtcd_point_triangle_distance2(found->point, v(tri[0]), v(tri[1]), v(tri[2]));
    const int32_t id = int32_t(args->primID);
    if (!(d2 <= found->best_d2) || !rtcd_nearer(found->best_d2, found->triangle, d2, id)) return false;
    found->best_d2 = d2;
    found->triangle = id;
    // Near enough: a radius no box reaches but those holding the point, and
    // no triangle nearer than this one can be taken.
    const bool enough = d2 <= found->enough_d2;
    if (enough) found->best_d2 = -1.0f;
    args->query->radius = enough ? 1e-30f : std::sqrt(d2) * (1.0f + 1e-6f) + 1e-30f;
    return true;
  }

  std::shared_ptr<DeviceHandle> device_;
  const Mesh& mesh_;  // owned by the registered Shape, which outlives the tracer
  RTCScene scene_;
};

class EmbreeTracerFactory final : public MeshTracerFactory {
 public:
  explicit EmbreeTracerFactory(const std::string& isa) : device_(std::make_shared<DeviceHandle>(isa)) {}
  std::unique_ptr<MeshTracer> build(const Mesh& mesh) const override {
    return std::make_unique<EmbreeTracer>(device_, mesh);
  }

 private:
  std::shared_ptr<DeviceHandle> device_;
};

}  // namespace

namespace {
// Throws BackendError unless Embree knows `isa` and this CPU runs it.
void check_isa(const std::string& isa) {
  if (isa.empty()) return;
  std::string known;
  for (const Isa& i : isas()) known += std::string(known.empty() ? "" : ", ") + i.name;
  for (const Isa& i : isas())
    if (isa == i.name) {
      if (!i.supported) throw BackendError("backend 'embree:isa=" + isa + "': this CPU does not run " + isa);
      return;
    }
  throw BackendError("backend 'embree:isa=" + isa + "': unknown instruction set '" + isa + "' (" + known + ")");
}
}  // namespace

std::unique_ptr<NarrowPhase> make_embree_narrow_phase(const BackendOptions& options, const Config& config) {
  check_isa(options.isa);
  return make_pipeline_narrow_phase(options.name(), {embree_description(options.isa)},
                                    make_cpu_executor(make_embree_tracers(options.isa)), config, options.threads);
}

std::unique_ptr<MeshTracerFactory> make_embree_tracers(const std::string& isa) {
  return std::make_unique<EmbreeTracerFactory>(isa);
}

std::string embree_description(const std::string& isa) {
  DeviceHandle d(isa);
  const long version = long(rtcGetDeviceProperty(d.device, RTC_DEVICE_PROPERTY_VERSION));
  return "cpu (Embree " + std::to_string(version / 10000) + "." + std::to_string(version / 100 % 100) + "." +
         std::to_string(version % 100) + ", TBB" + (isa.empty() ? "" : ", " + isa + " only") + ")";
}

}  // namespace rtcd

// What a step of the narrow phase returns: contacts, predictive rays, a
// summary per pair and statistics per step.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rtcd/config.hpp"
#include "rtcd/export.hpp"

namespace rtcd {
RTCD_PUBLIC_BEGIN

using BodyId = uint32_t;
using ShapeId = uint32_t;

// A candidate pair from the host's broad phase. Both directions are done:
// a's ray origins against b, and b's against a.
struct BodyPair {
  BodyId a = 0;
  BodyId b = 0;
};

// A pair's key, the same in either order (the lower id in the high half),
// and the pair a key stands for, lower id first: what hosts and recordings
// keep per-pair state by.
constexpr uint64_t pair_key(BodyId a, BodyId b) { return (uint64_t(a < b ? a : b) << 32) | (a < b ? b : a); }
constexpr BodyPair pair_of_key(uint64_t key) { return {BodyId(key >> 32), BodyId(key & 0xffffffffu)}; }

enum class Side : uint8_t { a, b };

// How a walked ray's line ended (hit, behind, front, boundary, ...: see
// line_status_name), the kernel's rtcd_line_status.
inline constexpr int kLineStatusCount = 7;  // which body of the pair cast the ray

// Fields common to a penetrating ray and a predictive one (world frame).
struct RayRecord {
  Side source = Side::a;
  BodyId source_body = 0;
  BodyId target_body = 0;
  uint32_t vertex = 0;    // ray origin index in the source shape (a mesh vertex)
  int32_t triangle = -1;  // impacted triangle of the target (box: face 0..5, sphere: 0)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();     // the source vertex
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  // unit, the source's inward normal
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();     // unit outward normal of the impacted triangle
};

// What found a contact: a ray from a vertex inside the target, an edge of
// the source that crosses the target with neither end inside, or a
// sphere's deepest point inside a sphere or box target (closed form).
enum class ContactKind : uint8_t { vertex, edge, sphere };
const char* to_string(ContactKind kind);

// One point of the source inside the target; moving it by direction * depth
// brings it to the target's surface. Vertex contacts: the vertex `origin`,
// toward the nearest point of the target's surface on `triangle`
// (Config::nearest_surface: depth is the true penetration), or with it off
// (the thesis' ray contact) along its inward normal `direction`, out
// through `triangle`. Edge
// contacts: the point `origin` of the edge `edge` halfway between where
// its line enters the target from either end, `direction` toward the
// nearest point of the target's surface, on `triangle` (see
// docs/ARCHITECTURE.md, Edge contacts).
struct Contact : RayRecord {
  ContactKind kind = ContactKind::vertex;
  // Edge contacts: the source's two vertex ids, the lower first (`vertex`
  // holds the first); vertex contacts: {vertex, vertex}.
  std::array<uint32_t, 2> edge{};
  double depth = 0.0;
  double projected_depth = 0.0;  // depth * |direction . normal| (section 2.2)
  // What to move the source vertex by to separate. Measured to the nearest
  // surface (Config::nearest_surface, and every edge and sphere contact):
  // direction * depth, the way out (the surface's normal there). Ray
  // contacts: normal * projected_depth when Config::projected, direction *
  // depth otherwise.
  Eigen::Vector3d push = Eigen::Vector3d::Zero();
};

// A vertex outside the target, within distance_extension of it along its
// outward normal: tracked so the walk sees it penetrate.
struct PredictiveRay : RayRecord {
  double distance = 0.0;
};

// certified: proven apart by the shapes' distance bounds at an earlier full
// step, and not moved past that proof's margin since: no rays this step.
enum class PairMode : uint8_t { full, iterative, certified };
const char* to_string(PairMode mode);

struct PairResult {
  BodyPair pair;
  bool colliding = false;
  PairMode mode = PairMode::full;
  double max_depth = 0.0;
  // Device backends: the device its rays ran on (a pair stays on one while
  // it stays in the broad phase); -1: the CPU, or no rays (certified).
  int32_t device = -1;
  // Ranges into StepResult::contacts and ::predictive.
  size_t first_contact = 0, contact_count = 0;
  size_t first_predictive = 0, predictive_count = 0;
};

// The step's rays by what they did: summed per job by the executors
// (RayTally) and per step by the pipeline. What each counts is in
// kRayCounters, the one table the sums, the JSON and docs/knobs.md read.
struct RayCounts {
  size_t candidates{}, rays_full{}, rays_predictive{}, rays_iterative{}, walk_steps{};
  size_t nearest_queries{}, rays_retraced{}, rays_watched{}, fold_casts{};
  size_t edges_tested{}, edges_skipped{}, edge_rays{}, edge_contacts{}, edges_held{};
  std::array<size_t, kLineStatusCount> walk_endings{};  // iterative rays by how their line ended (line_status_name)

  RayCounts& operator+=(const RayCounts& other);
  // The vertex rays: traced in full, predictive and walked (the replay
  // tables' "rays"); edge rays are counted apart.
  size_t rays() const { return rays_full + rays_predictive + rays_iterative; }
};

struct RayCounter {
  const char* name;
  size_t RayCounts::*field;
  const char* meaning;
};
inline constexpr RayCounter kRayCounters[] = {
    {"candidates", &RayCounts::candidates,
     "ray origins inside the grown bounding-box overlap"},
    {"rays_full", &RayCounts::rays_full,
     "inward rays traced in full steps"},
    {"rays_predictive", &RayCounts::rays_predictive,
     "outward predictive rays traced (full steps and re-traces)"},
    {"rays_iterative", &RayCounts::rays_iterative,
     "tracked rays walked in iterative steps"},
    {"walk_steps", &RayCounts::walk_steps,
     "triangles located by all walks"},
    {"nearest_queries", &RayCounts::nearest_queries,
     "nearest-triangle queries: vertices neither ray met, watched edges in their first walking step"},
    {"rays_retraced", &RayCounts::rays_retraced,
     "walked rays whose walks could not tell inside from outside, traced again"},
    {"rays_watched", &RayCounts::rays_watched,
     "tracked rays that reported nothing (vertices and edges near the target)"},
    {"fold_casts", &RayCounts::fold_casts,
     "walked contacts whose fold check cast a ray (beyond their face's clearance)"},
    {"edges_tested", &RayCounts::edges_tested,
     "edges (and spheres' deepest points) taken for a crossing test (Config::edge_contacts)"},
    {"edges_skipped", &RayCounts::edges_skipped,
     "of those, watched mesh edges that needed no ray: farther from the surface than the pair has moved, or none within reach"},
    {"edge_rays", &RayCounts::edge_rays,
     "rays those tests cast"},
    {"edge_contacts", &RayCounts::edge_contacts,
     "edges that cross the target with neither end inside"},
    {"edges_held", &RayCounts::edges_held,
     "watched edges whose last test stands: their pair has moved less than edge_retest_motion since (not in "
     "edges_tested)"},
};

// One device's share of a step (OpenCL backends): its rays, and what driving
// it took — commands, the host's waits on it, bytes each way, and the
// device's own time from its queue's profiling events.
struct DeviceWork {
  size_t jobs = 0;  // pair-directions it ran, those with ray origins to try
  size_t rays = 0;  // candidate rays it traced or walked
  size_t launches = 0;  // kernels enqueued
  size_t writes = 0, reads = 0;  // copies enqueued from the host, to the host (recovery reads too)
  size_t waits = 0;  // times the host blocked until the device was done with something
  size_t bytes_to_device = 0, bytes_from_device = 0;
  // Bytes read back apart, without a wait: the tracked rays' walk starts,
  // which the host waits for only to reorder them or to take a pair over.
  size_t bytes_recovery = 0;
  // Run time of its kernels and of its copies, each command from its start
  // to its end on the device. A command still running when the step ends (the
  // kernel keeping the tracked rays, enqueued after the last read) is
  // counted in the step in which it is seen finished.
  double seconds_kernels = 0, seconds_copies = 0;

  // Summed field by field: the work of several devices or steps.
  DeviceWork& operator+=(const DeviceWork& o) {
    jobs += o.jobs;
    rays += o.rays;
    launches += o.launches;
    writes += o.writes;
    reads += o.reads;
    waits += o.waits;
    bytes_to_device += o.bytes_to_device;
    bytes_from_device += o.bytes_from_device;
    bytes_recovery += o.bytes_recovery;
    seconds_kernels += o.seconds_kernels;
    seconds_copies += o.seconds_copies;
    return *this;
  }
};

// The step's counters beside the ray counters: kStepCounters says what each counts.
struct StepStats : RayCounts {
  size_t pairs_full = 0, pairs_iterative = 0;
  size_t fallbacks_to_full = 0;
  size_t pairs_certified = 0, certificates_granted = 0, certificates_expired = 0;
  size_t bytes_to_device = 0, bytes_from_device = 0, bytes_recovery = 0;
  // Over the devices (DeviceWork): kernels enqueued, copies each way,
  // blocking waits; their kernels' and copies' device time.
  size_t device_launches = 0, device_writes = 0, device_reads = 0, device_waits = 0;
  double seconds_device_kernels = 0, seconds_device_copies = 0;
  // Where the rays ran: one entry per device of a device backend, in its
  // order (empty on the CPU backends); rays the CPU ran in a device's stead
  // are in no entry.
  std::vector<DeviceWork> devices;
  // Why this step's rays ran on the CPU instead of the backend's devices
  // (from the failing batch on); empty when they did not.
  std::string cpu_fallback;
  // Wall time of the step's stages. A device backend enqueues the full
  // batch in seconds_full and waits for it with the walks, in
  // seconds_iterative; their sum is the step's ray time either way.
  double seconds_prepare = 0, seconds_full = 0, seconds_iterative = 0, seconds_gather = 0;

  // Zeroes every figure, keeping the buffer of `devices`: a steady step
  // allocates nothing.
  void reset();
};

// The pair and traffic counters of StepStats: the JSON and docs/knobs.md
// read this table, as they read kRayCounters.
struct StepCounter {
  const char* name;
  size_t StepStats::*field;
  const char* meaning;
};
inline constexpr StepCounter kStepCounters[] = {
    {"pairs_full", &StepStats::pairs_full, "pairs traced in full: new, sent back by equation 2.1, or every pair in full mode"},
    {"pairs_iterative", &StepStats::pairs_iterative, "pairs walked from their tracked rays"},
    {"fallbacks_to_full", &StepStats::fallbacks_to_full,
     "pairs with state that equation 2.1 sent back to full tracing (automatic mode)"},
    {"pairs_certified", &StepStats::pairs_certified,
     "pairs skipped without a ray: proven apart at an earlier full step, moved less than that proof's margin since "
     "(Config::trace_separated_pairs off)"},
    {"certificates_granted", &StepStats::certificates_granted,
     "pairs traced in full with nothing to report that the distance bounds proved apart by more than the distance "
     "extension"},
    {"certificates_expired", &StepStats::certificates_expired,
     "certified pairs whose motion passed their margin, traced in full this step"},
    {"bytes_to_device", &StepStats::bytes_to_device, "bytes copied from the host to the devices (0 on the CPU)"},
    {"bytes_from_device", &StepStats::bytes_from_device,
     "bytes copied from the devices to the host, the recovery reads apart (0 on the CPU)"},
    {"bytes_recovery", &StepStats::bytes_recovery,
     "bytes of tracked rays read back from the devices without a wait, waited for only when the host reorders them "
     "or the CPU takes a pair over"},
    {"device_launches", &StepStats::device_launches, "kernels enqueued on the devices (0 on the CPU)"},
    {"device_writes", &StepStats::device_writes, "copies enqueued from the host to the devices"},
    {"device_reads", &StepStats::device_reads, "copies enqueued from the devices to the host"},
    {"device_waits", &StepStats::device_waits, "times the host blocked until a device had finished a command"},
};

struct StepResult {
  std::vector<PairResult> pairs;  // in input order
  std::vector<Contact> contacts;  // grouped by pair, a's rays first, by vertex
  std::vector<PredictiveRay> predictive;
  StepStats stats;

  std::span<const Contact> contacts_of(const PairResult& p) const {
    return std::span(contacts).subspan(p.first_contact, p.contact_count);
  }
  std::span<const PredictiveRay> predictive_of(const PairResult& p) const {
    return std::span(predictive).subspan(p.first_predictive, p.predictive_count);
  }
};

const char* line_status_name(int status);  // rtcd_line_status → "hit", "behind", ...

RTCD_PUBLIC_END
}  // namespace rtcd

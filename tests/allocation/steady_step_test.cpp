// A steady-contact step allocates nothing once its buffers have grown: this
// binary counts every heap allocation of the process — malloc and its kin,
// from any library (Embree, TBB, the OpenCL driver, the C library itself) —
// and, apart, C++ operator new (the library's containers, the OpenCL C++
// wrappers). Heap blocks only: a thread's stack or a driver's mmap is not
// counted. The CPU backends make none of either; the OpenCL backends make no
// C++ allocation, while the OpenCL runtime mallocs for each command it is
// given (PoCL, two devices: 200 to 420 a step), which the test reports.
// glibc lets a program replace malloc; the replacements pass each call on to
// glibc's own allocator. Not run under AddressSanitizer, whose allocator the
// replacements would bypass (scripts/sanitize.sh).
#include <malloc.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <iostream>
#include <new>

#include <btBulletDynamicsCommon.h>
#include <gtest/gtest.h>

#include "rtcd/backend.hpp"
#include "rtcd/mesh_gen.hpp"
#include "rtcd/narrow_phase.hpp"
#include "rtcd/sim/dispatcher.hpp"
#include "support.hpp"

namespace {
std::atomic<size_t> allocations{0};      // every heap allocation
std::atomic<size_t> cxx_allocations{0};  // those through operator new
void count() { allocations.fetch_add(1, std::memory_order_relaxed); }
}  // namespace

// glibc's allocator under its own names.
extern "C" {
void* __libc_malloc(size_t size);
void* __libc_calloc(size_t count, size_t size);
void* __libc_realloc(void* p, size_t size);
void* __libc_memalign(size_t alignment, size_t size);
void* __libc_valloc(size_t size);
void* __libc_pvalloc(size_t size);
void __libc_free(void* p);

void* malloc(size_t size) {
  count();
  return __libc_malloc(size);
}
void* calloc(size_t n, size_t size) {
  count();
  return __libc_calloc(n, size);
}
// realloc(p, 0) frees, realloc(nullptr, n) allocates: both counted alike,
// as any call that may take a block from the heap.
void* realloc(void* p, size_t size) {
  count();
  return __libc_realloc(p, size);
}
void* memalign(size_t alignment, size_t size) {
  count();
  return __libc_memalign(alignment, size);
}
void* aligned_alloc(size_t alignment, size_t size) {
  count();
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, size_t alignment, size_t size) {
  count();
  if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0) return EINVAL;
  void* p = __libc_memalign(alignment, size);
  if (!p && size) return ENOMEM;
  *out = p;
  return 0;
}
void* valloc(size_t size) {
  count();
  return __libc_valloc(size);
}
void* pvalloc(size_t size) {
  count();
  return __libc_pvalloc(size);
}
void free(void* p) { __libc_free(p); }
}

// operator new is counted again apart. libstdc++'s array and nothrow forms
// call these two; the default deletes free what they return.
void* operator new(size_t size) {
  cxx_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
void* operator new(size_t size, std::align_val_t alignment) {
  cxx_allocations.fetch_add(1, std::memory_order_relaxed);
  const size_t a = size_t(alignment);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}

namespace rtcd {
namespace {

struct Steady {
  std::unique_ptr<NarrowPhase> narrow;
  std::vector<BodyPair> pairs;
  std::vector<Pose> b_poses;
};

// `count` copies of two blobs overlapping at rest, 10 units apart.
Steady make_steady(const std::string& backend, Mode mode, int count) {
  Config config;
  config.mode = mode;
  Steady s{make_narrow_phase(backend, config), {}, {}};
  const ShapeId a = s.narrow->add_shape(std::make_shared<Shape>(gen::concave_blob(300, 1)));
  const ShapeId b = s.narrow->add_shape(std::make_shared<Shape>(gen::concave_blob(300, 2)));
  for (int i = 0; i < count; ++i) {
    Pose pa, pb;
    pa.position = {10.0 * i, 0, 0};
    pb.position = {10.0 * i + 1.4, 0.1, 0.05};
    s.pairs.push_back({s.narrow->add_body(a, pa), s.narrow->add_body(b, pb)});
    s.b_poses.push_back(pb);
  }
  return s;
}

struct Allocations {
  size_t heap = 0;  // every one, operator new's included
  size_t cxx = 0;   // through operator new
  size_t most_heap_in_a_step = 0;  // the busiest step's
};

// What the measured steps did: contacts of the last, the steps in which
// every pair walked and some ray was walked, the pairs skipped on a
// certificate and the certificates granted and expired, summed; the most
// devices that ran commands in a step.
struct Measured {
  size_t contacts = 0, walked_steps = 0, certified = 0, granted = 0, expired = 0, devices = 0;
};

// Allocations made by `steps` steps after `warmup` steps, B moved by
// jitter(step) along y; `begun`: each step by detect_begin and detect_end.
template <class Jitter>
Allocations allocations_in_steady_steps(Steady& s, int warmup, int steps, Measured& m, const Jitter& jitter,
                                        bool begun = false) {
  StepResult result;
  Allocations before;
  size_t most = 0, step_start = 0;
  for (int step = 0; step < warmup + steps; ++step) {
    if (step == warmup) before = {allocations.load(), cxx_allocations.load()};
    if (step > warmup) most = std::max(most, allocations.load() - step_start);
    step_start = allocations.load();
    for (size_t i = 0; i < s.pairs.size(); ++i) {
      Pose p = s.b_poses[i];
      p.position.y() += jitter(step);
      s.narrow->set_pose(s.pairs[i].b, p);
    }
    if (begun) {
      s.narrow->detect_begin(s.pairs, result);
      s.narrow->detect_end();
    } else {
      s.narrow->detect(s.pairs, result);
    }
    if (step < warmup) continue;
    const bool all_walked = std::all_of(result.pairs.begin(), result.pairs.end(),
                                        [](const PairResult& p) { return p.mode == PairMode::iterative; });
    m.walked_steps += all_walked && result.stats.rays_iterative > 0;
    m.certified += result.stats.pairs_certified;
    m.granted += result.stats.certificates_granted;
    m.expired += result.stats.certificates_expired;
    const auto busy = size_t(std::count_if(result.stats.devices.begin(), result.stats.devices.end(),
                                           [](const DeviceWork& w) { return w.launches > 0; }));
    m.devices = std::max(m.devices, busy);
  }
  most = std::max(most, allocations.load() - step_start);
  m.contacts = result.contacts.size();
  return {allocations.load() - before.heap, cxx_allocations.load() - before.cxx, most};
}
// B jittering by 1e-3.
Allocations allocations_in_steady_steps(Steady& s, int warmup, int steps, Measured& m) {
  return allocations_in_steady_steps(s, warmup, steps, m, [](int step) { return step % 2 ? 1e-3 : 0.0; });
}

TEST(Allocation, TheCounterSeesAllocations) {
  size_t before = allocations.load();
  std::vector<int> grown;
  size_t cxx_before = cxx_allocations.load();
  grown.resize(100);
  EXPECT_GE(allocations.load() - before, 1u) << "operator new reaches malloc";
  EXPECT_GE(cxx_allocations.load() - cxx_before, 1u) << "operator new";
  before = allocations.load();
  void* p = std::malloc(64);  // a call the compiler may not elide: its result escapes
  asm volatile("" : : "r"(p) : "memory");
  std::free(p);
  EXPECT_GE(allocations.load() - before, 1u) << "malloc";
  before = allocations.load();
  void* q = nullptr;
  EXPECT_EQ(posix_memalign(&q, 64, 256), 0);
  std::free(q);
  EXPECT_GE(allocations.load() - before, 1u) << "posix_memalign (Embree's and TBB's aligned blocks)";
}

class SteadyStep : public ::testing::TestWithParam<std::tuple<std::string, Mode, int>> {};

TEST_P(SteadyStep, AllocatesNothing) {
  const auto& [backend, mode, count] = GetParam();
  Steady s = make_steady(backend, mode, count);
  Measured m;
  const Allocations made = allocations_in_steady_steps(s, 4, 10, m);
  EXPECT_EQ(made.cxx, 0u) << "C++ allocations in 10 steady steps";
  if (backend.starts_with("opencl")) {
    // The OpenCL runtime's own, reported: not ours to remove. Bounded by
    // the commands a step enqueues and their arguments, not by its pairs or
    // rays: PoCL makes about 715 a step in full mode and 526 walking with
    // 64 pairs on two devices, 355 and 261 with one pair on one (fewer in a
    // process whose runtime ran before, or under load); one allocation per
    // pair in full mode (64 more) lands near the ceiling, so
    // OpenClRuntimeAllocatesAsMuchForOnePairAsFor64 holds every mode to its
    // one-pair count.
    RecordProperty("runtime_mallocs_per_step", std::to_string(made.heap / 10));
    std::cout << "OpenCL runtime: " << made.heap / 10 << " heap allocations a step\n";
    EXPECT_LE(made.heap / 10, 760u) << "the OpenCL runtime's allocations a step";
  } else {
    EXPECT_EQ(made.heap, 0u) << "heap allocations in 10 steady steps";
  }
  EXPECT_GT(m.contacts, 0u) << "the bodies must be in contact for the test to mean anything";
  // The walking modes' measured steps walk: their buffers are the walks'.
  if (mode != Mode::full) {
    EXPECT_EQ(m.walked_steps, 10u) << "measured steps in which every pair walked";
  }
}

// The OpenCL runtime's own allocations a step do not grow with the pairs:
// one pair and 64, in one process after both warmed up (a runtime's first
// steps allocate more), make as many per busy device in each mode, within
// 8 in the step that allocates most (358 a device in full, 264 walking, on
// PoCL's pthread devices). The busiest step, not the mean: a loaded machine
// lets PoCL skip some of its allocations in some steps (a mean 17 below the
// usual, seen in CI), never add to them. One allocation per pair would add
// 32 a device. The 64 pairs spread over both devices, the one pair runs on
// one.
TEST(Allocation, OpenClRuntimeAllocatesAsMuchForOnePairAsFor64) {
  for (Mode mode : {Mode::full, Mode::iterative, Mode::automatic}) {
    SCOPED_TRACE(to_string(mode));
    Steady one = make_steady("opencl", mode, 1), many = make_steady("opencl", mode, 64);
    Measured m1, m64;
    allocations_in_steady_steps(one, 4, 1, m1);
    allocations_in_steady_steps(many, 4, 1, m64);
    const Allocations a1 = allocations_in_steady_steps(one, 2, 10, m1);
    const Allocations a64 = allocations_in_steady_steps(many, 2, 10, m64);
    ASSERT_GT(m1.devices * m64.devices, 0u) << "no device ran: the comparison would be vacuous";
    const double per_device1 = double(a1.most_heap_in_a_step) / double(m1.devices);
    const double per_device64 = double(a64.most_heap_in_a_step) / double(m64.devices);
    std::cout << to_string(mode) << ": " << per_device1 << " and " << per_device64
              << " in the busiest step a device, mean " << double(a1.heap) / double(10 * m1.devices) << " and "
              << double(a64.heap) / double(10 * m64.devices) << " (" << m1.devices << " and " << m64.devices
              << " devices)\n";
    EXPECT_EQ(a1.cxx, 0u) << "C++ allocations in 10 steps of 1 pair";
    EXPECT_EQ(a64.cxx, 0u) << "C++ allocations in 10 steps of 64 pairs";
    EXPECT_NEAR(per_device64, per_device1, 8.0) << "the runtime's allocations in the busiest step a device, 1 pair against 64";
    EXPECT_GT(a1.heap, 0u) << "the runtime allocated nothing: the comparison would be vacuous";
    EXPECT_GT(m64.contacts, m1.contacts);
  }
}

// Pairs apart certified (trace_separated_pairs off), their certificates
// expiring and granted again as B jumps 0.4 (past the margin) every four
// steps: skipped, expired and granted steps allocate nothing either.
TEST(Allocation, CertifiedStepsAllocateNothing) {
  for (const std::string backend : {"basic", "embree"}) {
    SCOPED_TRACE(backend);
    Config config;
    config.trace_separated_pairs = false;
    config.distance_extension = 0.05;
    config.displacement_threshold = 0.02;
    Steady s{make_narrow_phase(backend, config), {}, {}};
    const ShapeId a = s.narrow->add_shape(std::make_shared<Shape>(gen::concave_blob(300, 1)));
    const ShapeId b = s.narrow->add_shape(std::make_shared<Shape>(gen::concave_blob(300, 2)));
    for (int i = 0; i < 8; ++i) {
      Pose pa, pb;
      pa.position = {10.0 * i, 0, 0};
      pb.position = {10.0 * i + 3.0, 0.1, 0.05};  // apart
      s.pairs.push_back({s.narrow->add_body(a, pa), s.narrow->add_body(b, pb)});
      s.b_poses.push_back(pb);
    }
    Measured m;
    const Allocations made =
        allocations_in_steady_steps(s, 8, 16, m, [](int step) { return step % 8 < 4 ? 0.0 : 0.4; });
    EXPECT_EQ(made.cxx, 0u) << "C++ allocations in 16 steps";
    EXPECT_EQ(made.heap, 0u) << "heap allocations in 16 steps";
    EXPECT_GT(m.certified, 0u) << "pairs skipped";
    EXPECT_GT(m.granted, 0u) << "certificates granted";
    EXPECT_GT(m.expired, 0u) << "certificates expired";
  }
}

// Steps in two halves (detect_begin, detect_end) hand over to the narrow
// phase's worker thread, started in the warm-up, and allocate nothing.
TEST(Allocation, BegunStepsAllocateNothing) {
  for (const std::string backend : {"basic", "embree"}) {
    SCOPED_TRACE(backend);
    Steady s = make_steady(backend, Mode::automatic, 16);
    Measured m;
    const Allocations made =
        allocations_in_steady_steps(s, 4, 10, m, [](int step) { return step % 2 ? 1e-3 : 0.0; }, true);
    EXPECT_EQ(made.cxx, 0u) << "C++ allocations in 10 steps";
    EXPECT_EQ(made.heap, 0u) << "heap allocations in 10 steps";
    EXPECT_GT(m.contacts, 0u);
    EXPECT_EQ(m.walked_steps, 10u);
  }
}

std::string name(const ::testing::TestParamInfo<SteadyStep::ParamType>& info) {
  const auto& [backend, mode, count] = info.param;
  return test::test_name(backend) + "_" + (mode == Mode::automatic ? std::string("auto") : to_string(mode)) + "_" +
         std::to_string(count);
}

INSTANTIATE_TEST_SUITE_P(Backends, SteadyStep,
                         ::testing::Combine(::testing::ValuesIn(test::usable_backends()),
                                            ::testing::Values(Mode::full, Mode::iterative, Mode::automatic),
                                            ::testing::Values(1, 64)),
                         name);

// The Bullet host's batch: choosing and writing each pair's solver points
// (touching ones, then speculative gaps sorted by whether they close within
// the step) keeps its scratch from batch to batch. A blob sinking into
// another as it falls: some points touch, some gaps close and some do not.
TEST(Allocation, DispatcherSteadyBatchAllocatesNothing) {
  Config config;
  config.mode = Mode::automatic;
  auto narrow = make_narrow_phase("embree", config);
  const ShapeId shape = narrow->add_shape(std::make_shared<Shape>(gen::concave_blob(300, 1)));
  btDefaultCollisionConfiguration configuration;
  sim::DispatcherOptions options;
  options.speculative = true;
  sim::BatchDispatcher dispatcher(&configuration, *narrow, options);
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &configuration);
  world.setGravity(btVector3(0, 0, 0));
  btBoxShape bounds(btVector3(1.5f, 1.5f, 1.5f));
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  for (int i = 0; i < 2; ++i) {
    Pose pose;
    pose.position = {0.1 * i, 0.05 * i, 2.1 * i};
    btRigidBody::btRigidBodyConstructionInfo info(1, nullptr, &bounds, btVector3(1, 1, 1));
    info.m_startWorldTransform.setOrigin(btVector3(btScalar(pose.position.x()), btScalar(pose.position.y()),
                                                   btScalar(pose.position.z())));
    bodies.push_back(std::make_unique<btRigidBody>(info));
    world.addRigidBody(bodies.back().get());
    dispatcher.link(bodies.back().get(), {narrow->add_body(shape, pose), Pose{}, 0.5, 0.0});
  }
  bodies[1]->setLinearVelocity(btVector3(0, 0, -3));
  world.getDispatchInfo().m_timeStep = btScalar(1.0 / 60);
  world.performDiscreteCollisionDetection();
  btOverlappingPairCache* pairs = broadphase.getOverlappingPairCache();
  for (int batch = 0; batch < 4; ++batch) dispatcher.dispatchAllCollisionPairs(pairs, world.getDispatchInfo(), &dispatcher);
  const sim::BatchDispatcher::Batch& last = dispatcher.last_batch();
  ASSERT_EQ(last.pairs, 1u);
  ASSERT_GT(last.points - last.speculative_points, 0u) << "touching points";
  ASSERT_GT(last.speculative_points, 0u) << "speculative points";
  const Allocations before{allocations.load(), cxx_allocations.load()};
  for (int batch = 0; batch < 10; ++batch)
    dispatcher.dispatchAllCollisionPairs(pairs, world.getDispatchInfo(), &dispatcher);
  EXPECT_EQ(cxx_allocations.load() - before.cxx, 0u) << "C++ allocations in 10 steady batches";
  EXPECT_EQ(allocations.load() - before.heap, 0u) << "heap allocations in 10 steady batches";
  for (auto& body : bodies) {
    dispatcher.unlink(body.get());
    world.removeRigidBody(body.get());
  }
}

}  // namespace
}  // namespace rtcd

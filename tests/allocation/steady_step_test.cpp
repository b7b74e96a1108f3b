// A steady-contact step allocates nothing once its buffers have grown: this
// binary replaces the global operator new to count every heap allocation
// made through it (the library's containers, Eigen's fixed-size vectors).
#include <atomic>
#include <cstdlib>
#include <new>

#include <gtest/gtest.h>

#include "rtcd/mesh_gen.hpp"
#include "rtcd/narrow_phase.hpp"
#include "support.hpp"

namespace {
std::atomic<size_t> allocations{0};
}  // namespace

// GCC pairs operator new with free() here and warns; they are a matched pair.
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

void* operator new(std::size_t size) {
  allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
// Every form is replaced, so whatever a library calls (PoCL's compiler uses
// the nothrow one) is counted and pairs with free(); a form left to the
// runtime would allocate where AddressSanitizer then sees free() on it.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  allocations.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept { return operator new(size, tag); }
void* operator new(std::size_t size, std::align_val_t align) {
  allocations.fetch_add(1, std::memory_order_relaxed);
  const std::size_t a = std::size_t(align);
  if (void* p = std::aligned_alloc(a, (size + a - 1) / a * a)) return p;  // a multiple of the alignment
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t align) { return operator new(size, align); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

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

// Allocations made by `steps` steps after `warmup` steps, B jittering by 1e-3.
size_t allocations_in_steady_steps(Steady& s, int warmup, int steps, size_t& contacts) {
  StepResult result;
  size_t before = 0;
  for (int step = 0; step < warmup + steps; ++step) {
    if (step == warmup) before = allocations.load();
    for (size_t i = 0; i < s.pairs.size(); ++i) {
      Pose p = s.b_poses[i];
      p.position.y() += step % 2 ? 1e-3 : 0.0;
      s.narrow->set_pose(s.pairs[i].b, p);
    }
    s.narrow->detect(s.pairs, result);
  }
  contacts = result.contacts.size();
  return allocations.load() - before;
}

TEST(Allocation, TheCounterSeesAllocations) {
  const size_t before = allocations.load();
  std::vector<int> grown;
  grown.resize(100);
  EXPECT_GE(allocations.load() - before, 1u);
}

class SteadyStep : public ::testing::TestWithParam<std::tuple<std::string, Mode, int>> {};

TEST_P(SteadyStep, AllocatesNothing) {
  const auto& [backend, mode, count] = GetParam();
  Steady s = make_steady(backend, mode, count);
  size_t contacts = 0;
  EXPECT_EQ(allocations_in_steady_steps(s, 4, 10, contacts), 0u);
  EXPECT_GT(contacts, 0u) << "the bodies must be in contact for the test to mean anything";
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

}  // namespace
}  // namespace rtcd

// Backends by typed description: the string form read and written in one
// place, and a narrow phase's thread count its own.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>

#include "rtcd/backend.hpp"
#include "rtcd/cpu_executor.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"
#include "support.hpp"

namespace rtcd {
namespace {

TEST(BackendOptions, StringFormRoundTrips) {
  for (const char* text : {"auto", "basic", "embree", "embree:isa=avx2", "opencl", "opencl-basic", "opencl:gpu",
                           "opencl:cpu:devices=1,0:layout=grid", "opencl-basic:layout=compact", "basic:threads=3",
                           "opencl:devices=0:threads=2"}) {
    EXPECT_EQ(BackendOptions::parse(text).to_string(), text);
  }
  const BackendOptions o = BackendOptions::parse("opencl:layout=grid:gpu:devices=2,0");
  EXPECT_EQ(o.kind, BackendKind::opencl);
  EXPECT_EQ(o.device_type, DeviceType::gpu);
  EXPECT_EQ(o.devices, (std::vector<int>{2, 0}));
  EXPECT_EQ(o.layout, DeviceLayout::grid);
  EXPECT_EQ(o.to_string(), "opencl:gpu:devices=2,0:layout=grid") << "options in a fixed order";
}

TEST(BackendOptions, EveryUnknownPartIsNamed) {
  const std::pair<const char*, const char*> cases[] = {
      {"warp", "unknown backend 'warp'"},
      {"embree:gpu", "unknown option 'gpu'"},
      {"basic:isa=avx2", "unknown option 'isa=avx2'"},
      {"opencl:devices=0,x", "bad device index 'x'"},
      {"opencl:devices=1,1", "device 1 twice"},
      {"opencl:devices=", "bad device index ''"},
      {"opencl:layout=wide", "unknown option 'layout=wide'"},
      {"basic:threads=0", "threads takes a whole number of at least 1"},
      {"basic:threads=two", "threads takes a whole number"},
      {"basic:", "nothing after ':'"},
      {"opencl::gpu", "unknown option ''"},
  };
  for (const auto& [text, fragment] : cases) {
    try {
      BackendOptions::parse(text);
      ADD_FAILURE() << text << " parsed";
    } catch (const BackendError& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << text << ": " << e.what();
    }
  }
}

TEST(BackendOptions, OptionsTheKindDoesNotTakeAreRejected) {
  BackendOptions o;
  o.kind = BackendKind::basic;
  o.devices = {0};
  EXPECT_THROW(o.validate(), BackendError);
  EXPECT_THROW(make_narrow_phase(o), BackendError);
  o = {};
  o.kind = BackendKind::opencl;
  o.isa = "avx2";
  EXPECT_THROW(o.validate(), BackendError);
  o = {};
  o.threads = -1;
  EXPECT_THROW(make_narrow_phase(o), BackendError);
}

TEST(BackendOptions, TypedAndStringFormsMakeTheSameBackend) {
  BackendOptions o;
  o.kind = BackendKind::basic;
  o.threads = 1;
  EXPECT_EQ(make_narrow_phase(o)->name(), "basic") << "the name leaves out the thread count";
  EXPECT_EQ(make_narrow_phase("basic:threads=1")->name(), "basic");
  o.kind = BackendKind::embree;
  o.isa = "sse2";
  EXPECT_EQ(o.name(), "embree:isa=sse2");
  EXPECT_NE(make_narrow_phase(BackendOptions{})->name(), "auto") << "auto resolves to a kind";
}

// A tracer that hits nothing and notes the most threads the arena it ran
// in allows.
class ArenaProbe final : public MeshTracerFactory {
 public:
  explicit ArenaProbe(std::atomic<int>& seen) : seen_(seen) {}
  struct Tracer final : MeshTracer {
    std::atomic<int>* seen;
    TraceHit first_hit(const rtcd_ray&, float) const override {
      int now = tbb::this_task_arena::max_concurrency(), was = seen->load();
      while (now > was && !seen->compare_exchange_weak(was, now)) {
      }
      return {};
    }
    int32_t nearest(const rtcd_vec3&, float, float) const override { return -1; }
  };
  std::unique_ptr<MeshTracer> build(const Mesh&) const override {
    auto t = std::make_unique<Tracer>();
    t->seen = &seen_;
    return t;
  }

 private:
  std::atomic<int>& seen_;
};

int threads_seen(int threads) {
  std::atomic<int> seen{0};
  auto narrow = make_pipeline_narrow_phase("probe", {}, make_cpu_executor(std::make_unique<ArenaProbe>(seen)), {},
                                           threads);
  const ShapeId s = narrow->add_shape(test::shape(gen::icosphere(1.0, 2)));
  const BodyPair pair{narrow->add_body(s, test::at(0, 0, 0)), narrow->add_body(s, test::at(1.5, 0, 0))};
  narrow->detect(std::span(&pair, 1));
  return seen;
}

TEST(BackendOptions, EachNarrowPhaseHasItsOwnThreadCount) {
  const int cores = tbb::this_task_arena::max_concurrency();
  EXPECT_EQ(threads_seen(1), 1);
  EXPECT_EQ(threads_seen(0), cores) << "0: the caller's arena";
  // One narrow phase limited to one thread does not limit another made
  // in the same process, nor one stepped from inside its arena.
  EXPECT_EQ(threads_seen(std::max(cores, 2)), std::max(cores, 2));
  tbb::task_arena single(1);
  single.execute([&] { EXPECT_EQ(threads_seen(2), 2) << "its own arena, not the caller's"; });
}

}  // namespace
}  // namespace rtcd

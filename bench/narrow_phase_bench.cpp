// Rays per second of full tracing (basic, Embree) and of the iterative walk,
// on 902-triangle concave meshes in resting contact: one pair, and a batch.
// The OpenCL cases (where a device is usable) run the same on one device
// and on every device of the platform: /pairs/devices.
//   rtcd_bench [--benchmark_filter=...]
//   POCL_DEVICES="basic basic" rtcd_bench --benchmark_filter=opencl   # two single-threaded devices
#include <cstdio>
#include <thread>
#include <tuple>

#include "rtcd/backend.hpp"
#include "rtcd/distance_bound.hpp"
#include "rtcd/mesh_gen.hpp"

#include <benchmark/benchmark.h>

#include "bench_scene.hpp"

namespace {

using namespace rtcd;

struct Scene {
  std::unique_ptr<NarrowPhase> narrow;
  std::vector<BodyPair> pairs;
  std::vector<Pose> b_poses;
};

// `count` copies of the resting pair, 10 units apart so pairs never mix.
Scene make_scene(const std::string& backend, Mode mode, int count, bool verify_walks) {
  const bench::RestingPair& pair = bench::resting_pair();
  Config config;
  config.mode = mode;
  config.verify_walks = verify_walks;
  Scene s{make_narrow_phase(backend, config), {}, {}};
  const ShapeId sa = s.narrow->add_shape(pair.a), sb = s.narrow->add_shape(pair.b);
  for (int i = 0; i < count; ++i) {
    Pose pa, pb;
    pa.position = {10.0 * i, 0, 0};
    pb.position = pair.b_offset + Eigen::Vector3d(10.0 * i, 0, 0);
    s.pairs.push_back({s.narrow->add_body(sa, pa), s.narrow->add_body(sb, pb)});
    s.b_poses.push_back(pb);
  }
  return s;
}

// Steady contact: B jitters by 1e-3 (well under displacement_threshold).
void run(benchmark::State& state, const std::string& backend, Mode mode, bool verify_walks = true) {
  Scene s = make_scene(backend, mode, int(state.range(0)), verify_walks);
  s.narrow->detect(s.pairs);  // the first, full step
  size_t rays = 0, steps = 0, contacts = 0, walk_steps = 0, fold_casts = 0, up = 0, down = 0;
  size_t launches = 0, waits = 0;
  double prepare = 0, trace = 0, gather = 0, device = 0;
  StepResult r;  // reused: a host keeps its result buffers across steps
  for (auto _ : state) {
    const double jitter = (steps % 2 ? 1e-3 : 0.0);
    for (size_t i = 0; i < s.pairs.size(); ++i) {
      Pose p = s.b_poses[i];
      p.position.y() += jitter;
      s.narrow->set_pose(s.pairs[i].b, p);
    }
    s.narrow->detect(s.pairs, r);
    rays += r.stats.rays_full + r.stats.rays_predictive + r.stats.rays_iterative;
    contacts += r.contacts.size();
    walk_steps += r.stats.walk_steps;
    fold_casts += r.stats.fold_casts;
    up += r.stats.bytes_to_device;
    down += r.stats.bytes_from_device;
    launches += r.stats.device_launches;
    waits += r.stats.device_waits;
    device += r.stats.seconds_device_kernels;
    prepare += r.stats.seconds_prepare;
    trace += r.stats.seconds_full + r.stats.seconds_iterative;
    gather += r.stats.seconds_gather;
    ++steps;
  }
  state.counters["rays/s"] = benchmark::Counter(double(rays), benchmark::Counter::kIsRate);
  // Rays per second of the ray stage alone (tracing or walking), beside the whole step's.
  state.counters["ray stage rays/s"] = double(rays) / trace;
  state.counters["prepare us"] = 1e6 * prepare / double(steps);
  state.counters["rays us"] = 1e6 * trace / double(steps);
  state.counters["gather us"] = 1e6 * gather / double(steps);
  state.counters["rays/step"] = double(rays) / double(steps);
  state.counters["contacts/step"] = double(contacts) / double(steps);
  if (up + down > 0) {
    state.counters["bytes up/step"] = double(up) / double(steps);
    state.counters["bytes down/step"] = double(down) / double(steps);
    // What driving the devices took: kernels enqueued, blocking waits, and
    // the kernels' own time (profiling events), beside the ray stage's wall time.
    state.counters["launches/step"] = double(launches) / double(steps);
    state.counters["waits/step"] = double(waits) / double(steps);
    state.counters["kernels us"] = 1e6 * device / double(steps);
  }
  if (mode == Mode::iterative) {
    state.counters["walk steps/ray"] = double(walk_steps) / double(rays);
    state.counters["fold casts/step"] = double(fold_casts) / double(steps);
  }
}

void full_basic(benchmark::State& s) { run(s, "basic", Mode::full); }
void full_embree(benchmark::State& s) { run(s, "embree", Mode::full); }
void iterative(benchmark::State& s) { run(s, "embree", Mode::iterative); }
// Walked contacts trusted without the fold check.
void iterative_unverified(benchmark::State& s) { run(s, "embree", Mode::iterative, false); }

BENCHMARK(full_basic)->Arg(1)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(full_embree)->Arg(1)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(iterative)->Arg(1)->Arg(64)->Unit(benchmark::kMicrosecond);
BENCHMARK(iterative_unverified)->Arg(1)->Arg(64)->Unit(benchmark::kMicrosecond);

// A mesh's distance bound built from nothing (Shape::distance_bound), one
// core, on concave blobs of /triangles; the bytes it holds as a counter.
void distance_bound(benchmark::State& state) {
  const Mesh mesh = gen::concave_blob(int(state.range(0)), 1, 1.0);
  size_t bytes = 0;
  for (auto _ : state) {
    const Shape shape(mesh);
    bytes = shape.distance_bound().bytes();
    benchmark::DoNotOptimize(bytes);
  }
  state.counters["bytes"] = double(bytes);
}
BENCHMARK(distance_bound)->Arg(902)->Arg(20000)->Arg(200000)->Unit(benchmark::kMillisecond);

// An OpenCL variant on state.range(1) devices: the first one, or all.
void opencl(benchmark::State& state, const std::string& variant, Mode mode) {
  run(state, state.range(1) == 1 ? variant + ":devices=0" : variant, mode);
}

bool opencl_usable() {
  for (const auto& b : available_backends())
    if (b.name == "opencl" && b.usable) return true;
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  if (opencl_usable()) {
    for (const auto& [name, variant, mode] : {std::tuple{"opencl_full_basic", "opencl-basic", Mode::full},
                                              std::tuple{"opencl_full_bvh", "opencl", Mode::full},
                                              std::tuple{"opencl_iterative", "opencl", Mode::iterative},
                                              std::tuple{"opencl_grid_full_bvh", "opencl:layout=grid", Mode::full},
                                              std::tuple{"opencl_compact_iterative", "opencl:layout=compact", Mode::iterative}})
      benchmark::RegisterBenchmark(name, opencl, std::string(variant), mode)
          ->Args({1, 1})
          ->Args({64, 1})
          ->Args({64, 2})
          ->UseRealTime()  // the host thread mostly waits on the devices
          ->Unit(benchmark::kMicrosecond);
  }
  std::printf("rtcd_bench: backends");
  for (const auto& b : available_backends()) std::printf(" %s [%s]", b.name.c_str(), b.detail.c_str());
  std::printf("; hardware threads %u\n", std::thread::hardware_concurrency());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

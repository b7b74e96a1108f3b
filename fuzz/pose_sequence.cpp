// libFuzzer harness: the input is the JSON of a pose sequence
// (`rtcd query --sequence`), read by rtcd::app::read_sequence, then stepped
// on a fixed pair of 902-triangle concave blobs (blob_902 and stream_902 of
// data/meshes) with the pair state carried across steps, as the CLI does.
// rtcd::Error (UsageError for bad JSON or poses) is the accepted failure;
// every step must satisfy fuzz/invariants.hpp.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <tbb/global_control.h>
#include <unistd.h>

#include "rtcd/app/inputs.hpp"
#include "invariants.hpp"
#include "rtcd/backend.hpp"
#include "rtcd/error.hpp"
#include "rtcd/mesh_gen.hpp"

namespace {

using namespace rtcd;

tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);

const bool verbose = std::getenv("RTCD_FUZZ_VERBOSE") != nullptr;

// Built once: the Embree scenes of two 902-triangle meshes cost more than a step.
struct Rig {
  std::shared_ptr<const Shape> shape_a = std::make_shared<Shape>(gen::concave_blob(902, 1));
  std::shared_ptr<const Shape> shape_b = std::make_shared<Shape>(gen::concave_blob(902, 2));
  std::unique_ptr<NarrowPhase> narrow = make_narrow_phase(fuzz::cpu_backends().back());
  BodyPair pair;
  Rig() {
    pair.a = narrow->add_body(narrow->add_shape(shape_a), Pose{});
    pair.b = narrow->add_body(narrow->add_shape(shape_b), Pose{});
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Rig rig;
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("rtcd_fuzz_pose_sequence_" + std::to_string(::getpid()) + ".json");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  }
  std::vector<app::SequenceStep> steps;
  bool valid = true;
  try {
    steps = app::read_sequence(path.string());
  } catch (const Error& e) {
    valid = false;  // malformed sequences are rejected by design
    if (verbose) std::fprintf(stderr, "%s\n", e.what());
  }
  std::error_code ec;
  std::filesystem::remove(path, ec);
  if (!valid) return 0;

  // A step without the pair evicts its state: each input starts fresh, as a
  // new `rtcd query --sequence` would.
  StepResult out;
  rig.narrow->detect({}, out);
  for (size_t s = 0; s < steps.size(); ++s) {
    rig.narrow->set_pose(rig.pair.a, steps[s].a);
    rig.narrow->set_pose(rig.pair.b, steps[s].b);
    rig.narrow->detect(std::span(&rig.pair, 1), out);
    fuzz::check_step(rig.narrow->name() + " step " + std::to_string(s), out, rig.pair, *rig.shape_a, *rig.shape_b,
                     rig.narrow->config());
    if (verbose)
      std::fprintf(stderr, "step %zu: %s, %zu contacts, %zu predictive\n", s, to_string(out.pairs[0].mode),
                   out.contacts.size(), out.predictive.size());
  }
  return 0;
}

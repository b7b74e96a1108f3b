// `rtcd bench SCENE`: the thesis' experiments on a scene (docs/bench.md).
#pragma once

#include "rtcd/experiments/bench.hpp"

namespace rtcd::app {

// `options.scene` may name a scene under data/scenes ("avalanche"); an empty
// `options.out` becomes runs/bench-<scene>/. Exit 0 done, 2 bad input.
int run_bench(experiments::BenchOptions options, bool plots);

}  // namespace rtcd::app

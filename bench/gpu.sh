#!/usr/bin/env bash
# The OpenCL backend on a GPU: the validation families judged on it (full
# and iterative mode), the avalanche recording replayed on it with edge
# contacts (the default) and without (the thesis' configuration), the same
# replay on Embree with 2 threads and with every core of the machine, the
# stream of 500 bodies' recording on the GPU and on Embree, the
# host's side on 2 threads and on every core, and
# rtcd_bench's steady-contact cases. Needs an OpenCL GPU driver (its ICD).
#   bash bench/gpu.sh [OUT]        (default docs/results/gpu)
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:-docs/results/gpu}
bin=build/release/bin/rtcd
mkdir -p "$out"
recording=$(mktemp)
stream=$(mktemp)
trap 'rm -f "$recording" "$stream"' EXIT
xz -dc docs/results/avalanche/recording.rtcdrec.xz > "$recording"
xz -dc docs/results/stream/recording.rtcdrec.xz > "$stream"
{ nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv 2>/dev/null; lscpu | grep -E "Model name|^CPU\(s\)"; } > "$out/machine.txt"
"$bin" backends > "$out/backends.txt"
run() {
  local name=$1 start
  shift
  start=$(date +%s.%N)
  "$@" > "$out/$name.txt" 2>&1
  echo "$name: exit $?, $(awk "BEGIN{printf \"%.1f\", $(date +%s.%N) - $start}") s wall" | tee -a "$out/$name.txt"
}
run validate_full "$bin" validate --backend opencl:gpu --pairs 300 --no-oracles --mode full
run validate_iterative "$bin" validate --backend opencl:gpu --pairs 300 --no-oracles --mode iterative
all=$(nproc)
run replay_gpu "$bin" replay "$recording" --backend opencl:gpu
run replay_gpu_vertex "$bin" replay "$recording" --backend opencl:gpu --no-edge-contacts
run replay_embree2 "$bin" replay "$recording" --backend embree --threads 2
run replay_embree_all "$bin" replay "$recording" --backend embree --threads "$all"
# The host's side of each step (prepare, gather) on more threads.
for threads in 2 "$all"; do
  run replay_gpu_threads$threads "$bin" replay "$recording" --backend opencl:gpu --threads "$threads"
  run replay_gpu_vertex_threads$threads "$bin" replay "$recording" --backend opencl:gpu --threads "$threads" \
    --no-edge-contacts
done
run replay_embree_all_vertex "$bin" replay "$recording" --backend embree --threads "$all" --no-edge-contacts
run replay_stream_gpu "$bin" replay "$stream" --backend opencl:gpu --threads 2
run replay_stream_embree2 "$bin" replay "$stream" --backend embree --threads 2
run replay_gpu_full_threads$all "$bin" replay "$recording" --backend opencl:gpu --threads "$all" --mode full
run bench build/release/bench/rtcd_bench --benchmark_filter='opencl|full_embree|^iterative/' \
  --benchmark_repetitions=3 --benchmark_report_aggregates_only=true

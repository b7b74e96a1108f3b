#!/usr/bin/env bash
# Builds the libFuzzer harnesses (preset fuzz: clang, ASan, UBSan) and, for
# each, replays its saved regressions once, then fuzzes for FUZZ_SECONDS
# (default 60; 0 replays only) on a scratch copy of its seed corpus, so the
# committed corpus never grows. Exits non-zero when any harness crashes;
# crashing inputs are kept under build/fuzz/artifacts/<harness>/, copied
# to fuzz/regressions/<harness>/ and printed in base64 (the seed alone
# does not reproduce a finding: the corpus and the build change it).
#   scripts/fuzz.sh                      # every harness
#   FUZZ_SECONDS=600 scripts/fuzz.sh mesh_pair
# A campaign (FUZZ_CAMPAIGN=1): each harness for FUZZ_SECONDS on every core
# (libFuzzer's -fork, going on past crashes), then what it found merged
# with -merge=1 into fuzz/corpus/<harness>/ (only inputs that add coverage
# join the seeds), and every finding copied to fuzz/regressions/<harness>/
# for review: commit the corpus, fix each finding and keep it as a regression.
#   FUZZ_CAMPAIGN=1 FUZZ_SECONDS=3600 scripts/fuzz.sh
set -uo pipefail
cd "$(dirname "$0")/.."

seconds=${FUZZ_SECONDS:-60}
campaign=${FUZZ_CAMPAIGN:-0}
timeout=${FUZZ_TIMEOUT:-30}  # seconds one input may take before it counts as a hang
all=(mesh_pair mesh_file pose_sequence scene recording opencl)
if [ $# -gt 0 ]; then harnesses=("$@"); else harnesses=("${all[@]}"); fi

cmake --preset fuzz >/dev/null || exit 1
targets=()
for h in "${harnesses[@]}"; do targets+=("rtcd_fuzz_$h"); done
cmake --build --preset fuzz --target "${targets[@]}" || exit 1  # the harnesses only

# UBSan only reports by default: halt, so libFuzzer saves the input.
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
# PoCL's known leak is suppressed by the function it happens in
# (fuzz/lsan.supp); the opencl harness runs with the slow unwinder that
# names it (below), the others keep the fast one.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan.supp}
# The opencl harness runs on PoCL's CPU devices, two of them as in CI.
export POCL_DEVICES=${POCL_DEVICES:-"pthread pthread"}

scratch=$(mktemp -d "${TMPDIR:-/tmp}/rtcd_fuzz.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
failed=0
summary=()
for h in "${harnesses[@]}"; do
  bin=build/fuzz/fuzz/fuzz_$h
  if [ ! -x "$bin" ]; then
    echo "fuzz.sh: no harness '$h' (have: ${all[*]})" >&2
    exit 2
  fi
  artifacts=build/fuzz/artifacts/$h
  mkdir -p "$artifacts"
  result=ok
  unwind=()
  # (and without LSan's dynamic-TLS tracking, as scripts/sanitize.sh says why)
  [ "$h" = opencl ] && unwind=(env "ASAN_OPTIONS=${ASAN_OPTIONS:-fast_unwind_on_malloc=0:intercept_tls_get_addr=0}")

  # Regressions: each saved input once (libFuzzer runs file arguments and
  # stops). The opencl harness reads mesh_pair's inputs: it replays
  # mesh_pair's regressions too, so each is judged on OpenCL against basic.
  regressions=(fuzz/regressions/$h/*)
  [ "$h" = opencl ] && regressions=(fuzz/regressions/mesh_pair/* fuzz/regressions/opencl/*)
  mapfile -t regressions < <(for r in "${regressions[@]}"; do [ -e "$r" ] && echo "$r"; done)
  if [ "${#regressions[@]}" -gt 0 ]; then
    echo "== $h: ${#regressions[@]} regression input(s)"
    if ! "${unwind[@]}" "$bin" -timeout="$timeout" -artifact_prefix="$artifacts/" "${regressions[@]}" >"$scratch/$h.regressions.log" 2>&1; then
      tail -n 40 "$scratch/$h.regressions.log"
      result="regression crashed"
    fi
  fi

  runs="-"
  if [ "$seconds" -gt 0 ] && [ "$result" = ok ]; then
    echo "== $h: fuzzing ${seconds} s"
    # The opencl harness reads mesh_pair's input: it starts from its seeds.
    seeds=fuzz/corpus/$h
    [ "$h" = opencl ] && seeds=fuzz/corpus/mesh_pair
    cp -r "$seeds" "$scratch/$h"
    touch "$scratch/$h.log.start"
    dict=()
    [ -f "fuzz/$h.dict" ] && dict=(-dict="fuzz/$h.dict")
    # FUZZ_ARGS: extra libFuzzer flags, e.g. FUZZ_ARGS="-seed=1 -max_len=512".
    mode=()
    [ "$campaign" = 1 ] && mode=(-fork="$(nproc)" -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
    # shellcheck disable=SC2086
    "${unwind[@]}" "$bin" -max_total_time="$seconds" -timeout="$timeout" -rss_limit_mb=4096 -print_final_stats=1 \
      "${mode[@]}" "${dict[@]}" -artifact_prefix="$artifacts/" ${FUZZ_ARGS:-} "$scratch/$h" >"$scratch/$h.log" 2>&1
    rc=$?
    runs=$(grep -o 'Done [0-9]* runs in [0-9]* second(s)' "$scratch/$h.log" | tail -n 1)
    # A crash ends the run before "Done": count the executions from the final stats.
    [ -z "$runs" ] && runs=$(grep -o 'stat::number_of_executed_units: [0-9]*' "$scratch/$h.log" | sed 's/.*: /crashed after /;s/$/ runs/')
    # Fork mode reports its executions on its status lines (#N).
    [ -z "$runs" ] && runs=$(grep -o '^#[0-9]*' "$scratch/$h.log" | tail -n 1 | sed 's/#\(.*\)/\1 runs/')
    [ -n "$runs" ] && echo "$h: $runs"
    if [ "$campaign" = 1 ]; then
      # This campaign's findings: libFuzzer names them by kind.
      mapfile -t found < <(find "$artifacts" -maxdepth 1 -type f -newer "$scratch/$h.log.start" \
        \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' \))
      if [ "${#found[@]}" -gt 0 ]; then
        mkdir -p "fuzz/regressions/$h"
        cp "${found[@]}" "fuzz/regressions/$h/"
        result="${#found[@]} finding(s), copied to fuzz/regressions/$h/"
      elif [ $rc -ne 0 ]; then
        tail -n 60 "$scratch/$h.log"
        result="failed (rc $rc)"
      fi
      # The opencl harness reads mesh_pair's inputs: its corpus is mesh_pair's.
      if [ "$h" != opencl ]; then
        before=$(ls "fuzz/corpus/$h" | wc -l)
        "${unwind[@]}" "$bin" -merge=1 -timeout="$timeout" -rss_limit_mb=4096 "fuzz/corpus/$h" "$scratch/$h" \
          >"$scratch/$h.merge.log" 2>&1 &&
          echo "$h: $(($(ls "fuzz/corpus/$h" | wc -l) - before)) input(s) that add coverage merged into fuzz/corpus/$h"
      fi
    elif [ $rc -ne 0 ]; then
      tail -n 60 "$scratch/$h.log"
      # The input, not the seed, reproduces a finding: keep it as a
      # regression and print it, so a CI log alone carries it.
      mapfile -t found < <(find "$artifacts" -maxdepth 1 -type f -newer "$scratch/$h.log.start" \
        \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' -o -name 'slow-unit-*' \))
      mkdir -p "fuzz/regressions/$h"
      for f in "${found[@]}"; do
        cp "$f" "fuzz/regressions/$h/"
        echo "finding fuzz/regressions/$h/$(basename "$f") ($(stat -c %s "$f") bytes), base64:"
        head -c 65536 "$f" | base64
      done
      result="crashed (rc $rc; ${#found[@]} input(s) saved under fuzz/regressions/$h/)"
    fi
  fi
  [ "$result" = ok ] || failed=1
  summary+=("$(printf '%-14s %-36s %s' "$h" "${runs:--}" "$result")")
done

echo
echo "harness        executions                           result"
printf '%s\n' "${summary[@]}"
exit $failed

#!/usr/bin/env bash
# The test suite under AddressSanitizer and UndefinedBehaviorSanitizer (the
# asan preset): every label but the differential runs (their 1,000 pairs per
# family take too long instrumented; the robustness and conformance suites
# cover the same code paths), the consumer build and the allocation count
# (it replaces malloc, which would bypass ASan's allocator), each test bounded.
# The OpenCL tests run too, on PoCL's CPU devices (ctest sets POCL_DEVICES):
# LeakSanitizer skips PoCL's known leak by the function it happens in
# (fuzz/lsan.supp), which needs the slow unwinder; rtcd's own allocations,
# and those it makes through the OpenCL runtime, stay checked.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake --preset asan >/dev/null
cmake --build --preset asan
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan.supp}
export ASAN_OPTIONS=${ASAN_OPTIONS:-fast_unwind_on_malloc=0}
ctest --preset asan -j2 -LE "differential|consumer|allocation" --timeout 600 "$@"

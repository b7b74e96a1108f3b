#!/usr/bin/env bash
# The test suite under AddressSanitizer and UndefinedBehaviorSanitizer (the
# asan preset): every label but the differential runs (their 1,000 pairs per
# family take too long instrumented; the robustness and conformance suites
# cover the same code paths), the consumer build and the allocation count
# (it replaces malloc, which would bypass ASan's allocator), each test bounded.
# The OpenCL tests run too, on PoCL's CPU devices (ctest sets POCL_DEVICES):
# LeakSanitizer skips what the ICD loader and PoCL keep until exit
# (fuzz/lsan.supp names them); rtcd's own allocations stay checked.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake --preset asan >/dev/null
cmake --build --preset asan
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/fuzz/lsan.supp}
ctest --preset asan -j2 -LE "differential|consumer|allocation" --timeout 600 "$@"

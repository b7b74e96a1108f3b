#!/usr/bin/env bash
# The test suite under AddressSanitizer and UndefinedBehaviorSanitizer (the
# asan preset): every label but the differential runs (their 1,000 pairs per
# family take too long instrumented; the robustness and conformance suites
# cover the same code paths) and the consumer build, each test bounded.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake --preset asan >/dev/null
cmake --build --preset asan
ctest --preset asan -j2 -LE "differential|consumer" --timeout 600 "$@"

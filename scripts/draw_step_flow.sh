#!/usr/bin/env bash
# Renders docs/step_flow.dot (a step's data flow) to docs/step_flow.svg with
# Graphviz (Debian's graphviz package). The SVG is committed, so neither the
# build nor CI needs Graphviz: run this after editing the .dot file.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v dot >/dev/null; then
  echo "draw_step_flow.sh: 'dot' not found; install Debian's graphviz package" >&2
  exit 2
fi
dot -Tsvg docs/step_flow.dot -o docs/step_flow.svg

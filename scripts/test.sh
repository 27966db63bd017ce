#!/usr/bin/env bash
# Every test: Python (generator, compiled models, physics, the binary) and
# the C runtime's own tests (ctest, run from test_runtime_c.py).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
python -m pytest -q tests "$@"

#!/usr/bin/env bash
# Every test: Python (generator, compiled models, physics, the binary) and
# the C runtime's own tests (ctest, run from test_runtime_c.py).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
# On pytest-xdist workers, one per core up to 4 (EOMGEN_TEST_JOBS overrides;
# 0 runs in this process). Each test file stays on one worker, so its module
# fixtures are built once. On 2 cores: 15 min instead of 23 from an empty cache.
jobs="${EOMGEN_TEST_JOBS:-$(n=$(nproc 2>/dev/null || echo 2); echo $(( n < 4 ? n : 4 )))}"
python -m pytest -q -n "$jobs" --dist loadfile tests "$@"

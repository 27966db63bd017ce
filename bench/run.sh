#!/usr/bin/env bash
# Side-by-side benchmark of eomgen, PyDy (Cython) and CasADi (issue 7).
#
#   bash bench/run.sh            # the full run (n = 1..10, then 12, 16, 20 within budget)
#   bash bench/run.sh --quick    # a ~2-minute subset (n = 1, 2, 4)
#   bash bench/run.sh --max-seconds 120 --json /tmp/r.json
#
# Creates bench/.venv (or uses $EOMGEN_BENCH_VENV), installs pydy, casadi,
# cython, scipy and eomgen (editable, from this checkout) into it, then runs
# bench/bench_peers.py with the arguments given. Needs python3 (with venv)
# and gcc.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/.." && pwd)"
VENV="${EOMGEN_BENCH_VENV:-$HERE/.venv}"
PY="${PYTHON:-python3}"

if [ ! -x "$VENV/bin/python" ]; then
    echo "creating $VENV" >&2
    "$PY" -m venv "$VENV"
fi
if ! (cd / && "$VENV/bin/python" -c "import pydy, casadi, Cython, scipy, gen") >/dev/null 2>&1; then
    echo "installing pydy, casadi, cython, scipy and eomgen into $VENV" >&2
    "$VENV/bin/python" -m pip install -q --upgrade pip
    "$VENV/bin/python" -m pip install -q pydy casadi cython scipy setuptools
    "$VENV/bin/python" -m pip install -q -e "$ROOT"
fi
command -v gcc >/dev/null || { echo "bench/run.sh: gcc is needed" >&2; exit 2; }
exec "$VENV/bin/python" "$HERE/bench_peers.py" "$@"

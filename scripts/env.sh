# Source me: creates .venv (if missing) and installs eomgen with its test
# and documentation dependencies into it. Needs python3 (3.9+), a C compiler and cmake.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${EOMGEN_VENV:-$ROOT/.venv}"
if [ ! -x "$VENV/bin/python" ]; then
    python3 -m venv "$VENV"
fi
# quiet, idempotent install (editable: the checkout is the package)
if ! "$VENV/bin/python" -c "import gen, scipy, pytest, xdist, sympy, cffi, jinja2, matplotlib, hypothesis, fmpy, distributed, tqdm, pyarrow, pandas, sphinx, sphinx_gallery, myst_parser, furo" 2>/dev/null \
   || [ "$ROOT/pyproject.toml" -nt "$VENV/.eomgen-installed" ]; then
    "$VENV/bin/python" -m pip install -q --upgrade pip
    "$VENV/bin/python" -m pip install -q -e "$ROOT[test,docs]"
    touch "$VENV/.eomgen-installed"
fi
export PATH="$VENV/bin:$PATH"

# Source me: creates .venv (if missing) and installs eomgen with its test
# and documentation dependencies into it. Needs python3 (3.9+), a C compiler and cmake.
#
# This file is sourced into the user's shell, so it changes no shell option
# (no `set -e`, `set -u` or `pipefail`: those would stay on in an interactive
# terminal and close it at the next failing command). Each step checks its own
# status instead; on failure it prints one line and the source returns 1.
# Its one lasting effect is PATH (the helper function is unset after use).
_eomgen_env() {
    local root venv
    root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)" || return 1
    venv="${EOMGEN_VENV:-$root/.venv}"
    if [ ! -x "$venv/bin/python" ]; then
        python3 -m venv "$venv" || { echo "env.sh: could not create the venv $venv" >&2; return 1; }
    fi
    # quiet, idempotent install (editable: the checkout is the package); opty
    # (the peer of gen.OptimalControl) after cyipopt-wheels, without its
    # dependencies: its cyipopt requirement is a source build that needs IPOPT
    if ! "$venv/bin/python" -c "import gen, cyipopt, opty, scipy, pytest, xdist, sympy, cffi, jinja2, matplotlib, hypothesis, fmpy, distributed, tqdm, pyarrow, pandas, sphinx, sphinx_gallery, myst_parser, furo" 2>/dev/null \
       || [ "$root/pyproject.toml" -nt "$venv/.eomgen-installed" ]; then
        { "$venv/bin/python" -m pip install -q --upgrade pip \
          && "$venv/bin/python" -m pip install -q -e "$root[test,docs]" \
          && "$venv/bin/python" -m pip install -q --no-deps "opty==1.5.0" \
          && touch "$venv/.eomgen-installed"; } \
          || { echo "env.sh: installing eomgen into $venv failed" >&2; return 1; }
    fi
    export PATH="$venv/bin:$PATH"
}
# the status of sourcing is the status of the last command: 0, or 1 on failure
if _eomgen_env; then unset -f _eomgen_env; else unset -f _eomgen_env; false; fi

#!/usr/bin/env bash
# The main job: install, generate the seed pendulum (Kane and Lagrange),
# compile it, build the standalone binary, simulate, print A.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
python examples/pendulum_nonmin.py --out out/pendulum "$@"

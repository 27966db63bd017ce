#!/usr/bin/env bash
# Build the documentation site into docs/_build/html, warnings as errors.
# Every tutorial (docs/tutorials/*.py) runs during the build and checks its
# numbers against its reference; a failed check fails the build.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/env.sh
python -m sphinx -W --keep-going -b html docs docs/_build/html "$@"
echo "open docs/_build/html/index.html"

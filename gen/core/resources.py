"""Where the templates and the C runtime live: inside the installed
package (gen/templates, gen/csrc in a wheel) or beside it in a checkout."""
from __future__ import annotations

from pathlib import Path

# the package folder (gen/): core/ is one below it
_HERE = Path(__file__).resolve().parent.parent


def _find(name):
    for cand in (_HERE / name, _HERE.parent / name):
        if cand.is_dir():
            return cand
    raise FileNotFoundError(
        f"eomgen cannot find its '{name}' directory (looked in {_HERE / name} and "
        f"{_HERE.parent / name}); reinstall the package")


def templates_dir() -> Path:
    return _find("templates")


def csrc_dir() -> Path:
    return _find("csrc")

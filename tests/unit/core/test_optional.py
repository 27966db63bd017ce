"""The optional dependencies (gen/core/optional.py): each in one extra of
pyproject.toml, and a missing one names the feature, the package and the
extra."""
import re
import sys
from pathlib import Path

import pytest

import gen
from gen.core.optional import EXTRAS, require

ROOT = Path(__file__).resolve().parents[3]


def test_every_optional_import_is_in_its_extra():
    tomllib = pytest.importorskip("tomllib", reason="tomllib needs Python 3.11")
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]
    for name, (extra, package) in EXTRAS.items():
        names = [re.split(r"[<>=~!;]", d)[0].strip() for d in extras[extra]]
        assert package in names, (name, extra, extras[extra])


def test_a_missing_dependency_names_the_feature_the_package_and_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "cyipopt", None)       # import cyipopt -> ImportError
    with pytest.raises(gen.MissingDependencyError,
                       match=r"^gen.OptimalControl needs cyipopt-wheels, which is not installed: "
                             r"pip install eomgen\[ocp\] \(or pip install cyipopt-wheels\)$") as e:
        require("cyipopt", "gen.OptimalControl")
    assert isinstance(e.value, ImportError)
    with pytest.raises(KeyError, match="numpy is not an optional dependency"):
        require("numpy", "x")

"""Every code block of the topic guides (docs/guides/*.md) runs.

The rules a guide follows (tests/docs/test_guides.py reads them):

- A fenced block tagged ``python`` runs. The blocks of one guide run in order in one
  namespace (a later block uses what an earlier one made), in a temporary folder, with the
  checkout on ``sys.path`` (``import examples.seed_pendulum`` works).
- A block in another language (``sh``, ``c``, ``cpp``, ``text``) is not Python and is not
  run; every block names its language.
- ``<!-- guide: not run (why) -->`` on the line before a ``python`` block shows it without
  running it; the reason is part of the marker.
- ``<!-- guide: setup`` ... ``-->`` holds Python that runs before the guide's first block
  without being shown: the context a guide's text assumes (a model, a gain).

The fast tier parses every block and checks the markers; running a guide compiles its
models (the C++ and FMU guides and the large ensembles are in the slow tier).
"""
import ast
import os
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
GUIDES = ROOT / "docs" / "guides"
FENCE = re.compile(r"^```(\S*)[^\n]*\n(.*?)^```\s*$", re.S | re.M)
NOT_RUN = re.compile(r"<!--\s*guide:\s*not run\s*\((.+?)\)\s*-->\s*$")
SETUP = re.compile(r"<!--\s*guide:\s*setup\s*\n(.*?)-->", re.S)
LANGUAGES = {"python", "sh", "c", "cpp", "text"}

# guides whose blocks take long to run (a C++ compile, an FMU build, 10^4 runs)
SLOW = {"eigen.md", "fmu.md", "ensembles.md", "verification.md", "estimation.md",
        "robots.md"}


def blocks(path):
    """[(language, code, line, run)] of a guide's fenced blocks."""
    text = path.read_text()
    out = []
    for m in FENCE.finditer(text):
        line = text[:m.start()].count("\n") + 1
        before = text[:m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        run = m.group(1) == "python" and not NOT_RUN.search(before)
        out.append((m.group(1), m.group(2), line, run))
    return out


def setup_code(path):
    return "\n".join(m.group(1) for m in SETUP.finditer(path.read_text()))


def guides():
    return sorted(GUIDES.glob("*.md"))


def test_every_block_names_its_language_and_python_parses():
    """The rules above hold: a language on every fence, Python that parses,
    and at least the API guide's blocks run (not all marked away)."""
    seen = 0
    for path in guides():
        for lang, code, line, run in blocks(path):
            where = f"{path.name}:{line}"
            assert lang in LANGUAGES, f"{where}: a fence without a known language ({lang!r})"
            if lang == "python":
                ast.parse(code, filename=where)
                seen += run
        ast.parse(setup_code(path), filename=f"{path.name} (setup)")
    assert seen >= 15, seen
    api = [b for b in blocks(GUIDES / "python_api.md") if b[3]]
    assert len(api) >= 8 and all(b[0] == "python" for b in api)


def test_the_markers_are_read():
    """A marked block is not run; the next one is; a setup comment is code."""
    import tempfile
    text = ("# t\n\n<!-- guide: setup\nx = 1\n-->\n\n<!-- guide: not run (needs a board) -->\n"
            "```python\nraise SystemExit\n```\n\n```python\ny = x + 1\n```\n\n```sh\nls\n```\n")
    with tempfile.TemporaryDirectory() as d:
        p = Path(d) / "g.md"
        p.write_text(text)
        got = [(b[0], b[3]) for b in blocks(p)]
        assert got == [("python", False), ("python", True), ("sh", False)]
        ns = run_guide(p, Path(d))
        assert ns["y"] == 2


def run_guide(path, cwd):
    """Run a guide's setup and blocks in one namespace, in cwd; returns it."""
    ns = {"__name__": f"guide_{path.stem}"}
    old = os.getcwd()
    sys.path.insert(0, str(ROOT))
    os.chdir(cwd)
    try:
        setup = setup_code(path)
        if setup.strip():
            exec(compile(setup, f"{path.name} (setup)", "exec"), ns)
        for lang, code, line, run in blocks(path):
            if not run:
                continue
            # line numbers in tracebacks are the guide's
            exec(compile("\n" * line + code, str(path), "exec"), ns)
    finally:
        os.chdir(old)
        sys.path.remove(str(ROOT))
    return ns


def _cases():
    out = []
    for path in guides():
        if not any(b[3] for b in blocks(path)):
            continue
        marks = [pytest.mark.slow] if path.name in SLOW else []
        out.append(pytest.param(path.name, id=path.stem, marks=marks))
    return out


@pytest.mark.parametrize("name", _cases())
def test_guide_runs(name, tmp_path, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    run_guide(GUIDES / name, tmp_path)

"""Golden files of the generated sources: the seed Kane pendulum
(examples/seed_pendulum.py kane_model()) rendered for the C backend (double)
and for the Eigen backend, every generated file compared character for
character with tests/golden/sources/c/<file> and tests/golden/sources/eigen/<file>.
The Eigen backend's C files are checked to be the C backend's own (for the
other scalar type: what the C backend renders for it), so only its face and
project are golden files of their own. Nothing is compiled.

A failure means the generated code changed. If the change is intended,
regenerate the golden files and review them with `git diff tests/golden/sources`:

    EOMGEN_UPDATE_GOLDEN=1 python -m pytest tests/golden/test_golden_sources.py

With EOMGEN_UPDATE_GOLDEN=1 the test rewrites the folder of each backend
(files no longer generated are removed) instead of comparing, passes, and
says so in a warning.
"""
import difflib
import os
import warnings
from pathlib import Path

import pytest

import gen.codegen.backends
import gen.toolchain.host
import gen.plan.ir
import gen.codegen.render

GOLDEN = Path(__file__).resolve().parents[1] / "golden" / "sources"
UPDATE = os.environ.get("EOMGEN_UPDATE_GOLDEN", "") not in ("", "0")
MAX_DIFF_LINES = 60
HOW_TO_UPDATE = ("if the change is intended: EOMGEN_UPDATE_GOLDEN=1 python -m pytest "
                 "tests/golden/test_golden_sources.py, then review git diff tests/golden/sources")


# the runtime's files are copied into the project verbatim (csrc/ has its own
# tests): the golden files are what the templates produce
RUNTIME_COPIES = {Path(f).name for f in (gen.codegen.backends.RUNTIME_SOURCES + gen.codegen.backends.RUNTIME_HEADERS
                                         + gen.codegen.backends.EIGEN_RUNTIME_HEADERS
                                         + gen.codegen.backends.RUNTIME_MAIN)}


def render(model, backend, real="double"):
    """{file name: text} of the files the templates render for a model (with
    the C backend: the stand-ins of the derivative kernels that gen.compile
    links before they are built, and the Python host module's declarations
    and source, gen/toolchain/host.py)."""
    out = gen.codegen.render.render(gen.plan.ir.plan(model), real=real, backend=backend)
    files = {k: v for k, v in out.files.items() if k not in RUNTIME_COPIES}
    # the runtime's structs and codes: the csrc/ copy (tests/unit/codegen/test_abi.py keeps
    # that copy current), not a golden file of its own
    from gen.core.resources import csrc_file
    assert files.pop("gen_rt_abi.h") == csrc_file("gen_rt_abi.h").read_text(), \
        "the model's gen_rt_abi.h is not the runtime's csrc/gen_rt_abi.h"
    if backend == "c":
        core = gen.plan.ir.plan(model, derivatives=False)
        files.update(gen.codegen.render.render(core, real=real, backend=backend, project=False,
                                       only={"stub"}).files)
        files["host/host.h"], files["host/host.c"] = gen.toolchain.host.host_sources(real,
                                                                            hand_written=False)
    return files


def eigen_split(model, files):
    """The Eigen backend's files, split: (its own: the face and its project,
    compared with the golden files; {file: reason} of the failures of the
    rest). The rest is the C backend's files, which must be the C backend's
    own to the byte (the same files, so the same bits), and the C model
    again for the other scalar type under the prefixed name, which must be
    what the C backend renders for that type and name."""
    import copy
    import dataclasses
    import gen.codegen.backends.eigen
    plan = gen.plan.ir.plan(model)
    c_files = gen.codegen.render.render(plan, real="double", backend="c").files
    alt = gen.codegen.backends.eigen.alt_name(model.name, "double")
    alt_model = copy.copy(model)
    alt_model.name = alt
    alt_files = gen.codegen.render.render(dataclasses.replace(plan, model=alt_model), real="float",
                                  backend="c", project=False).files
    own, bad = {}, {}
    for name, text in files.items():
        if name.startswith(alt) and name in alt_files and name != "gen_rt_config.h":
            if text != alt_files[name]:
                bad[name] = "differs from the C backend's file for float"
        elif name in c_files and name not in ("gen_rt_config.h", "CMakeLists.txt"):
            if text != c_files[name]:
                bad[name] = "differs from the C backend's file"
        else:
            own[name] = text
    return own, bad


def _read(folder):
    return {p.relative_to(folder).as_posix(): p.read_text(encoding="utf-8")
            for p in sorted(folder.rglob("*")) if p.is_file()}


def _update(folder, files):
    folder.mkdir(parents=True, exist_ok=True)
    for name in _read(folder):
        if name not in files:
            (folder / name).unlink()
    for name, text in files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(path, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(text)


def _diff(name, golden, now):
    lines = list(difflib.unified_diff(golden.splitlines(keepends=True),
                                      now.splitlines(keepends=True),
                                      fromfile=f"golden/{name}", tofile=f"generated/{name}"))
    more = len(lines) - MAX_DIFF_LINES
    text = "".join(line if line.endswith("\n") else line + "\n"
                   for line in lines[:MAX_DIFF_LINES])
    if more > 0:
        text += f"... ({more} more diff lines)\n"
    return text


@pytest.mark.parametrize("backend", ["c", "eigen"])
def test_generated_sources_match_golden(kane_model, backend):
    files = render(kane_model, backend)
    if backend == "eigen":
        files, bad = eigen_split(kane_model, files)
        assert not bad, f"the Eigen backend's C files are not the C backend's: {bad}"
    folder = GOLDEN / backend
    if UPDATE:
        _update(folder, files)
        msg = f"EOMGEN_UPDATE_GOLDEN: rewrote {len(files)} golden files in {folder}"
        print(msg)
        warnings.warn(msg)
        return
    assert folder.is_dir(), f"no golden files in {folder}; {HOW_TO_UPDATE}"
    golden = _read(folder)
    missing = sorted(set(golden) - set(files))
    extra = sorted(set(files) - set(golden))
    changed = [n for n in sorted(set(golden) & set(files)) if golden[n] != files[n]]
    if not (missing or extra or changed):
        return
    report = [f"generated sources of the seed Kane pendulum ({backend} backend) differ "
              f"from {folder}:"]
    if missing:
        report.append(f"  no longer generated: {', '.join(missing)}")
    if extra:
        report.append(f"  new files: {', '.join(extra)}")
    if changed:
        report.append(f"  changed: {', '.join(changed)}")
        report.append(f"first difference ({changed[0]}):")
        report.append(_diff(changed[0], golden[changed[0]], files[changed[0]]))
    report.append(HOW_TO_UPDATE)
    pytest.fail("\n".join(report), pytrace=False)

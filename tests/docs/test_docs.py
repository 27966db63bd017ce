"""The documentation: every public Python name has a numpy-style docstring
with its parameters, returns and raises, and appears in the API reference
(fast tier); the site builds with warnings as errors, every tutorial run and
its numbers checked (slow); the README's 20-line example is the one the site
shows, and it runs (slow: it compiles a model)."""
import ast
import dataclasses
import inspect
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import gen
from gen.sim.simulator import Simulator

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"

# classes that users receive rather than construct: their docstring describes
# them, and their constructor's parameters are not part of the API
RECEIVED = {
    "Model": "built by Model.from_kanes / from_lagrange / from_system",
    "VerifyReport": "returned by gen.verify",
    "EnsembleResult": "returned by Simulator.ensemble",
    "Simulator": "returned by gen.compile",
    "Solution": "returned by Simulator.simulate",
}


def public_objects():
    """(qualified name, object, kind) of gen.__all__, gen.sim.simulator.Simulator
    and the public methods and properties of the public classes."""
    out = []
    classes = []
    for name in gen.__all__:
        if name == "__version__":
            continue
        obj = getattr(gen, name)
        out.append((name, obj, "class" if inspect.isclass(obj) else "function"))
        if inspect.isclass(obj):
            classes.append((name, obj))
    out.append(("Simulator", Simulator, "class"))
    classes.append(("Simulator", Simulator))
    for cname, cls in classes:
        for mname, member in vars(cls).items():
            if mname.startswith("_"):
                continue
            if isinstance(member, property):
                out.append((f"{cname}.{mname}", member.fget, "property"))
            elif isinstance(member, (staticmethod, classmethod)):
                out.append((f"{cname}.{mname}", member.__func__, "method"))
            elif inspect.isfunction(member):
                out.append((f"{cname}.{mname}", member, "method"))
    return out


def _sections(doc):
    """{section title: body} of a numpy-style docstring."""
    lines = doc.splitlines()
    found = {}
    current = None
    for i, line in enumerate(lines):
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if line.strip() and re.fullmatch(r"-{3,}", nxt.strip()) and \
                len(nxt.strip()) >= len(line.strip()):
            current = line.strip()
            found[current] = []
            continue
        if current is not None and not re.fullmatch(r"-{3,}", line.strip()):
            found[current].append(line)
    return {k: "\n".join(v) for k, v in found.items()}


def _params(func, skip_first):
    sig = inspect.signature(func)
    names = []
    for i, (name, par) in enumerate(sig.parameters.items()):
        if skip_first and i == 0:
            continue
        names.append(name)
    return names


def _body_nodes(func):
    """The AST nodes of func's own body (not of functions nested in it)."""
    try:
        src = textwrap.dedent(inspect.getsource(func))
    except (OSError, TypeError):
        return []
    tree = ast.parse(src).body[0]
    nodes, todo = [], list(ast.iter_child_nodes(tree))
    while todo:
        n = todo.pop()
        if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
            continue
        nodes.append(n)
        todo.extend(ast.iter_child_nodes(n))
    return nodes


def _returns_value(func):
    return any(isinstance(n, ast.Return) and n.value is not None
               and not (isinstance(n.value, ast.Constant) and n.value.value is None)
               for n in _body_nodes(func))


def _raises(func):
    return any(isinstance(n, ast.Raise) and n.exc is not None for n in _body_nodes(func))


def _own_init(cls):
    init = vars(cls).get("__init__")
    if init is None:
        return None
    if dataclasses.is_dataclass(cls) and init.__code__.co_filename == "<string>":
        return init          # generated: its fields are the parameters
    return init


def docstring_problems(qualname, obj, kind):
    """What is missing in obj's docstring, as a list of strings."""
    doc = inspect.getdoc(obj) if kind != "property" else obj.__doc__
    if not doc or not doc.strip():
        return ["no docstring"]
    doc = inspect.cleandoc(doc)
    problems = []
    sec = _sections(doc)
    if kind == "property":
        return problems
    if kind == "class":
        init = _own_init(obj)
        short = qualname.split(".")[-1]
        if init is None or short in RECEIVED or issubclass(obj, Warning):
            return problems
        params = _params(init, skip_first=True)
        func = init
    else:
        params = _params(obj, skip_first=kind == "method"
                         and next(iter(inspect.signature(obj).parameters), "") in ("self", "cls"))
        func = obj
    if params:
        body = sec.get("Parameters")
        if body is None:
            problems.append("no Parameters section")
        else:
            listed = set()
            for line in body.splitlines():
                m = re.match(r"^(\S[^:]*?)\s*:", line) or re.match(r"^(\*{0,2}\w+(?:,\s*\*{0,2}\w+)*)\s*$", line)
                if m and not line.startswith(" "):
                    listed |= {n.strip().lstrip("*") for n in m.group(1).split(",")}
            missing = [p for p in params if p not in listed]
            if missing:
                problems.append(f"parameters not in its Parameters section: {missing}")
    if kind != "class" and _returns_value(func) and "Returns" not in sec and "Yields" not in sec:
        problems.append("returns a value but has no Returns section")
    if _raises(func) and "Raises" not in sec:
        problems.append("raises but has no Raises section")
    return problems


def test_every_public_name_has_a_numpy_docstring():
    names = public_objects()
    assert len(names) > 60, "the list of public names is complete"
    bad = {q: p for q, o, k in names for p in [docstring_problems(q, o, k)] if p}
    assert not bad, "\n".join(f"{q}: {'; '.join(p)}" for q, p in sorted(bad.items()))


def test_the_docstring_check_catches_what_it_should():
    """The check is not vacuous: it flags a missing docstring, a missing
    Parameters section, an undocumented parameter, a return value or a raise
    without their sections, and passes a complete one."""
    def bare(x):
        return x

    def partial(x, y):
        """Do it.

        Parameters
        ----------
        x : float
            The x.
        """
        if x:
            raise ValueError("no")

    def complete(x, *, y=1):
        """Do it.

        Parameters
        ----------
        x, y : float
            The numbers.

        Returns
        -------
        float
            Their sum.

        Raises
        ------
        ValueError
            When x is zero.
        """
        if not x:
            raise ValueError("zero")
        return x + y

    assert docstring_problems("bare", bare, "function") == ["no docstring"]
    got = docstring_problems("partial", partial, "function")
    assert got == ["parameters not in its Parameters section: ['y']",
                   "raises but has no Raises section"], got
    assert docstring_problems("complete", complete, "function") == []


def _reference_entries():
    """{documented name: members} from the autodoc directives of the API
    reference (members None: all of them)."""
    text = (DOCS / "api" / "python.rst").read_text()
    out = {}
    for m in re.finditer(r"^\.\. auto(?:class|function|exception):: (\S+)\n((?:   .*\n|\s*\n)*)",
                         text, re.M):
        opts = m.group(2)
        members = None
        mm = re.search(r":members:(.*(?:\n {13,}.*)*)", opts)
        if mm is not None and mm.group(1).strip():
            members = {s.strip() for s in mm.group(1).replace("\n", " ").split(",") if s.strip()}
        out[m.group(1)] = members if mm is not None else set()
    return out


def test_every_public_name_is_in_the_api_reference():
    ref = _reference_entries()
    missing = []
    for qual, obj, kind in public_objects():
        if "." not in qual:
            key = "gen.sim.simulator.Simulator" if qual == "Simulator" else f"gen.{qual}"
            if key not in ref:
                missing.append(qual)
        else:
            cname, mname = qual.split(".", 1)
            key = "gen.sim.simulator.Simulator" if cname == "Simulator" else f"gen.{cname}"
            members = ref.get(key, set())
            if members is not None and mname not in members:
                missing.append(qual)
    assert not missing, f"not in docs/api/python.rst: {missing}"


# ------------------------------------------------------------ the README
def _readme_example():
    text = (ROOT / "README.md").read_text()
    block = text.split("<!-- example:begin -->", 1)[1].split("<!-- example:end -->", 1)[0]
    return block.split("```python\n", 1)[1].split("```", 1)[0]


def test_readme_example_is_the_documented_one_and_runs(tmp_path, monkeypatch):
    """The README's 20-line example is docs/snippets/first_model.py (the
    getting-started page includes that file), and it runs: the pendulum's
    linearization at rest is [[0, 1], [-g/l, 0]], B = [0, 1/(m l^2)], and
    the RK4 run from 0.1 rad keeps its energy."""
    code = _readme_example()
    assert code == (DOCS / "snippets" / "first_model.py").read_text()
    assert len(code.strip().splitlines()) <= 20
    monkeypatch.chdir(tmp_path)
    ns = {"__name__": "readme_example"}
    exec(compile(code, "README.md", "exec"), ns)
    g, l, m = 9.81, 0.5, 1.0
    assert np.allclose(ns["A_lin"], [[0, 1], [-g / l, 0]], rtol=0, atol=1e-12)
    assert np.allclose(ns["B_lin"], [[0], [1 / (m * l**2)]], rtol=0, atol=1e-12)
    t, X = ns["t"], ns["X"]
    assert X.shape == (len(t), 2) and t[-1] == pytest.approx(10.0)
    energy = 0.5 * m * l**2 * X[:, 1] ** 2 - m * g * l * np.cos(X[:, 0])
    assert np.ptp(energy) < 1e-9 * abs(energy[0])


# ------------------------------------------------------------ the site
@pytest.mark.slow
def test_site_builds_without_warnings_and_runs_every_tutorial(tmp_path):
    """sphinx-build -W --keep-going: every page, the API reference, the C
    API from gen/codegen/abi.py, and every tutorial executed (their assertions check
    their numbers); then the built pages hold what they should."""
    pytest.importorskip("sphinx_gallery")
    out = tmp_path / "html"
    env = dict(os.environ, MPLBACKEND="Agg")
    # run_stale_examples: every tutorial runs, even when sphinx-gallery's
    # record in docs/auto_tutorials says it has not changed since the last build
    p = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-b", "html",
                        "-D", "sphinx_gallery_conf.run_stale_examples=True",
                        "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
                       capture_output=True, text=True, env=env, cwd=ROOT)
    assert p.returncode == 0, p.stdout[-4000:] + p.stderr[-8000:]
    assert "build succeeded" in p.stdout
    tutorials = sorted((DOCS / "tutorials").glob("plot_*.py"))
    assert len(tutorials) >= 5
    for script in tutorials:
        page = out / "auto_tutorials" / f"{script.stem}.html"
        assert page.is_file(), page
        html = page.read_text()
        assert "sphx-glr-single-img" in html or "sphx-glr-multi-img" in html, \
            f"{script.name} produced no figure"
    api = (out / "api" / "python.html").read_text()
    for name in ("Simulator.simulate", "Model.from_kanes", "export_fmu", "LinearFeedback"):
        assert name.split(".")[-1] in api
    c_api = (out / "api" / "c.html").read_text()
    from gen.codegen import abi
    for fn in abi.FUNCTIONS:
        assert f"pendulum_kane_{fn.verb}" in c_api, fn.verb
    for s in abi.STATUSES:
        assert f"PENDULUM_KANE_{s.name}" in c_api, s.name

"""The house's plan, measured against the tree (issue 42): gen/ is packages
by stage, each importing only the packages below it, no module taking
another's underscore name."""
import ast
from pathlib import Path

import gen

GEN = Path(gen.__file__).resolve().parent

# the stages, bottom up: a package imports only its own modules and those of
# packages before it (export and design are one floor: the products)
FLOORS = [("core",), ("sym",), ("intake",), ("plan",), ("codegen",), ("toolchain",), ("sim",),
          ("pipeline",), ("export", "design"), ("cli",)]
TOP = {"__init__.py", "__main__.py", "_version.py", "pipeline.py"}


def _floor(module):
    head = module.split(".")[0]
    if head == "_version":
        return -1
    return next(i for i, names in enumerate(FLOORS) if head in names)


def _modules():
    """{dotted module under gen: path}."""
    out = {}
    for p in sorted(GEN.rglob("*.py")):
        parts = list(p.relative_to(GEN).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


def _imports(module, path):
    """[(imported module under gen, [names])] of path, relative imports
    resolved, at any depth."""
    parts = module.split(".") if module else []
    pkg = parts if path.name == "__init__.py" else parts[:-1]
    out = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = pkg[:len(pkg) - (node.level - 1)]
            target = ".".join(base + ([node.module] if node.module else []))
            out.append((target, [a.name for a in node.names]))
        elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("gen."):
            out.append((node.module[4:], [a.name for a in node.names]))
    return out


def test_top_level_holds_only_the_package_the_version_and_the_pipeline():
    assert {p.name for p in GEN.glob("*.py")} == TOP
    for folder in [d for d in GEN.rglob("*") if d.is_dir() and d.name != "__pycache__"]:
        modules = [p for p in folder.glob("*.py") if p.name != "__init__.py"]
        assert len(modules) <= 12, f"{folder.relative_to(GEN)} holds {len(modules)} modules"


def test_packages_import_only_packages_below_them():
    bad = []
    for module, path in _modules().items():
        if not module or module == "__main__":
            continue
        mine = _floor(module)
        for target, names in _imports(module, path):
            if not target:          # `from .. import x` at the top: x's package
                target = names[0]
            if target.split(".")[0] == module.split(".")[0]:
                continue
            if _floor(target) >= mine:
                bad.append(f"gen.{module} imports gen.{target}")
    assert bad == []


def test_no_module_takes_another_modules_underscore_name():
    private = [(m, t, n) for m, p in _modules().items() for t, names in _imports(m, p)
               for n in names if n.startswith("_") and t != "_version"]
    assert private == []


# ---------------------------------------------------------- small rooms
MAX_MODULE_LINES = 900
MAX_FUNCTION_LINES = 100     # def to its last line, docstring included
MAX_TEMPLATE_LINES = 300
TEMPLATES = GEN.parent / "templates" if (GEN.parent / "templates").is_dir() else GEN / "templates"


def _functions(tree):
    return [n for n in ast.walk(tree) if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]


def test_no_module_over_900_lines_and_no_function_over_100():
    long_modules, long_functions = [], []
    for module, path in _modules().items():
        text = path.read_text()
        n = len(text.splitlines())
        if n > MAX_MODULE_LINES:
            long_modules.append(f"gen/{path.relative_to(GEN)}: {n} lines")
        for f in _functions(ast.parse(text)):
            length = f.end_lineno - f.lineno + 1
            if length > MAX_FUNCTION_LINES:
                long_functions.append(f"gen/{path.relative_to(GEN)}:{f.lineno} {f.name}: {length}")
    assert long_modules == [] and long_functions == []


def test_no_template_over_300_lines():
    long = [f"{p.relative_to(TEMPLATES)}: {n}" for p in sorted(TEMPLATES.rglob("*.j2"))
            for n in [len(p.read_text().splitlines())] if n > MAX_TEMPLATE_LINES]
    assert long == []


def test_only_the_toolchain_opens_libraries_and_builds():
    words = ("ffi.dlopen", "cffi.FFI(", "ctypes.CDLL", "build_plain")
    bad = [f"gen/{p.relative_to(GEN)}: {w}" for p in _modules().values()
           if "toolchain" not in p.relative_to(GEN).parts
           for w in words if w in p.read_text()]
    assert bad == []


# ------------------------------------------- no process-wide mutable state
_MUTATORS = {"append", "extend", "add", "update", "setdefault", "pop", "popitem", "clear",
             "remove", "insert", "discard", "__setitem__", "__delitem__"}


def _module_containers(tree):
    """Names bound at module level to a mutable container (a dict, list or
    set display or call, a defaultdict, an OrderedDict)."""
    out = set()
    for node in tree.body:
        targets, value = [], None
        if isinstance(node, ast.Assign):
            targets, value = node.targets, node.value
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            targets, value = [node.target], node.value
        mutable = isinstance(value, (ast.Dict, ast.List, ast.Set, ast.DictComp, ast.ListComp,
                                     ast.SetComp)) or (
            isinstance(value, ast.Call) and isinstance(value.func, (ast.Name, ast.Attribute))
            and (getattr(value.func, "id", None) or getattr(value.func, "attr", None))
            in ("dict", "list", "set", "defaultdict", "OrderedDict", "WeakValueDictionary",
                "WeakKeyDictionary"))
        if mutable:
            out |= {t.id for t in targets if isinstance(t, ast.Name)}
    return out


def _locked(stack):
    """Whether a node's enclosing nodes hold a `with <...lock...>:`."""
    for node in stack:
        if isinstance(node, (ast.With, ast.AsyncWith)):
            for item in node.items:
                if "lock" in ast.unparse(item.context_expr).lower():
                    return True
    return False


def _mutations(tree, names):
    """(line, name) of every change of a module-level container inside a
    function that is not under a lock."""
    found = []

    def visit(node, stack, in_function, shadowed):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            args = {a.arg for a in ast.walk(node.args) if isinstance(a, ast.arg)} \
                if not isinstance(node, ast.Lambda) else {a.arg for a in node.args.args}
            local = set()
            if not isinstance(node, ast.Lambda):
                glob = {n for s in ast.walk(node) if isinstance(s, ast.Global) for n in s.names}
                local = {t.id for s in ast.walk(node) if isinstance(s, (ast.Assign, ast.AnnAssign))
                         for t in (s.targets if isinstance(s, ast.Assign) else [s.target])
                         if isinstance(t, ast.Name)} - glob
            in_function, shadowed = True, shadowed | args | local
        target = None
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) \
                and node.func.attr in _MUTATORS and isinstance(node.func.value, ast.Name):
            target = node.func.value.id
        elif isinstance(node, (ast.Assign, ast.AugAssign, ast.Delete)):
            for t in (node.targets if isinstance(node, (ast.Assign, ast.Delete)) else [node.target]):
                if isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name):
                    target = t.value.id
        elif isinstance(node, ast.Global):
            hit = [n for n in node.names]
            if hit and not _locked(stack):
                found.extend((node.lineno, f"global {n}") for n in hit)
        if target in names and in_function and target not in shadowed and not _locked(stack):
            found.append((node.lineno, target))
        for child in ast.iter_child_nodes(node):
            visit(child, stack + [node], in_function, shadowed)

    visit(tree, [], False, frozenset())
    return found


def test_no_module_level_state_changed_outside_a_lock():
    bad = []
    for module, path in _modules().items():
        tree = ast.parse(path.read_text())
        for line, name in _mutations(tree, _module_containers(tree)):
            bad.append(f"gen/{path.relative_to(GEN)}:{line} {name}")
    assert bad == []


def test_no_import_circle_between_modules():
    """No circle of imports between gen's modules, at any depth (an import
    inside a function counts: it ties the modules as much as one at the
    top); `from pkg import name` names pkg's module, or pkg.name where that
    is a module."""
    modules = _modules()
    edges = {}
    for module, path in modules.items():
        targets = set()
        for target, names in _imports(module, path):
            for name in names:
                sub = f"{target}.{name}" if target else name
                targets.add(sub if sub in modules else target)
        edges[module] = sorted(t for t in targets if t in modules and t != module)
    circles, state = [], {}

    def visit(m, trail):
        state[m] = "open"
        for t in edges[m]:
            if state.get(t) == "open":
                circles.append(" -> ".join(trail[trail.index(t):] + [t]))
            elif t not in state:
                visit(t, trail + [t])
        state[m] = "done"

    for m in sorted(modules):
        if m not in state:
            visit(m, [m])
    assert circles == []

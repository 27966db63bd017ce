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

"""House rule 1: imports go one way (semkit, sim at the bottom; gbmgen on top), and inside a
package its modules import each other one way (no cycle, function-level imports included)."""
import ast
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
OURS = {"semkit", "sim", "gbmgen"}
ALLOWED = {"semkit": {"semkit"}, "sim": {"sim"}, "gbmgen": {"gbmgen", "semkit", "sim"}}


def _imports(path):
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name.split(".")[0]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            yield node.module.split(".")[0]


@pytest.mark.parametrize("pkg", sorted(ALLOWED))
def test_import_direction(pkg):
    bad = []
    for f in (ROOT / pkg).rglob("*.py"):
        for mod in _imports(f):
            if mod in OURS and mod not in ALLOWED[pkg]:
                bad.append(f"{f.relative_to(ROOT)} imports {mod}")
    assert not bad, "forbidden imports: " + "; ".join(bad)


def test_forbidden_import_is_detected(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("import os\nfrom gbmgen.table import x\n")
    assert "gbmgen" in set(_imports(f))


_NO_WORK = """
import importlib, pkgutil, sys
import numba.core.registry  # noqa: F401
from numba.core.dispatcher import Dispatcher
pkg = importlib.import_module("{pkg}")
assert "matplotlib" not in sys.modules, "importing {pkg} imported matplotlib"
for info in pkgutil.walk_packages(pkg.__path__, "{pkg}."):
    if not info.name.endswith("__main__"):
        importlib.import_module(info.name)
compiled = [f"{{name}}.{{k}}" for name, mod in list(sys.modules.items())
            if name.split(".")[0] == "{pkg}"
            for k, v in vars(mod).items() if isinstance(v, Dispatcher) and v.overloads]
dispatchers = [k for name, mod in list(sys.modules.items()) if name.split(".")[0] == "{pkg}"
               for k, v in vars(mod).items() if isinstance(v, Dispatcher)]
assert not compiled, "compiled at import: " + ", ".join(compiled)
print(len(dispatchers))
"""


@pytest.mark.parametrize("pkg", sorted(ALLOWED))
def test_import_does_no_work(pkg):
    """Importing every module of a package compiles no numba kernel and loads no matplotlib."""
    out = subprocess.run([sys.executable, "-c", _NO_WORK.format(pkg=pkg)], cwd=ROOT,
                         capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    if pkg in ("sim", "semkit", "gbmgen"):
        assert int(out.stdout.split()[-1]) > 0  # the check saw the package's kernels


def _module_name(path, root):
    rel = path.relative_to(root).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _import_edges(path, name, modules):
    """Modules of ``modules`` imported anywhere in ``path`` (function-level imports included)."""
    is_pkg = path.name == "__init__.py"
    here = name.split(".") if is_pkg else name.split(".")[:-1]

    def known(mod):  # the deepest known module a dotted name refers to
        parts = mod.split(".")
        for k in range(len(parts), 0, -1):
            m = ".".join(parts[:k])
            if m in modules:
                return m
        return None

    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = here[:len(here) - node.level + 1] if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in modules else mod
                       for a in node.names]
        else:
            continue
        for t in targets:
            m = known(t)
            if m is not None and m != name:
                yield m


def import_cycles(pkg_dir):
    """Import cycles among the modules of one package (strongly connected components)."""
    files = {_module_name(f, pkg_dir.parent): f for f in pkg_dir.rglob("*.py")}
    graph = {m: set(_import_edges(f, m, files)) for m, f in files.items()}
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):  # Tarjan
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


@pytest.mark.parametrize("pkg", sorted(ALLOWED))
def test_no_import_cycle_inside_a_package(pkg):
    """Modules of a package import each other one way (function-level imports count); only a
    package's ``__init__`` may resolve names lazily with a module ``__getattr__``."""
    cycles = import_cycles(ROOT / pkg)
    assert not cycles, "import cycles: " + "; ".join(" <-> ".join(c) for c in cycles)
    lazy = [str(f.relative_to(ROOT)) for f in (ROOT / pkg).rglob("*.py")
            if f.name != "__init__.py" and any(
                isinstance(n, ast.FunctionDef) and n.name == "__getattr__"
                for n in ast.parse(f.read_text()).body)]
    assert not lazy, "module __getattr__ outside a package __init__: " + ", ".join(lazy)


def test_import_cycle_is_detected(tmp_path):
    pkg = tmp_path / "p"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("from .b import x\n")
    (pkg / "a.py").write_text("def f():\n    from .sub import b\n")
    (pkg / "sub" / "b.py").write_text("from .. import a\nx = 1\n")
    (pkg / "c.py").write_text("from . import a\n")
    assert import_cycles(pkg) == [["p.a", "p.sub.b"]]

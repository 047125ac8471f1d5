"""House rule 1: imports go one way (semkit, sim at the bottom; gbmgen on top)."""
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


def _sim_imports(path):
    """Modules of ``sim`` that ``path`` imports (relative and absolute, any depth)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    pkg = path.relative_to(ROOT).with_suffix("").parts[:-1]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = list(pkg[:len(pkg) - node.level + 1]) if node.level else []
            mod = ".".join(base + ([node.module] if node.module else []))
            if mod.split(".")[0] == "sim":
                if node.module:         # from .x import y: module x (or x.y if a module)
                    yield mod
                for a in node.names:
                    yield f"{mod}.{a.name}"


def test_sim_modules_import_no_loop():
    """No import cycle among the modules of sim (measure <-> simulation was one)."""
    files = {".".join(f.relative_to(ROOT).with_suffix("").parts): f
             for f in (ROOT / "sim").rglob("*.py")}
    files = {k.removesuffix(".__init__"): v for k, v in files.items()}
    # the package itself (sim/__init__ re-exports) is not an edge of the module graph
    graph = {m: {d for d in _sim_imports(f) if d in files and d not in (m, "sim")}
             for m, f in files.items()}
    state = {}

    def visit(m, path):
        state[m] = 1
        for d in sorted(graph[m]):
            if state.get(d) == 1:
                raise AssertionError("import cycle: " + " -> ".join(path + [m, d]))
            if d not in state:
                visit(d, path + [m])
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m, [])

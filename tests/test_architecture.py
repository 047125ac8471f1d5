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


@pytest.mark.parametrize("pkg", sorted(ALLOWED))
def test_import_does_no_work(pkg):
    """Importing a package neither compiles numba kernels nor imports matplotlib."""
    code = (f"import sys, {pkg}; "
            "assert 'matplotlib' not in sys.modules, 'matplotlib imported'; "
            "import numba.core.registry as r; "
            "n = sum(len(d.overloads) for d in r.cpu_target.target_context._defns.values()) "
            "if hasattr(r.cpu_target.target_context, '_defns') else 0; print('ok')")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr

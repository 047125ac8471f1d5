"""sim picks numba's OpenMP layer, and says so when numba's threads started on another first."""
import subprocess
import sys

import pytest

SCRIPT = """
import os, warnings
os.environ.pop("NUMBA_THREADING_LAYER", None)
import numba
{before}
with warnings.catch_warnings(record=True) as w:
    warnings.simplefilter("always")
    import sim._jit
print([type(x.message).__name__ for x in w])
numba.set_num_threads(1)
print(numba.threading_layer())
"""


def _run(before):
    env = {k: v for k, v in __import__("os").environ.items() if k != "NUMBA_THREADING_LAYER"}
    out = subprocess.run([sys.executable, "-c", SCRIPT.format(before=before)], env=env,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-500:]
    return out.stdout.split("\n")[:2]


def test_sim_first_runs_on_openmp_without_a_warning():
    warned, layer = _run("")
    if layer != "omp":
        pytest.skip(f"OpenMP layer unavailable here ({layer})")
    assert warned == "[]"


def test_numba_threads_started_first_give_a_warning():
    warned, layer = _run("numba.set_num_threads(1)")
    if layer == "omp":
        pytest.skip("numba's default layer is OpenMP here: nothing to warn about")
    assert warned == "['ThreadingLayerWarning']"

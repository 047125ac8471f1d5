"""semkit's public API index: every name resolves, importing does no work."""
import subprocess
import sys

import semkit


def test_every_public_name_resolves():
    for name in semkit.__all__:
        assert getattr(semkit, name) is not None


def test_import_is_cheap():
    code = ("import sys, semkit; heavy = {'cv2', 'numba', 'matplotlib', 'skimage', 'scipy'}; "
            "print(sorted(heavy & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip() == "[]", out.stdout + out.stderr


def test_python_m_semkit_version():
    out = subprocess.run([sys.executable, "-m", "semkit", "--version"], capture_output=True,
                         text=True)
    assert out.returncode == 0 and out.stdout.startswith("semkit ")

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


def test_a_default_analysis_does_not_import_scipy_ndimage(tmp_path):
    """Every worker process of a folder run pays its imports once; scipy.ndimage costs about
    0.2 s of CPU and the default crack analysis (typing included) does not need it."""
    from semkit.io import write_image
    from semkit.synth import make_sem_image
    write_image(tmp_path / "a.png", make_sem_image((200, 260), stage="post", seed=3).image)
    code = ("import sys; from semkit.workflow import analyse_file; "
            f"r = analyse_file({str(tmp_path / 'a.png')!r}, manifest_row={{'stage': 'failure'}})"
            "; assert not r[0]['error'], r[0]['error']; "
            "print(sorted(m for m in sys.modules if m.startswith('scipy.ndimage')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip() == "[]", out.stdout + out.stderr


def test_python_m_semkit_version():
    out = subprocess.run([sys.executable, "-m", "semkit", "--version"], capture_output=True,
                         text=True)
    assert out.returncode == 0 and out.stdout.startswith("semkit ")

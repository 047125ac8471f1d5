"""Check: does a change of ``semkit`` keep the answers of ``semkit analyse``?

Runs ``semkit.workflow.analyse_folder`` (default options, crack masks saved) twice on the same
folder, once with this checkout's ``semkit`` and once with a reference source tree (e.g. the
``main`` branch: ``git archive main semkit | tar -x -C /tmp/ref``), each in its own process,
and compares:

* the crack masks and label images, pixel by pixel;
* the ``images.csv`` numbers (crack area, length, number of cracks, P, A_T, A_S, threshold);
* the ``cracks.csv`` rows (area, length, type).

Without ``--folder`` the images are those of :mod:`benchmarks.sem_pipeline` (all 40, or 12 with
``--quick``). Prints a table and exits 1 when anything differs beyond ``--rtol``.

Run: ``python benchmarks/same_answers.py --ref /tmp/ref [--folder F] [--quick] [--rtol 0]``
"""
from __future__ import annotations

import argparse
import pathlib
import subprocess
import sys
import tempfile

import numpy as np
import pandas as pd

HERE = pathlib.Path(__file__).resolve().parent
CHILD = """
import sys
ref = sys.argv[3]
if ref:  # import semkit from the reference tree, not from the installed checkout
    sys.meta_path[:] = [f for f in sys.meta_path if "editable" not in repr(f).lower()]
    sys.path.insert(0, ref)
import semkit
from semkit.workflow import analyse_folder
print(semkit.__file__, file=sys.stderr)
analyse_folder(sys.argv[1], sys.argv[2], jobs=1, progress=False, overlays=False,
               save_masks=True)
"""
IMAGE_COLS = ["n_cracks", "crack_area_um2", "crack_length_um", "area_T_um2", "area_S_um2", "P",
              "threshold_value", "n_rejected", "n_thin"]
CRACK_COLS = ["crack_id", "area_um2", "length_um", "type_post"]


def _run(folder, out, ref):
    return subprocess.Popen([sys.executable, "-c", CHILD, str(folder), str(out), ref or ""])


def _compare(a, b, rtol):
    rows = []
    ia, ib = (pd.read_csv(p / "images.csv").set_index("image") for p in (a, b))
    ca, cb = (pd.read_csv(p / "cracks.csv") for p in (a, b))
    for name in ia.index:
        ea, eb = (str(t.at[name, "error"]) if pd.notna(t.at[name, "error"]) else ""
                  for t in (ia, ib))
        if ea or eb:  # a failed image: the same failure on both sides
            rows.append(dict(image=name, crack_px=0, mask_diff_px=0 if ea == eb else -1,
                             labels_same=ea == eb, max_rel_diff=0.0, cracks_same=ea == eb,
                             error=ea or eb))
            continue
        ma = np.asarray(_read(a / "masks" / f"{pathlib.Path(name).stem}_cracks.png")) > 0
        mb = np.asarray(_read(b / "masks" / f"{pathlib.Path(name).stem}_cracks.png")) > 0
        la = _read(a / "masks" / f"{pathlib.Path(name).stem}_labels.png")
        lb = _read(b / "masks" / f"{pathlib.Path(name).stem}_labels.png")
        worst = 0.0
        for c in IMAGE_COLS:
            x, y = ia.at[name, c], ib.at[name, c]
            if not (pd.isna(x) and pd.isna(y)):
                worst = max(worst, abs(float(x) - float(y)) / max(abs(float(x)), 1e-12))
        ka = ca[ca.image == name][CRACK_COLS].reset_index(drop=True)
        kb = cb[cb.image == name][CRACK_COLS].reset_index(drop=True)
        same_cracks = ka.shape == kb.shape and (ka.type_post == kb.type_post).all() and \
            np.allclose(ka[["area_um2", "length_um"]], kb[["area_um2", "length_um"]],
                        rtol=rtol, atol=0, equal_nan=True)
        rows.append(dict(image=name, crack_px=int(ma.sum()), mask_diff_px=int((ma != mb).sum()),
                         labels_same=bool(np.array_equal(la, lb)), max_rel_diff=worst,
                         cracks_same=bool(same_cracks), error=""))
    return pd.DataFrame(rows)


def _read(p):
    import cv2
    return cv2.imread(str(p), cv2.IMREAD_UNCHANGED)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--ref", required=True, help="source tree holding the reference semkit/")
    ap.add_argument("--folder", help="images (with manifest.csv); default the benchmark's")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--rtol", type=float, default=0.0,
                    help="relative tolerance of the numbers (default 0: identical)")
    args = ap.parse_args(argv)
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="semkit_same_"))
    folder = pathlib.Path(args.folder) if args.folder else tmp / "images"
    if not args.folder:
        sys.path.insert(0, str(HERE))
        from sem_pipeline import SIZES, _make
        sizes = SIZES[:8] + SIZES[20:24] if args.quick else SIZES
        folder.mkdir()
        truth = pd.DataFrame([_make(k, s, folder) for k, s in enumerate(sizes)])
        truth.assign(specimen="S1", test="ucs", pixel_size_um=1.0)[
            ["image", "specimen", "test", "stage", "pixel_size_um"]].to_csv(
                folder / "manifest.csv", index=False)
    procs = [_run(folder, tmp / "ref", args.ref), _run(folder, tmp / "new", None)]
    if any(p.wait() for p in procs):
        return 2
    r = _compare(tmp / "ref", tmp / "new", args.rtol)
    print(r.to_string(index=False))
    ok = (r.mask_diff_px == 0).all() and r.labels_same.all() and r.cracks_same.all() and \
        (r.max_rel_diff <= args.rtol).all()
    print(f"\n{len(r)} images, {int(r.crack_px.sum())} crack px, "
          f"{int(r.mask_diff_px.sum())} differ; largest relative difference of images.csv "
          f"numbers {r.max_rel_diff.max():.2g}: {'SAME' if ok else 'DIFFERENT'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

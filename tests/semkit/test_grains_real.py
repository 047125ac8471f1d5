"""Mineral-fraction agreement on real sandstone thin sections with hand-labelled masks (issue #3).

Data: ../shared/real_sem/sandstone_thinsection_minerals (GPL-3.0; read in place, never copied).
Mask classes: 0 matrix/pores/cement, 1 K-feldspar, 2 lithic, 3 plagioclase, 4 quartz.

What a grey-level phase classifier can honestly do on optical (PPL) thin sections: separate the
framework grains (classes 1-4, bright in PPL) from the darker matrix. Quartz and the feldspars
have the same PPL grey level (their XPL colours depend on crystal orientation), so a per-mineral
split is not attempted from grey levels; with the masks as the phase map, the grain table and
``grains.csv`` reproduce the masks' mineral fractions exactly.
Measured (half resolution, multi-Otsu, 2 phases), framework fraction error predicted - mask:
2a -0.096, 2b -0.072, 5a -0.038, image039 -0.107, image047 -0.074 (mean |err| 0.077).
"""
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage as ndi

from semkit.grains import grain_size_table, grain_table, mineral_phases

DATA = Path(__file__).resolve().parents[3] / "shared" / "real_sem" / \
    "sandstone_thinsection_minerals"
if not DATA.is_dir():
    DATA = Path("/work/shared/real_sem/sandstone_thinsection_minerals")
IDS = ["2a", "2b", "5a", "image039", "image047"]
CLASSES = {1: "K-feldspar", 2: "lithic", 3: "plagioclase", 4: "quartz"}
FRAMEWORK_TOL_EACH = 0.12
FRAMEWORK_TOL_MEAN = 0.09

pytestmark = pytest.mark.skipif(not (DATA / "masks").is_dir(),
                                reason="shared/real_sem/sandstone_thinsection_minerals absent")


def _load(i, step=2):
    tifffile = pytest.importorskip("tifffile")
    from skimage.io import imread
    mask = tifffile.imread(DATA / "masks" / f"{i}_mask.ome.tiff")[::step, ::step]
    ppl = imread(DATA / "ppl" / f"{i}_ppl.jpg")[::step, ::step]
    return ppl, mask


def test_framework_fraction_agreement_with_masks():
    errs = []
    for i in IDS:
        ppl, mask = _load(i)
        ph, _ = mineral_phases(ppl, 2)
        errs.append((ph == 1).mean() - (mask > 0).mean())
    errs = np.array(errs)
    assert np.all(np.abs(errs) <= FRAMEWORK_TOL_EACH), errs.round(3)
    assert np.abs(errs).mean() <= FRAMEWORK_TOL_MEAN, errs.round(3)


@pytest.mark.parametrize("i", ["2a", "image047"])
def test_grains_csv_fractions_match_masks(i):
    _, mask = _load(i, step=1)
    grains = np.zeros(mask.shape, np.int32)
    for k in CLASSES:  # connected components per class = approximate grain instances
        lab, n = ndi.label(mask == k)
        grains[lab > 0] = lab[lab > 0] + grains.max()
    t = grain_table(grains, mask, pixel_size_um=1.0, names=list(CLASSES.values()))
    table = grain_size_table(t, classes="50,300")
    got = table.groupby("mineral").volume_fraction_pct.first()
    counts = np.bincount(mask.ravel(), minlength=5)[1:]
    for k, name in CLASSES.items():
        want = 100 * counts[k - 1] / counts.sum()
        assert got.get(name, 0.0) == pytest.approx(want, abs=1e-9)
    assert len(t) == sum(ndi.label(mask == k)[1] for k in CLASSES)

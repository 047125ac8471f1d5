"""The Ch. 6 damage measures in the summary.json of a test on a specimen with a hole
(sim.hole_damage through the loading skeleton)."""
import json

import numpy as np
import pytest
from _specimens import random_specimen

from sim import hole_damage as hd
from sim.protocols.registry import run_test


def _with_hole(spec, centre, radius):
    """``spec`` without the particles in a hole, the hole recorded as gbmgen defect does."""
    from sim import Specimen
    keep = np.hypot(spec.x - centre[0], spec.y - centre[1]) >= radius
    idx = np.cumsum(keep) - 1
    bk = keep[spec.bond_i] & keep[spec.bond_j]
    arrays = {k: getattr(spec, k) for k in spec.__dataclass_fields__ if k != "meta"}
    for k in ("x", "y", "r", "mineral", "grain"):
        arrays[k] = arrays[k][keep]
    arrays["bond_i"], arrays["bond_j"] = idx[spec.bond_i[bk]], idx[spec.bond_j[bk]]
    for k in ("bond_kind", "joint_nx", "joint_ny"):
        arrays[k] = arrays[k][bk]
    meta = {"defects": [{"type": "hole", "kind": "manual", "centres_m": [list(centre)],
                         "radius_m": radius}]}
    return Specimen(**arrays, meta=meta)


def test_summary_json_has_the_measures_when_the_specimen_has_holes(tmp_path):
    spec = random_specimen(4e-3, 8e-3, 0.2e-3, seed=3, pb_ten=20e6, pb_coh=20e6)
    holed = _with_hole(spec, (2e-3, 4e-3), 0.8e-3)
    res = run_test("ucs", holed, out=tmp_path / "h", progress=False, figures=False,
                   platen_velocity=0.05, max_strain=4e-3)
    on_disk = json.loads((tmp_path / "h" / "summary.json").read_text())["hole_damage"]
    m = res.summary["hole_damage"]
    assert on_disk["damaged_area_mm2"] == pytest.approx(m["damaged_area_mm2"])
    assert m["holes"][0]["radius_mm"] == pytest.approx(0.8)
    assert m["crack_joins_holes"] is None
    # the measure from the result's own arrays, recomputed here
    sim = res.sim
    state = sim.bond_state
    broken = (state == 1) | (state == 2)
    assert broken.any()                    # the weak specimen cracked
    ref = hd.hole_damage(holed.x, holed.y, holed.r, holed.bond_i, holed.bond_j, broken,
                         [(2e-3, 4e-3, 0.8e-3)])
    assert m["damaged_area_mm2"] == pytest.approx(ref["damaged_area_mm2"])
    assert 0 < m["max_displacement_mm"] < 0.1
    plain = run_test("ucs", spec, progress=False, platen_velocity=0.05, max_strain=1e-4)
    assert "hole_damage" not in plain.summary

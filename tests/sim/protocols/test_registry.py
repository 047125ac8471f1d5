"""The registry of tests, the shared options object and run_test."""
import dataclasses

import pytest

from sim import Specimen
from sim.protocols.options import SHARED, TestOptions, split_options
from sim.protocols.registry import TESTS, protocol, run_test


def test_registry_names_and_protocol_attributes():
    assert list(TESTS) == ["ucs", "tension", "brazilian", "biaxial"]
    for name, cls in TESTS.items():
        assert cls.name == name and cls.help and cls.peak in ("ucs_mpa", "tensile_mpa")
        assert not set(f.name for f in dataclasses.fields(cls)) & set(SHARED)
    with pytest.raises(ValueError, match="unknown test 'shear'; expected one of ucs, tension"):
        protocol("shear")


def test_split_options_sorts_and_refuses_unknown_keywords():
    shared, own = split_options(TESTS["biaxial"], {"confinement": 5e6, "post_peak": 0.7})
    assert shared.post_peak == 0.7 and own == {"confinement": 5e6}
    with pytest.raises(ValueError, match="biaxial test: unknown option 'grip_depth'"):
        split_options(TESTS["biaxial"], {"grip_depth": 1e-3})
    with pytest.raises(ValueError, match="'ramp_records' = 0"):
        TestOptions(ramp_records=0)
    with pytest.raises(ValueError, match="'resume' needs 'out'"):
        TestOptions(resume=True)
    base = TestOptions(max_strain=2e-4, post_peak=None, progress=False)
    shared, _ = split_options(TESTS["ucs"], {"damping": 0.5}, base=base)
    assert shared.damping == 0.5 and shared.max_strain == 2e-4


def test_run_test_takes_one_options_object_and_keywords(tmp_path):
    s = Specimen.lattice(nx=10, ny=16, radius=1e-3, gap=2e-3)
    opts = TestOptions(max_strain=2e-4, post_peak=None, progress=False, figures=False)
    a = run_test("ucs", s, options=opts, adaptive=False, platen_velocity=0.05)
    b = run_test("ucs", s, out=tmp_path / "b", max_strain=2e-4, post_peak=None,
                 progress=False, figures=False, adaptive=False, platen_velocity=0.05)
    assert a.summary["steps"] == b.summary["steps"] > 0
    assert (tmp_path / "b" / "summary.json").exists()
    assert a.summary["options"]["platen_velocity_m_per_s"] == 0.05

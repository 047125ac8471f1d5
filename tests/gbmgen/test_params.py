"""Parameter presets and files."""
import numpy as np
import pytest

from gbmgen.errors import InputError
from gbmgen.params import load_params


def test_presets_carry_reference_values():
    ch4 = load_params("thesis-ch4").mineral_arrays(["pyroxene", "plagioclase", "biotite"])
    np.testing.assert_allclose(ch4["pb_emod"], [58e9, 65e9, 61e9])
    np.testing.assert_allclose(ch4["pb_coh"], [250e6, 300e6, 270e6])
    np.testing.assert_allclose(ch4["pb_kratio"], [2.0, 2.0, 1.5])
    ch5 = load_params("thesis-ch5")
    a5 = ch5.mineral_arrays(["pyroxene", "plagioclase", "biotite"])
    np.testing.assert_allclose(a5["density"], [2500, 2600, 3000])
    np.testing.assert_allclose(a5["pb_ten"], [310e6, 360e6, 320e6])
    np.testing.assert_allclose(a5["fric"], 1.2)
    assert ch5.joint["sj_fa"] == 30.0


def test_file_errors_name_the_field(tmp_path):
    p = tmp_path / "p.yaml"
    p.write_text("minerals:\n  quartz: {density: 2650}\nsmooth_joint: {}\n")
    with pytest.raises(InputError, match=r"'minerals.quartz.emod' missing"):
        load_params(str(p))
    p.write_text("minerals: {}\n")
    with pytest.raises(InputError, match="'minerals' missing or empty"):
        load_params(str(p))
    with pytest.raises(InputError, match="no such parameter file"):
        load_params(str(tmp_path / "none.yaml"))


def test_bond_like_joint_stiffness_is_resolved_at_build(tmp_path):
    """Presets ask for sj_kn = mean(pb_emod) / (2 r_mean), sj_ks = sj_kn / 2 (not 4e9 Pa/m)."""
    from _gbmgen_builds import small_specimen

    spec = small_specimen()
    kn = np.mean(spec.pb_emod) / (2.0 * np.mean(spec.r))
    np.testing.assert_allclose(spec.sj_kn, [kn], rtol=1e-12)
    np.testing.assert_allclose(spec.sj_ks, [kn / 2.0], rtol=1e-12)
    assert 1e14 < kn < 1e15  # ~60 GPa / 0.2 mm, five orders above the tabled 4e9


def test_calibration_files_load_and_literal_numbers_stay(tmp_path):
    """A file in gbmsim calibrate's layout (key 'joint') is a valid --params file."""
    from sim.protocols.parameters import save_parameters, thesis_parameters

    p = tmp_path / "calibrated.yaml"
    save_parameters(p, thesis_parameters())
    prm = load_params(str(p))
    assert prm.joint["sj_kn"] == 4e9 and prm.joint["sj_ks"] == 2e9
    np.testing.assert_allclose(prm.joint_arrays()["sj_kn"], [4e9])
    a = prm.mineral_arrays(["biotite"])
    np.testing.assert_allclose(a["pb_ten"], [320e6])


def test_bond_stiffness_needs_the_particles():
    with pytest.raises(InputError, match="mean particle radius"):
        load_params("thesis-ch4").joint_arrays()


def test_calibrated_preset_is_the_calibration_result():
    """``thesis-ch4-calibrated`` holds what ``gbmsim calibrate`` wrote (6 significant digits),
    with the joint stiffness as the 'bond' rule that it was derived from."""
    from pathlib import Path

    import yaml
    path = (Path(__file__).resolve().parents[2] / "benchmarks" / "ucs_results"
            / "calibration_10x20_seated" / "calibrated_params.yaml")
    cal = yaml.safe_load(path.read_text())
    p = load_params("thesis-ch4-calibrated")
    for m, fields in cal["minerals"].items():
        for k, v in fields.items():
            assert p.minerals[m][k] == pytest.approx(v, rel=1e-5), (m, k)
    for k in ("sj_ten", "sj_coh", "sj_fa", "sj_fric"):
        assert p.joint[k] == pytest.approx(cal["joint"][k], rel=1e-5), k
    assert p.joint["sj_kn"] == "bond" and p.joint["sj_ks"] == "bond"
    # the calibrated joint stiffness is the bond rule at the calibration packings' mean radius
    emod = np.mean([cal["minerals"][m]["pb_emod"] for m in cal["minerals"]])
    r_mean = emod / (2 * cal["joint"]["sj_kn"])
    assert 0.098e-3 < r_mean < 0.1e-3
    assert cal["joint"]["sj_ks"] == pytest.approx(cal["joint"]["sj_kn"] / 2, rel=1e-12)

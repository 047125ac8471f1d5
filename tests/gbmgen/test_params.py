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

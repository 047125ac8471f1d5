"""gbmgen run: one SEM image -> semkit grains.csv -> specimen (grains only, small specimen)."""
import json
import pathlib
import shutil

import pytest

from gbmgen.cli import main
from gbmgen.table import read_table
from sim.specimen import Specimen

SAMPLE = pathlib.Path(__file__).resolve().parents[2] / "sample_images" / "S1_pre_01.png"


@pytest.mark.skipif(not SAMPLE.exists(), reason="sample_images not present")
def test_run_one_image(tmp_path, capsys):
    img = tmp_path / "images"
    img.mkdir()
    shutil.copy(SAMPLE, img / SAMPLE.name)
    out = tmp_path / "out"
    rc = main(["run", str(img), "--out", str(out), "--no-cracks", "--no-progress",
               "--pixel-size-um", "1.43", "--width-mm", "5", "--height-mm", "10", "--seed", "2"])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    table = read_table(out / "semkit" / "grains.csv")  # the measured table validates
    spec = Specimen.load(out / "specimen.npz")
    assert spec.meta["source_table"].endswith("grains.csv") and spec.meta["seed"] == 2
    assert [str(m) for m in spec.mineral_names] == list(table.minerals)
    assert summary["grains"] == spec.n_grains > 10
    assert (out / "specimen.png").exists() and (out / "run.json").exists()
    # model scale 10: the specimen's largest seeded size range is 10 x the measured one
    hi_mm = max(v[1] for v in spec.meta["grains"]["scenario_ranges_mm"].values())
    assert hi_mm == pytest.approx(10 * table.range_um()[:, 1].max() / 1000)


def test_run_missing_folder(tmp_path, capsys):
    assert main(["run", str(tmp_path / "none"), "--out", str(tmp_path / "o")]) == 2
    assert "not a folder" in capsys.readouterr().err

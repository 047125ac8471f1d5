"""gbmgen run: one SEM image -> semkit grains.csv -> specimen (grains only, small specimen)."""
import json
import pathlib
import shutil

import pandas as pd
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
    args = ["--no-cracks", "--no-progress", "--test", "none", "--pixel-size-um", "1.43",
            "--width-mm", "5", "--height-mm", "10"]
    rc = main(["run", str(img), "--out", str(out), *args, "--seed", "2"])
    assert rc == 0
    summary = json.loads(capsys.readouterr().out)
    # without --seed: the fixed default seed, and two runs build the same specimen
    for k in (1, 2):
        assert main(["run", str(img), "--out", str(tmp_path / f"d{k}"), *args]) == 0
    capsys.readouterr()
    d1, d2 = (Specimen.load(tmp_path / f"d{k}" / "specimen.npz") for k in (1, 2))
    assert d1.meta["seed"] == d2.meta["seed"] == 1 and (d1.x == d2.x).all()
    assert json.loads((tmp_path / "d1" / "run.json").read_text())["seed_source"] == "default"
    table = read_table(out / "semkit" / "grains.csv")  # the measured table validates
    spec = Specimen.load(out / "specimen.npz")
    assert spec.meta["source_table"].endswith("grains.csv") and spec.meta["seed"] == 2
    assert [str(m) for m in spec.mineral_names] == list(table.minerals)
    assert summary["grains"] == spec.n_grains > 10
    assert (out / "specimen.png").exists() and (out / "run.json").exists()
    # model scale 10: the specimen's largest seeded size range is 10 x the measured one
    hi_mm = max(v[1] for v in spec.meta["grains"]["scenario_ranges_mm"].values())
    assert hi_mm == pytest.approx(10 * table.range_um()[:, 1].max() / 1000)


def _one_error_line(capsys, *words):
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith("gbmgen: error: ") and all(w in lines[0] for w in words), err
    return lines[0]


def test_run_missing_folder(tmp_path, capsys):
    assert main(["run", str(tmp_path / "none"), "--out", str(tmp_path / "o")]) == 2
    _one_error_line(capsys, "not a folder")


def test_run_bad_input_exit_2_one_line_nothing_left(tmp_path, capsys, monkeypatch):
    """An empty folder, a corrupt image and a bad grains.csv (semkit's errors and ours): exit
    2, one stderr line naming the file or field, and no output folder left behind."""
    empty = tmp_path / "empty"
    empty.mkdir()
    out = tmp_path / "o1"
    assert main(["run", str(empty), "--out", str(out), "--no-progress"]) == 2
    _one_error_line(capsys, "no image files")
    assert not out.exists()
    corrupt = tmp_path / "corrupt"
    corrupt.mkdir()
    (corrupt / "S1_pre_01.png").write_bytes(b"not an image")
    out = tmp_path / "o2"
    assert main(["run", str(corrupt), "--out", str(out), "--no-progress"]) == 2
    _one_error_line(capsys, "S1_pre_01.png")
    assert not out.exists()

    def bad_table(images, sem, **kw):               # semkit writes an unusable grains.csv
        sem.mkdir(parents=True, exist_ok=True)
        (sem / "grains.csv").write_text("mineral,class,d_min_um\npyroxene,fine,-3\n")
        return pd.DataFrame({"image": ["a.png"], "error": [None]}), pd.DataFrame()

    monkeypatch.setattr("semkit.workflow.analyse_folder", bad_table)
    img = tmp_path / "images"
    img.mkdir()
    out = tmp_path / "o3"
    assert main(["run", str(img), "--out", str(out), "--no-cracks", "--no-progress"]) == 2
    _one_error_line(capsys, "grains.csv")
    assert not out.exists()
    with pytest.raises(SystemExit) as exc:
        main(["run", str(img), "--out", str(out), "--seed", "x"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--seed" in err and "'random'" in err


def test_run_and_build_default_seed_is_fixed_and_random_draws(tmp_path, capsys):
    from gbmgen import config
    a, b, c = (tmp_path / f"{k}.npz" for k in "abc")
    for path, extra in ((a, []), (b, []), (c, ["--seed", "random"])):
        assert main(["build", "--table", "table-4-1", "--width-mm", "3", "--height-mm", "6",
                     "--out", str(path), "--no-progress", *extra]) == 0
    sa, sb, sc = (Specimen.load(p) for p in (a, b, c))
    assert sa.meta["seed"] == sb.meta["seed"] == config.DEFAULT_SEED
    assert (sa.x == sb.x).all() and sc.meta["seed"] != config.DEFAULT_SEED


@pytest.mark.skipif(not SAMPLE.exists(), reason="sample_images not present")
def test_run_whole_chain_sets_sem_p_beside_simulated_p(tmp_path, capsys):
    """Images with a manifest -> cracks, P, grains.csv -> specimen -> UCS -> P_sem beside P_sim."""
    img = tmp_path / "images"
    img.mkdir()
    names = ["S1_pre_01.png", "S1_fail_01.png"]
    for n in names:
        shutil.copy(SAMPLE.parent / n, img / n)
    man = (SAMPLE.parent / "manifest.csv").read_text().splitlines()
    (img / "manifest.csv").write_text("\n".join([man[0]] + [ln for ln in man[1:]
                                                            if ln.split(",")[0] in names]) + "\n")
    out = tmp_path / "out"
    rc = main(["run", str(img), "--out", str(out), "--no-progress", "--seed", "3", "--jobs", "1",
               "--width-mm", "3", "--height-mm", "6", "--post-peak", "0.9"])
    assert rc == 0
    run = json.loads((out / "run.json").read_text())
    ts = run["test_summary"]
    # a bonded granite-like specimen: stiff and strong, cracks logged by kind
    assert 20 < ts["elastic"]["E_measured_gpa"] < 200 and 30 < ts["ucs_mpa"] < 500
    assert not ts["representative"]["ok"] and ts["representative"]["warnings"]   # 3 x 6 mm
    assert ts["stop_reason"] == "post_peak" and ts["cracks"]["total"] > 0
    ucs = json.loads((out / "ucs" / "summary.json").read_text())
    assert ucs["ucs_mpa"] == pytest.approx(ts["ucs_mpa"])
    # the SEM damage ratio of the loaded image, pooled, equals semkit's damage.csv row
    import pandas as pd
    d = pd.read_csv(out / "semkit" / "damage.csv")
    failure = d[d["stage"] == "failure"].iloc[0]
    assert run["P_sem"]["P_pooled"] == pytest.approx(failure["area_T_um2"] / failure["area_S_um2"])
    # the pooled P carries the loaded stage's status
    assert run["P_sem"]["P_status"] == failure["P_status"]
    assert (failure["P_status"] == "low_confidence") == ("low_confidence" in run["P_sem"]["P_note"])
    # and the stage's typing band of its P_mean
    row = next(r for r in run["P_sem"]["by_stage"] if r["stage"] == "failure")
    assert row["P_mean_low"] == pytest.approx(failure["P_mean_low"])
    assert 0 < row["P_mean_low"] < row["P_mean_high"] == pytest.approx(failure["P_mean_high"])
    # the pooled SEM P's band: one loaded image, whose pooled ratio is the stage's mean, so
    # the same draws give the same band
    assert (run["P_sem"]["P_pooled_low"], run["P_sem"]["P_pooled_high"]) == pytest.approx(
        (failure["P_mean_low"], failure["P_mean_high"]))
    assert run["P_sem"]["P_pooled_low"] < run["P_sem"]["P_pooled"] < run["P_sem"]["P_pooled_high"]
    assert "simulated ucs" in capsys.readouterr().err


def test_sem_damage_pools_loaded_stages_and_names_each_flagged_stage_once(tmp_path):
    from gbmgen.run import sem_damage
    rows = [("S1", "ucs", "pre-test", 0.0, 0.0, "no_p"),
            ("S1", "ucs", "failure", 30.0, 10.0, "low_confidence"),
            ("S2", "ucs", "failure", 10.0, 30.0, "low_confidence"),
            ("S2", "ucs", "initiating", 5.0, 10.0, "ok")]
    d = pd.DataFrame(rows, columns=["specimen", "test", "stage", "area_T_um2", "area_S_um2",
                                    "P_status"])
    d["P_mean"] = d["P_pooled"] = d["area_T_um2"] / d["area_S_um2"].where(d["area_S_um2"] > 0)
    d.to_csv(tmp_path / "damage.csv", index=False)
    out = sem_damage(tmp_path)
    assert out["P_pooled"] == pytest.approx(45.0 / 50.0)
    assert out["P_status"] == "low_confidence"
    assert "S1 ucs failure, S2 ucs failure " in out["P_note"]
    # a table written without stage statuses is unchecked, not ok
    d.drop(columns="P_status").to_csv(tmp_path / "damage.csv", index=False)
    out = sem_damage(tmp_path)
    assert (out["P_status"], out["P_note"]) == ("unchecked", "")
    # all loaded stages ok
    d.assign(P_status="ok").to_csv(tmp_path / "damage.csv", index=False)
    assert sem_damage(tmp_path)["P_status"] == "ok"

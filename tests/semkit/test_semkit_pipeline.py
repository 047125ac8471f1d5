"""semkit.workflow and semkit.cli: batch runs, failures recorded, exit codes, laziness."""
import numpy as np
import pandas as pd
import pytest

from semkit import analysis, cli, workflow
from semkit.analysis import analyse_image
from semkit.io import write_image
from semkit.synth import make_sem_image

GOOD = ("a.png", "b.png", "c.png")


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    d = tmp_path_factory.mktemp("imgs")
    for k, name in enumerate(GOOD):
        s = make_sem_image((160, 200), n_cracks=4, widths=(3, 6), seed=40 + k)
        write_image(d / name, s.image)
    (d / "manifest.csv").write_text("image,specimen,stage,magnification,pixel_size_um\n"
                                    "a.png,S1,pre-test,,0.5\nb.png,S1,failure,200,\n")
    return d


@pytest.fixture(scope="module")
def bad_folder(folder, tmp_path_factory):
    d = tmp_path_factory.mktemp("mixed")
    for name in GOOD + ("manifest.csv",):
        (d / name).write_bytes((folder / name).read_bytes())
    (d / "corrupt.png").write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    (d / "empty.tif").write_bytes(b"")
    write_image(d / "dark.png", np.zeros((64, 64), np.uint8))
    (d / "notes.gif").write_bytes(b"GIF89a")
    return d


def test_batch_goes_on_and_records_errors(bad_folder, tmp_path, capsys):
    out = tmp_path / "out"
    rc = cli.main(["analyse", str(bad_folder), "--out", str(out), "--no-progress", "--jobs", "1",
                   "--pixel-size-um", "2.0", "--no-classify"])
    assert rc == 1
    err = capsys.readouterr().err.strip().splitlines()
    # issue 15: a non-image file is skipped and listed in one line, not a failed image
    assert len(err) == 2 and err[0] == "semkit: skipped 1 non-image file(s): notes.gif"
    assert "3 of 6 images failed" in err[1]
    img = pd.read_csv(out / "images.csv", keep_default_na=False)
    assert list(img.columns[:12]) == analysis.IMAGE_COLUMNS
    errors = dict(zip(img["image"], img["error"]))
    assert "cannot read" in errors["corrupt.png"] and "cannot read" in errors["empty.tif"]
    assert "no contrast" in errors["dark.png"]
    assert "notes.gif" not in errors
    assert all(errors[n] == "" for n in GOOD)
    src = dict(zip(img["image"], img["pixel_size_source"]))
    assert src == {**src, "a.png": "manifest", "b.png": "magnification", "c.png": "cli"}
    cracks = pd.read_csv(out / "cracks.csv")
    for col in ("image", "crack_id", "area_um2", "length_um", "mean_aperture_um",
                "orientation_deg", "tortuosity", "n_branches", "type_pre", "type_post",
                "confidence"):
        assert col in cracks.columns
    assert set(cracks["image"]) == set(GOOD)
    assert (cracks["type_pre"] == "unknown").all()
    assert sorted(p.name for p in (out / "overlays").iterdir()) == [
        f"{n[:-4]}_overlay.png" for n in GOOD]
    assert not list(out.glob("*.tmp*"))


def test_parallel_equals_serial(folder, tmp_path):
    kw = dict(progress=False, overlays=False, classify=False)
    i1, c1 = workflow.analyse_folder(folder, tmp_path / "s", jobs=1, **kw)
    i2, c2 = workflow.analyse_folder(folder, tmp_path / "p", jobs=2, **kw)
    cols = ["image", "n_cracks", "crack_area_um2", "crack_length_um", "crack_area_fraction"]
    pd.testing.assert_frame_equal(i1[cols], i2[cols])
    pd.testing.assert_frame_equal(c1.drop(columns=[]), c2)
    assert (i1["seconds"] > 0).all()


def test_bad_cli_input_exit_2(folder, tmp_path, capsys):
    assert cli.main(["analyse", str(tmp_path / "nope"), "--out", str(tmp_path / "o")]) == 2
    assert cli.main(["analyse", str(folder), "--out", str(tmp_path / "o"),
                     "--threshold", "triangle"]) == 2
    cfg = tmp_path / "c.yaml"
    cfg.write_text("threshold: otsu\ncolour: red\n")
    assert cli.main(["analyse", str(folder), "--out", str(tmp_path / "o"), "--config",
                     str(cfg)]) == 2
    err = capsys.readouterr().err
    assert "nope" in err and "triangle" in err and "colour" in err
    assert cli.main([]) == 2


def test_config_file_and_flags(folder, tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("threshold: manual:60\nflatten: none\noverlays: false\n")
    out = tmp_path / "o"
    rc = cli.main(["analyze", str(folder), "--out", str(out), "--config", str(cfg),
                   "--no-progress", "--no-length", "--jobs", "1", "--no-classify"])
    assert rc == 0
    img = pd.read_csv(out / "images.csv")
    assert (img["threshold_method"] == "manual").all() and (img["threshold_value"] == 60).all()
    assert img["crack_length_um"].isna().all() and not (out / "overlays").exists()


def test_interrupt_keeps_finished_results(folder, tmp_path, monkeypatch):
    real = workflow.analyse_file
    calls = []

    def flaky(path, **kw):
        calls.append(path)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(path, **kw)

    monkeypatch.setattr(workflow, "analyse_file", flaky)
    out = tmp_path / "o"
    rc = cli.main(["analyse", str(folder), "--out", str(out), "--no-progress", "--jobs", "1",
                   "--no-classify"])
    assert rc == 130
    assert len(pd.read_csv(out / "images.csv")) == 2


def test_stages_are_lazy_and_skippable():
    img = np.full((64, 64), 180, np.uint8)
    img[20:24, 5:60] = 30
    a = analyse_image(img, pixel_size_um=2.0, threshold="otsu", flatten="none", length=False)
    row = a.summary()
    assert row["n_cracks"] == 1 and row["crack_area_um2"] == pytest.approx(4 * 55 * 4.0)
    assert np.isnan(row["crack_length_um"])
    assert "skeleton" not in a.__dict__          # never computed
    a2 = analyse_image(img, pixel_size_um=2.0, threshold="otsu", flatten="none")
    # a 4 x 55 bar is a 51-px centreline with round-ish caps of half its width
    assert a2.cracks["length_um"].iloc[0] == pytest.approx(2.0 * 51, rel=0.04)
    assert a2.skeleton.sum() > 0 and a2.crack_labels.max() == 1


def test_pores_reported_apart():
    s = make_sem_image((240, 320), n_cracks=3, widths=(3, 5), n_pores=3, seed=8)
    a = analyse_image(s.image)
    row = a.summary()
    assert row["n_pores"] >= 2
    assert not (a.crack_labels[s.pore_mask] > 0).any()


def test_bad_options():
    from semkit.errors import InputError
    with pytest.raises(InputError, match="despeckle"):
        analyse_image(np.zeros((10, 10)), despeckle="gauss")
    with pytest.raises(InputError, match="pixel_size_um"):
        analyse_image(np.zeros((10, 10)), pixel_size_um=0)


def test_save_masks_and_typing_only_on_loaded_stages(folder, tmp_path):
    """--save-masks writes the 0/255 crack mask and the 16-bit labels (= crack_id); without
    --classify only manifest images of a loaded stage are typed (b.png: failure)."""
    from semkit.io import read_image
    out = tmp_path / "o"
    assert cli.main(["analyse", str(folder), "--out", str(out), "--no-progress", "--jobs", "1",
                     "--save-masks", "--no-overlay"]) == 0
    img = pd.read_csv(out / "images.csv").set_index("image")
    assert img.loc["a.png", "P_status"] == "pre-test"
    assert img.loc["c.png", "P_status"] == "not_classified"
    assert img.loc["b.png", "P_status"] in ("ok", "low_confidence", "no_shear", "no_cracks")
    cracks = pd.read_csv(out / "cracks.csv")
    for name in GOOD:
        m = read_image(out / "masks" / f"{name[:-4]}_cracks.png")
        lab = read_image(out / "masks" / f"{name[:-4]}_labels.png")
        assert m.dtype == np.uint8 and set(np.unique(m)) <= {0, 255}
        assert lab.dtype == np.uint16 and ((lab > 0) == (m == 255)).all()
        kept = cracks[(cracks.image == name) & cracks.rejected_as.isna()]
        assert set(np.unique(lab[lab > 0])) == set(kept.crack_id)


def test_bright_cracks_are_read_as_the_same_image_inverted(tmp_path):
    """A fluorescent-dye section shows cracks bright: ``--bright-cracks`` inverts the grey
    first, so the numbers equal those of the dark-crack image exactly; without it the
    inverted image is not read as fine."""
    from semkit.io import invert_grey
    s = make_sem_image((256, 320), stage="post", n_cracks=8, widths=(2, 6), seed=7)
    kw = dict(pixel_size_um=s.pixel_size_um, stage="failure", classify=False)
    dark = analyse_image(s.image, **kw).summary()
    bright = invert_grey(s.image)
    flagged = analyse_image(bright, **kw).summary()
    inv = analyse_image(bright, bright_cracks=True, **kw).summary()
    for k in ("n_cracks", "crack_area_um2", "crack_length_um", "valid"):
        assert inv[k] == dark[k], k
    assert dark["valid"] and not flagged["valid"]
    assert abs(dark["crack_area_um2"] / s.pixel_size_um ** 2 / s.crack_area_px - 1) < 0.25
    # the CLI flag reaches the analysis
    write_image(tmp_path / "f.png", bright)
    assert cli.main(["analyse", str(tmp_path), "--out", str(tmp_path / "o"), "--bright-cracks",
                     "--pixel-size-um", str(s.pixel_size_um), "--no-progress",
                     "--jobs", "1"]) == 0
    row = pd.read_csv(tmp_path / "o" / "images.csv").iloc[0]
    assert row["n_cracks"] == dark["n_cracks"]


class _KillsTheWorker:
    """Unpickled (in a worker, as part of its call) it ends that process abruptly, as an
    out-of-memory kill would."""

    def __reduce__(self):
        import os
        return os._exit, (3,)


@pytest.mark.parametrize("n_files", [6, 2])
def test_a_dead_worker_fails_only_the_images_it_held(tmp_path, n_files):
    """``jobs=2``: one worker, kept two images ahead but never with the last one, and this
    process. The worker dies on the first image it is handed; the images it held (the two
    largest of six; the larger of two, the other being this process's) are failed rows naming
    the worker, and this process measures every other image (the run ends: no call is left
    waiting)."""
    import threading
    names = [f"i{k}.png" for k in range(n_files)]
    for k, name in enumerate(names):
        s = make_sem_image((220 - 10 * k, 260), n_cracks=3, widths=(3, 6), seed=60 + k)
        write_image(tmp_path / name, s.image)
    files = sorted(tmp_path.glob("*.png"))
    by_size = [p.name for p in sorted(files, key=lambda p: -p.stat().st_size)]
    held = set(by_size[:min(2, n_files - 1)])
    rows = {}

    def kwargs_of(p):
        kw = dict(pixel_size_um=1.0, options=workflow.AnalysisOptions(classify=False))
        if p.name == by_size[0]:
            kw["seed"] = _KillsTheWorker()
        return kw

    run = threading.Thread(target=workflow._run_shared,
                           args=(files, 2, kwargs_of, lambda n, r: rows.update({n: r})))
    run.start()
    run.join(120)
    assert not run.is_alive(), "the folder loop waits on a call no worker will answer"
    failed = {n for n, r in rows.items() if isinstance(r[0].get("error"), str)
              and r[0]["error"]}
    assert failed == held, failed
    assert all(rows[n][0]["error"].startswith("worker: ") for n in failed)
    assert sorted(rows) == names
    assert all(rows[n][0]["n_cracks"] > 0 for n in names if n not in failed)


def test_folder_processes_keep_freed_memory_on_glibc():
    import platform

    from semkit.workflow import keep_freed_memory
    assert keep_freed_memory() is (platform.libc_ver()[0] == "glibc")

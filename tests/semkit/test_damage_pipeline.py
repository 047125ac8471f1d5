"""Issue #3 stages inside `semkit analyse` (types, P, damage.csv, grains.csv) and the
`semkit grains | indices | classify` subcommands, on tiny synthetic folders."""
import json

import numpy as np
import pandas as pd
import pytest

from semkit.cli import main

synth = pytest.importorskip("semkit.synth")

NAMES = "pyroxene,biotite,plagioclase"  # semkit.synth greys 200, 150, 100: brightest first


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    from skimage.io import imsave
    d = tmp_path_factory.mktemp("imgs")
    rows, truth = [], []
    for k, (stage, sstage) in enumerate([("pre", "pre-test"), ("post", "initiating"),
                                         ("post", "failure")]):
        s = synth.make_sem_image((256, 320), stage=stage, n_cracks=6, seed=400 + k)
        name = f"img{k}.png"
        imsave(d / name, s.image, check_contrast=False)
        rows.append(dict(image=name, specimen="A", test="ucs", stage=sstage,
                         pixel_size_um=1.43))
        truth.append(s)
    pd.DataFrame(rows).to_csv(d / "manifest.csv", index=False)
    return d, truth


def test_analyse_writes_types_p_damage_and_grains(folder, tmp_path, capsys):
    d, truth = folder
    out = tmp_path / "out"
    rc = main(["analyse", str(d), "--out", str(out), "--jobs", "1", "--no-progress",
               "--grains", "--minerals", NAMES, "--classes", "20,140", "--no-overlay"])
    assert rc == 0
    imgs = pd.read_csv(out / "images.csv").set_index("image")
    cracks = pd.read_csv(out / "cracks.csv")
    assert imgs.loc["img0.png", "P_status"] == "pre-test" and np.isnan(imgs.loc["img0.png", "P"])
    for name in ("img1.png", "img2.png"):
        r = imgs.loc[name]
        if r.area_S_um2 > 0:
            assert r.P == pytest.approx(r.area_T_um2 / r.area_S_um2)
    # rows of rejected objects (rejected_as set) are not cracks and carry no type
    rejected = cracks["rejected_as"].fillna("").astype(str) != ""
    assert (cracks.loc[rejected, "type_post"] == "unknown").all()
    cracks = cracks[~rejected]
    post = cracks[cracks.image != "img0.png"]
    assert set(post.type_post) <= {"tensile", "shear", "mixed"}
    assert (cracks[cracks.image == "img0.png"].type_post == "unknown").all()
    assert set(cracks.type_pre) <= {"inter", "intra", "trans"}
    assert {"log_aperture", "frac_tensile", "area_pv_um2", "confidence", "p_shear",
            "type_post_ok", "type_note"} <= set(cracks)
    dmg = pd.read_csv(out / "damage.csv")
    assert list(dmg.stage) == ["pre-test", "initiating", "failure"]
    assert dmg.set_index("stage").loc["failure", "P_mean"] == pytest.approx(
        imgs.loc["img2.png", "P"])
    assert (out / "P_by_stage.png").stat().st_size > 1000
    # the run ends with each stage's mean P and its band, as damage.csv has them
    f = dmg.set_index("stage").loc["failure"]
    line = [ln for ln in capsys.readouterr().err.splitlines() if "A_T/A_S" in ln]
    assert len(line) == 1 and "pre-test" not in line[0]
    assert f"failure {f.P_mean:.3g} ({f.P_mean_low:.3g}-" in line[0]
    g = pd.read_csv(out / "grains.csv")
    assert set(g.mineral) == set(NAMES.split(","))
    vf = g.groupby("mineral").volume_fraction_pct.first()
    # synth shares 50 / 20 / 30 %; three small images: loose check
    assert vf["pyroxene"] == pytest.approx(50, abs=15)
    assert g[g["class"] == "fine"].d_max_um.eq(20).all()
    # the indices CLI reads it
    rc = main(["indices", str(out / "grains.csv"), "--json"])
    assert rc == 0


def test_indices_cli_json(tmp_path, capsys):
    rows = []
    for name, e, f, v in [("pyroxene", (9, 20, 140, 240), (5, 89, 7), 50),
                          ("plagioclase", (8, 20, 80, 200), (17, 68, 15), 30),
                          ("biotite", (8, 20, 80, 180), (26, 63, 11), 20)]:
        for c, cls in enumerate(("fine", "medium", "coarse")):
            rows.append(dict(mineral=name, **{"class": cls}, d_min_um=e[c], d_max_um=e[c + 1],
                             frequency_pct=f[c], volume_fraction_pct=v))
    pd.DataFrame(rows).to_csv(tmp_path / "t41.csv", index=False)
    assert main(["indices", str(tmp_path / "t41.csv"), "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["MHI"] == pytest.approx(2.6308, abs=1e-3) and r["H"] == pytest.approx(0.3988,
                                                                                   abs=1e-3)
    assert r["R_a_mm"] == pytest.approx(0.06929, abs=1e-4)
    (tmp_path / "bad.csv").write_text("a,b\n1,2\n")
    assert main(["indices", str(tmp_path / "bad.csv")]) == 2


def test_classify_train_cli_and_labels_override(folder, tmp_path):
    d, truth = folder
    out = tmp_path / "out"
    assert main(["analyse", str(d), "--out", str(out), "--jobs", "1", "--no-progress",
                 "--no-overlay"]) == 0
    cracks = pd.read_csv(out / "cracks.csv")
    post = cracks[cracks.image == "img2.png"].sort_values("area_um2", ascending=False)
    labels = pd.DataFrame(dict(image="img2.png", crack_id=post.crack_id.iloc[:4],
                               type=["tensile", "shear", "tensile", "shear"]))
    labels.to_csv(tmp_path / "labels.csv", index=False)
    model = tmp_path / "m.json"
    assert main(["classify", str(d), "--train", str(tmp_path / "labels.csv"), "--out",
                 str(model)]) == 0
    m = json.loads(model.read_text())
    assert m["version"] == 3 and len(m["coef"]) == 3 and len(m["coef"][0]) == len(m["mean"])
    assert m["n_per_type"][0] > 0 and m["n_per_type"][1] > 0 and m["n_per_type"][2] == 0
    out2 = tmp_path / "out2"
    assert main(["analyse", str(d), "--out", str(out2), "--jobs", "1", "--no-progress",
                 "--no-overlay", "--crack-model", str(model), "--labels",
                 str(tmp_path / "labels.csv")]) == 0
    c2 = pd.read_csv(out2 / "cracks.csv").set_index(["image", "crack_id"])
    for r in labels.itertuples():
        assert c2.loc[(r.image, r.crack_id), "type_post"] == r.type
        assert c2.loc[(r.image, r.crack_id), "type_source"] == "user"
    i2 = pd.read_csv(out2 / "images.csv").set_index("image")
    sub = c2.loc["img2.png"]
    a_t = (sub.area_pv_um2 * sub.frac_tensile).sum()
    a_s = (sub.area_pv_um2 * sub.frac_shear).sum()
    assert i2.loc["img2.png", "P"] == pytest.approx(a_t / a_s)
    (tmp_path / "bad.json").write_text("{}")
    assert main(["analyse", str(d), "--out", str(tmp_path / "o3"), "--crack-model",
                 str(tmp_path / "bad.json")]) == 2


def test_grains_cli_fractions_and_counts(folder, tmp_path):
    d, truth = folder
    out = tmp_path / "g"
    assert main(["grains", str(d), "--out", str(out), "--minerals", NAMES, "--no-progress",
                 "--seed", "0"]) == 0
    g = pd.read_csv(out / "grains_per_grain.csv")
    t = pd.read_csv(out / "grains.csv")
    assert (out / "grain_maps" / "img0_grains.png").is_file()
    assert (out / "grain_histograms.png").is_file()
    assert t.groupby("mineral").frequency_pct.sum().round(6).eq(100).all()
    for k, s in enumerate(truth):  # area fractions of each image against the truth map
        got = g[g.image == f"img{k}.png"].groupby("mineral").area_um2.sum()
        got = got / got.sum()
        want = pd.Series(np.bincount(s.mineral_labels.ravel(), minlength=3) /
                         s.mineral_labels.size, index=list(s.mineral_names))
        for name in want.index:
            assert got.get(name, 0.0) == pytest.approx(want[name], abs=0.05), (k, name)

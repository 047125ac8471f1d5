"""semkit.io: reading images and the pixel size (manifest, TIFF tags, magnification, CLI)."""
import numpy as np
import pandas as pd
import pytest
import tifffile

from semkit import config
from semkit.errors import InputError
from semkit.io import (
    load_image,
    magnification_pixel_size,
    read_image,
    read_manifest,
    resolve_pixel_size,
    tiff_pixel_size,
    write_image,
)

IMG = (np.arange(40 * 50).reshape(40, 50) % 251).astype(np.uint8)

ZEISS = ("0\r\nAP_IMAGE_PIXEL_SIZE\r\nImage Pixel Size = 715.2 nm\r\n"
         "AP_MAG\r\nMag = 200 X\r\nDP_DETECTOR_CHANNEL\r\nSignal A = QBSD\r\n")
FEI = ("[User]\r\nDate=11/21/2026\r\n[Scan]\r\nPixelWidth=2.78e-06\r\nPixelHeight=2.78e-06\r\n"
       "[Image]\r\nMagnification=100\r\n")


def test_png_tiff_8_16_bit_and_rgb(tmp_path):
    write_image(tmp_path / "a.png", IMG)
    assert np.array_equal(read_image(tmp_path / "a.png"), IMG)
    im16 = IMG.astype(np.uint16) * 257
    write_image(tmp_path / "b.png", im16)
    assert read_image(tmp_path / "b.png").dtype == np.uint16
    tifffile.imwrite(tmp_path / "c.tif", im16)
    assert np.array_equal(read_image(tmp_path / "c.tif"), im16)
    rgb = np.stack([IMG, IMG, IMG], axis=-1)
    write_image(tmp_path / "d.png", rgb)
    g = read_image(tmp_path / "d.png")
    assert g.shape == IMG.shape and np.abs(g.astype(int) - IMG).max() <= 1
    write_image(tmp_path / "e.jpg", IMG)
    assert read_image(tmp_path / "e.jpg").shape == IMG.shape


@pytest.mark.parametrize("compression", ["lzw", "zlib", "packbits"])
def test_compressed_tiffs_as_sem_software_writes_them(tmp_path, compression):
    """SEM software and ImageJ save LZW or Deflate TIFFs; an LZW tile failed with 'requires
    the imagecodecs package' (a dependency now)."""
    im16 = IMG.astype(np.uint16) * 257
    for img, name in ((IMG, "a.tif"), (im16, "b.tif")):
        tifffile.imwrite(tmp_path / name, img, compression=compression)
        assert np.array_equal(read_image(tmp_path / name), img)


def test_a_tiff_tifffile_cannot_decode_is_read_by_libtiff(tmp_path, monkeypatch):
    """Without a codec in tifffile, OpenCV's libtiff reads the pixels."""
    tifffile.imwrite(tmp_path / "a.tif", IMG, compression="lzw")

    def no_codec(self, *a, **k):
        raise ValueError("<COMPRESSION.LZW: 5> requires the 'imagecodecs' package")
    monkeypatch.setattr(tifffile.TiffPage, "asarray", no_codec)
    assert np.array_equal(read_image(tmp_path / "a.tif"), IMG)


@pytest.mark.parametrize("name,content,match", [
    ("bad.png", b"this is not a png", "cannot read"),
    ("empty.tif", b"", "cannot read"),
    ("x.gif", b"GIF89a", "unsupported format"),
])
def test_bad_files_raise_input_error_naming_the_file(tmp_path, name, content, match):
    p = tmp_path / name
    p.write_bytes(content)
    with pytest.raises(InputError, match=match) as e:
        read_image(p)
    assert name in str(e.value)


def test_tiny_image_rejected(tmp_path):
    write_image(tmp_path / "t.png", np.zeros((3, 3), np.uint8))
    with pytest.raises(InputError, match="at least 8 x 8"):
        read_image(tmp_path / "t.png")


def test_zeiss_cz_sem_tag(tmp_path):
    p = tmp_path / "zeiss.tif"
    tifffile.imwrite(p, IMG, extratags=[(34118, "s", 0, ZEISS, True)])
    px, mag = tiff_pixel_size(p)
    assert px == pytest.approx(0.7152) and mag == 200
    assert resolve_pixel_size(p, pixel_size_um=9.0)[:2] == (pytest.approx(0.7152), "metadata")


@pytest.mark.parametrize("tag", [34680, 34682])  # FEI_SFEG, FEI_HELIOS
def test_fei_tags(tmp_path, tag):
    p = tmp_path / "fei.tif"
    tifffile.imwrite(p, IMG, extratags=[(tag, "s", 0, FEI, True)])
    px, mag = tiff_pixel_size(p)
    assert px == pytest.approx(2.78) and mag == 100
    li = load_image(p)
    assert li.pixel_size_source == "metadata" and li.pixel_size_um == pytest.approx(2.78)


def test_source_order_manifest_magnification_cli_default(tmp_path):
    p = tmp_path / "a.png"
    write_image(p, IMG)
    (tmp_path / "manifest.csv").write_text(
        "image,specimen,magnification,pixel_size_um\na.png,S1,500,0.9\nb.png,S1,500,\n"
        "c.png,S1,,\n")
    rows = {r["image"]: r for r in read_manifest(tmp_path).to_dict("records")}
    assert resolve_pixel_size(p, manifest_row=rows["a.png"])[:2] == (0.9, "manifest")
    assert resolve_pixel_size(p, manifest_row=rows["b.png"])[:2] == (0.56, "magnification")
    assert resolve_pixel_size(p, manifest_row=rows["c.png"], pixel_size_um=1.7)[:2] == (1.7, "cli")
    assert resolve_pixel_size(p)[:2] == (config.DEFAULT_PIXEL_SIZE_UM, "default")
    with pytest.raises(InputError, match="pixel_size_um"):
        resolve_pixel_size(p, pixel_size_um=-1.0)


def test_magnification_table():
    assert [magnification_pixel_size(m) for m in (100, 200, 500)] == [2.78, 1.43, 0.56]
    assert magnification_pixel_size(350) is None and magnification_pixel_size(None) is None


def test_manifest_without_image_column(tmp_path):
    pd.DataFrame({"file": ["a.png"]}).to_csv(tmp_path / "manifest.csv", index=False)
    with pytest.raises(InputError, match="'image' column"):
        read_manifest(tmp_path)

"""Stage 1: read SEM images and find their pixel size; atomic file writes.

Pixel-size sources, first found wins (:func:`resolve_pixel_size`):

1. ``manifest`` — the ``pixel_size_um`` column of ``manifest.csv`` beside the images;
2. ``metadata`` — SEM TIFF tags: Zeiss ``CZ_SEM`` (tag 34118, ``ap_image_pixel_size`` or
   ``ap_pixel_size``) or FEI/Thermo ``FEI_HELIOS``/``FEI_SFEG`` (tags 34682/34680,
   ``[Scan] PixelWidth`` in m);
3. ``magnification`` — the manifest's ``magnification`` column (or the TIFF's magnification)
   through :data:`semkit.config.MAGNIFICATION_TABLE_UM`;
4. ``cli`` — the value given by the user (``--pixel-size-um``);
5. ``default`` — :data:`semkit.config.DEFAULT_PIXEL_SIZE_UM` (1 µm), flagged as such.
"""
from __future__ import annotations

import dataclasses
import math
import os
import pathlib
import tempfile

import numpy as np
import pandas as pd

from . import config
from .errors import InputError

__all__ = ["LoadedImage", "read_image", "to_grey", "working_grey", "invert_grey", "tiff_pixel_size",
           "magnification_pixel_size", "read_manifest", "resolve_pixel_size", "load_image",
           "write_image", "write_csv_atomic", "list_images", "list_folder"]

_UNIT_UM = {"m": 1e6, "mm": 1e3, "um": 1.0, "µm": 1.0, "nm": 1e-3, "pm": 1e-6}


@dataclasses.dataclass
class LoadedImage:
    """An image read from disk with its pixel size and where that size came from."""

    image: np.ndarray
    pixel_size_um: float
    pixel_size_source: str
    magnification: float | None = None


def invert_grey(image) -> np.ndarray:
    """Invert a grey image in its dtype's range (bright cracks become dark ones).

    Integers: ``max - I`` with the dtype's maximum; floats: ``min + max - I`` (the image's own
    range).

    Examples
    --------
    >>> invert_grey(np.array([[0, 200]], np.uint8)).tolist()
    [[255, 55]]
    >>> invert_grey(np.array([[0.5, 2.0]])).tolist()
    [[2.0, 0.5]]
    """
    a = np.asarray(image)
    if np.issubdtype(a.dtype, np.integer):
        return (np.iinfo(a.dtype).max - a).astype(a.dtype)
    return (a.min() + a.max() - a).astype(a.dtype)


def to_grey(image) -> np.ndarray:
    """Convert an RGB(A) or grey array to a 2-D grey array, keeping the dtype's range.

    Parameters
    ----------
    image : (M, N) or (M, N, 3|4) ndarray

    Returns
    -------
    grey : (M, N) ndarray, same dtype family (luminance 0.299 R + 0.587 G + 0.114 B).

    Examples
    --------
    >>> to_grey(np.full((2, 2, 3), 100, np.uint8)).tolist()
    [[100, 100], [100, 100]]
    """
    a = np.asarray(image)
    if a.ndim == 2:
        return a
    if a.ndim == 3 and a.shape[2] in (3, 4):
        g = a[..., :3].astype(np.float64) @ np.array([0.299, 0.587, 0.114])
        if np.issubdtype(a.dtype, np.integer):
            return np.clip(np.rint(g), 0, np.iinfo(a.dtype).max).astype(a.dtype)
        return g.astype(a.dtype)
    if a.ndim == 3 and a.shape[2] == 1:
        return a[..., 0]
    raise InputError(f"image: expected a 2-D grey or RGB array, got shape {a.shape}")


def working_grey(image) -> np.ndarray:
    """The grey image on the scale semkit's stages work in.

    Unsigned integers stay as they are. An image with negative greys (signed CT numbers,
    background-subtracted floats) is shifted so that its darkest pixel is 0 (float32): the
    illumination model is multiplicative, so grey 0 must mean black. A float image whose greys
    all lie within 0..1 (normalised data, ImageJ 32-bit) is scaled to 0..255: the stages' few
    absolute floors (contrast 1e-3, histogram bin widths) assume greys of a few units.

    Examples
    --------
    >>> working_grey(np.array([[0.0, 0.5], [1.0, 0.2]])).tolist()
    [[0.0, 127.5], [255.0, 51.0]]
    >>> working_grey(np.array([[-100, 0], [20, -50]], np.int16)).tolist()
    [[0.0, 100.0], [120.0, 50.0]]
    """
    a = np.asarray(image)
    if a.dtype.kind == "u" or a.size == 0:
        return a
    lo = a.min()
    if lo < 0:
        return (a.astype(np.float64) - float(lo)).astype(np.float32)
    if a.dtype.kind == "f" and a.max() <= 1.0:
        return a * a.dtype.type(255.0)
    return a


def read_image(path) -> np.ndarray:
    """Read a PNG/JPG/BMP or 8/16-bit TIFF as a 2-D grey array.

    Raises
    ------
    InputError
        Unsupported suffix, unreadable/corrupt file, empty image, or not 8/16-bit/float.
    """
    path = pathlib.Path(path)
    suf = path.suffix.lower()
    if suf not in config.IMAGE_SUFFIXES:
        raise InputError(f"{path.name}: unsupported format {suf!r}; expected one of "
                         f"{', '.join(config.IMAGE_SUFFIXES)}")
    try:
        if suf in (".tif", ".tiff"):
            a = _read_tiff(path)
        else:
            a = _read_cv2(path)
            if a is None:
                raise ValueError("decoder returned nothing")
    except InputError:
        raise
    except Exception as e:  # noqa: BLE001 (any decoder failure is a bad file)
        raise InputError(f"{path.name}: cannot read image ({type(e).__name__}: {e})") from None
    a = np.squeeze(a)
    if a.ndim == 3 and a.shape[0] in (3, 4) and a.shape[2] not in (3, 4):
        a = np.moveaxis(a, 0, -1)  # planar RGB TIFF
    a = to_grey(a) if a.ndim == 3 else a
    if a.ndim != 2 or a.size == 0 or min(a.shape) < 8:
        raise InputError(f"{path.name}: expected a 2-D image of at least 8 x 8 px, got shape "
                         f"{a.shape}")
    if a.dtype == bool or not (np.issubdtype(a.dtype, np.integer)
                               or np.issubdtype(a.dtype, np.floating)):
        raise InputError(f"{path.name}: unsupported pixel type {a.dtype}")
    return a


def _read_tiff(path):
    """The first page of a TIFF: tifffile (with imagecodecs for LZW, Deflate, JPEG, ...);
    when tifffile cannot decode it, OpenCV's libtiff; the first error when both fail."""
    import tifffile
    try:
        with tifffile.TiffFile(path) as tif:
            return tif.pages.first.asarray()
    except Exception as e:  # noqa: BLE001 (a codec tifffile lacks may be in libtiff)
        a = _read_cv2(path)
        if a is None:
            raise e from None
        return a


def _read_cv2(path):
    """An image file through OpenCV, channels as RGB(A); None when it cannot decode it."""
    import cv2
    a = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if a is not None and a.ndim == 3:
        a = a[..., [2, 1, 0] + ([3] if a.shape[2] == 4 else [])]  # BGR -> RGB
    return a


def _parse_length_um(value, unit):
    try:
        v = float(value)
    except (TypeError, ValueError):
        return None
    f = _UNIT_UM.get(str(unit).strip().replace("μ", "µ"))
    return v * f if f and v > 0 else None


def _parse_mag(value):
    """'200 X', '1.00 K X', 200 -> 200.0 (None if unparseable)."""
    if isinstance(value, (int, float)):
        return float(value) if value > 0 else None
    s = str(value).upper().replace("X", "").strip()
    mult = 1.0
    if s.endswith("K"):
        mult, s = 1000.0, s[:-1].strip()
    try:
        v = float(s) * mult
    except ValueError:
        return None
    return v if v > 0 else None


def tiff_pixel_size(path):
    """Pixel size and magnification from SEM TIFF tags (Zeiss CZ_SEM, FEI/Thermo).

    Returns
    -------
    pixel_size_um : float or None
    magnification : float or None
    """
    import tifffile
    try:
        with tifffile.TiffFile(path) as tif:
            sem = tif.sem_metadata
            fei = tif.fei_metadata
    except Exception:  # noqa: BLE001
        return None, None
    px, mag = None, None
    if sem:
        for key in ("ap_image_pixel_size", "ap_pixel_size"):
            v = sem.get(key)
            if isinstance(v, tuple) and len(v) >= 3:
                px = _parse_length_um(v[1], v[2])
                if px:
                    break
        v = sem.get("ap_mag")
        if isinstance(v, tuple) and len(v) >= 2:
            mag = _parse_mag(v[1] if len(v) == 2 else f"{v[1]} {v[2]}")
    if fei and px is None:
        for sec in ("Scan", "EScan", "Image"):
            s = fei.get(sec) or {}
            if "PixelWidth" in s:
                px = _parse_length_um(s["PixelWidth"], "m")
                if px:
                    break
        s = fei.get("Image") or {}
        if mag is None and "Magnification" in s:
            mag = _parse_mag(s["Magnification"])
    return px, mag


def magnification_pixel_size(magnification):
    """Pixel size (µm) from the magnification table, or None if the value is not in it.

    Examples
    --------
    >>> magnification_pixel_size(200)
    1.43
    """
    if magnification is None:
        return None
    try:
        m = float(magnification)
    except (TypeError, ValueError):
        return None
    for k, v in config.MAGNIFICATION_TABLE_UM.items():
        if math.isclose(m, k, rel_tol=1e-6):
            return v
    return None


def read_manifest(folder) -> pd.DataFrame | None:
    """Read ``manifest.csv`` in ``folder`` (None if absent); checks its ``image`` column."""
    p = pathlib.Path(folder) / "manifest.csv"
    if not p.is_file():
        return None
    try:
        m = pd.read_csv(p)
    except Exception as e:  # noqa: BLE001
        raise InputError(f"{p}: cannot read CSV ({e})") from None
    if "image" not in m.columns:
        raise InputError(f"{p}: expected an 'image' column, got {list(m.columns)}")
    for col in ("pixel_size_um", "magnification"):
        if col in m.columns:
            m[col] = pd.to_numeric(m[col], errors="coerce")
    return m


def resolve_pixel_size(path, *, manifest_row=None, pixel_size_um=None):
    """Choose the pixel size of one image; see the module docstring for the order.

    Returns
    -------
    pixel_size_um : float
    source : {"manifest", "metadata", "magnification", "cli", "default"}
    magnification : float or None
    """
    mag = None
    if manifest_row is not None:
        v = manifest_row.get("pixel_size_um")
        mag = manifest_row.get("magnification")
        mag = None if mag is None or pd.isna(mag) else float(mag)
        if v is not None and not pd.isna(v) and v > 0:
            return float(v), "manifest", mag
    path = pathlib.Path(path)
    if path.suffix.lower() in (".tif", ".tiff"):
        px, tmag = tiff_pixel_size(path)
        if px:
            return px, "metadata", tmag
        mag = mag or tmag
    px = magnification_pixel_size(mag)
    if px:
        return px, "magnification", mag
    if pixel_size_um is not None:
        if not pixel_size_um > 0:
            raise InputError(f"pixel_size_um: expected a positive number, got {pixel_size_um}")
        return float(pixel_size_um), "cli", mag
    return config.DEFAULT_PIXEL_SIZE_UM, "default", mag


def load_image(path, *, manifest_row=None, pixel_size_um=None) -> LoadedImage:
    """Read an image and resolve its pixel size (stage 1)."""
    image = read_image(path)
    px, src, mag = resolve_pixel_size(path, manifest_row=manifest_row, pixel_size_um=pixel_size_um)
    return LoadedImage(image, px, src, mag)


def list_images(folder):
    """Sorted image files of ``folder`` (suffix in ``config.IMAGE_SUFFIXES``).

    See Also
    --------
    list_folder : the images and the other files apart.
    """
    return list_folder(folder)[0]


def list_folder(folder):
    """The image files of ``folder`` and its other (non-hidden) files, each sorted.

    Returns
    -------
    images, others : list of pathlib.Path
        ``others`` leaves out ``manifest.csv``.
    """
    folder = pathlib.Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: expected a folder of images")
    files = sorted(p for p in folder.iterdir() if p.is_file() and not p.name.startswith("."))
    images = [p for p in files if p.suffix.lower() in config.IMAGE_SUFFIXES]
    others = [p for p in files if p not in images and p.name != "manifest.csv"]
    return images, others


def _atomic(path, write):
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp" + path.suffix,
                               dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o644)  # mkstemp makes 0600; results are meant to be shared
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_csv_atomic(df: pd.DataFrame, path) -> None:
    """Write a CSV through a temporary file and ``os.replace`` (never half-written)."""
    _atomic(path, lambda tmp: df.to_csv(tmp, index=False))


def write_image(path, image) -> None:
    """Write PNG/TIFF/JPG atomically (PNG and TIFF keep 16 bits)."""
    path = pathlib.Path(path)

    def w(tmp):
        if path.suffix.lower() in (".tif", ".tiff"):
            import tifffile
            tifffile.imwrite(tmp, image)
        else:
            import cv2
            a = image[..., ::-1] if image.ndim == 3 else image
            ext = path.suffix.lower()
            ok, buf = cv2.imencode(ext, np.ascontiguousarray(a))
            if not ok:
                raise InputError(f"{path.name}: cannot encode image as {ext}")
            buf.tofile(tmp)
    _atomic(path, w)

"""Stages 1-6 put together: one image (:func:`analyse_image`) or a folder (:func:`analyse_folder`).

:class:`CrackAnalysis` computes each stage lazily on first access (``functools.cached_property``)
so a stage whose output is not asked for never runs: without ``length`` there is no skeleton;
an overlay-free run never draws. A later stage (grains, classification) is added as one more
cached property plus an option, and merges its columns in :meth:`CrackAnalysis.crack_rows` /
:meth:`CrackAnalysis.summary`.

Folder runs use worker processes (``jobs``) with a tqdm bar; ``images.csv`` and ``cracks.csv``
are rewritten atomically as images finish, so an interrupted run keeps what it finished. A failed
image becomes a row of ``images.csv`` with its ``error`` and the batch goes on.
"""
from __future__ import annotations

import dataclasses
import functools
import os
import pathlib
import time
from concurrent.futures import ProcessPoolExecutor, as_completed

import numpy as np
import pandas as pd

from . import config
from .errors import InputError

__all__ = ["AnalysisOptions", "CrackAnalysis", "analyse_image", "analyse_file",
           "analyse_folder", "IMAGE_COLUMNS"]

#: images.csv columns (DESIGN.md §4) in order; more follow.
IMAGE_COLUMNS = ["image", "pixel_size_um", "pixel_size_source", "threshold_method",
                 "threshold_value", "n_cracks", "crack_area_um2", "crack_length_um",
                 "area_T_um2", "area_S_um2", "P", "seconds"]
_EXTRA_IMAGE_COLUMNS = ["image_area_um2", "crack_area_fraction", "crack_density_per_mm",
                        "threshold_ok", "threshold_note", "n_thin", "n_pores", "pore_area_um2",
                        "width_px", "height_px", "flatten", "despeckle", "error"]


@dataclasses.dataclass(frozen=True)
class AnalysisOptions:
    """Options of the crack pipeline; each maps 1:1 to a CLI flag (kebab-case).

    Attributes
    ----------
    threshold : str
        ``auto`` (default), ``otsu``, ``local`` or ``manual:VALUE`` (see :mod:`semkit.threshold`).
    flatten : str
        Illumination flattening: ``polynomial`` (default), ``gaussian`` or ``none``.
    denoise_sigma_px : float
        Gaussian denoising of the grey image before thresholding, px (0 = off).
    despeckle : str
        ``specks`` (default: remove isolated compact specks only), ``median`` (ImageJ 3 x 3
        median on the binary: erases 1-px cracks) or ``none``.
    min_area_um2 : float or None
        Remove objects smaller than this (µm²) after despeckling.
    max_hole_px : int or None
        Fill enclosed holes up to this area (px); None fills all (ImageJ).
    length : bool
        Skeletonise and measure lengths (``--no-length`` skips the skeleton).
    exclude_pores : bool
        Report round compact objects as pores, not cracks.
    bridge_gaps : bool
        Close 1-px gaps along thin cracks (3 x 3 closing) so a 1-px crack whose blurred core
        dips under the detection level stays one object.
    """

    threshold: str = "auto"
    flatten: str = "polynomial"
    denoise_sigma_px: float = config.DENOISE_SIGMA_PX
    despeckle: str = "specks"
    min_area_um2: float | None = None
    max_hole_px: int | None = config.FILL_HOLES_MAX_PX
    length: bool = True
    exclude_pores: bool = True
    bridge_gaps: bool = True
    # --- issue #3 stages (semkit.classify / grains / damage) ---
    classify: bool = True           # type_post, confidence, features, area_T/area_S/P
    crack_model: str | None = None  # JSON model from `semkit classify --train` (default built in)
    grains: bool = False            # phases, grains, type_pre, grains.csv
    minerals: str | None = None     # names brightest-first ("a,b,c") or a number of phases
    # --- end issue #3 ---

    def __post_init__(self):
        from .threshold import parse_method
        parse_method(self.threshold)
        # --- issue #3 ---
        if self.crack_model is not None:
            from .classify import load_model
            load_model(self.crack_model)
        if self.minerals is not None:
            from .grains import parse_minerals
            parse_minerals(self.minerals)
        # --- end issue #3 ---
        if self.flatten not in ("polynomial", "gaussian", "none"):
            raise InputError(f"flatten: expected polynomial, gaussian or none, "
                             f"got {self.flatten!r}")
        if self.despeckle not in ("specks", "median", "none"):
            raise InputError(f"despeckle: expected specks, median or none, got {self.despeckle!r}")
        if not (self.denoise_sigma_px >= 0):
            raise InputError(f"denoise_sigma_px: expected >= 0, got {self.denoise_sigma_px}")
        if self.min_area_um2 is not None and not self.min_area_um2 >= 0:
            raise InputError(f"min_area_um2: expected >= 0, got {self.min_area_um2}")


class CrackAnalysis:
    """Lazy crack analysis of one grey image (stages 2-6); each attribute is one stage.

    Notation: M x N image, n objects after cleaning (cracks and pores), labels 1..n.

    Attributes (computed on first access)
    -------------------------------------
    flat, field : (M, N) float32
        Flattened image and illumination field (stage 2).
    smooth : (M, N) float32
        Denoised flattened image.
    thresholded : ThresholdResult
        Stage 3.
    object_mask, area_mask : (M, N) bool
        Cleaned objects (stage 4) and the pixels counted for area.
    labels : (M, N) int32 ; n_objects : int
        Crack (and pore) objects (stage 5). ``crack_labels`` has pores removed.
    skeleton : (M, N) bool
        Thin skeleton of ``object_mask`` (stage 6; only when ``options.length``).
    objects : DataFrame
        One row per object (:func:`semkit.measure.crack_table`), ``is_pore`` flags pores.
    cracks : DataFrame
        ``objects`` without pores, with the object label in ``crack_id``.
    """

    def __init__(self, image, *, pixel_size_um=config.DEFAULT_PIXEL_SIZE_UM,
                 pixel_size_source="cli", name="", options=None):
        from .io import to_grey
        img = to_grey(np.asarray(image))
        if img.ndim != 2 or img.size == 0:
            raise InputError(f"{name or 'image'}: expected a non-empty 2-D image")
        if not np.isfinite(img).all() if img.dtype.kind == "f" else False:
            raise InputError(f"{name or 'image'}: image holds NaN or inf")
        if not pixel_size_um > 0:
            raise InputError(f"pixel_size_um: expected > 0, got {pixel_size_um}")
        self.image = img
        self.pixel_size_um = float(pixel_size_um)
        self.pixel_size_source = pixel_size_source
        self.name = name
        self.options = options or AnalysisOptions()

    # stage 2
    @functools.cached_property
    def _flat_field(self):
        from .illumination import flatten_illumination
        if self.options.flatten == "none":
            return self.image.astype(np.float32), np.ones(self.image.shape, np.float32)
        return flatten_illumination(self.image, method=self.options.flatten)

    @property
    def flat(self):
        return self._flat_field[0]

    @property
    def field(self):
        return self._flat_field[1]

    @functools.cached_property
    def smooth(self):
        from .cleanup import denoise
        return denoise(self.flat, sigma_px=self.options.denoise_sigma_px)

    # stage 3
    @functools.cached_property
    def thresholded(self):
        from .threshold import crack_mask
        img = self.smooth
        if float(np.ptp(img)) == 0.0:
            raise InputError(f"{self.name or 'image'}: image is uniform (no contrast)")
        return crack_mask(img, method=self.options.threshold)

    # stage 4
    @functools.cached_property
    def _masks(self):
        from . import cleanup
        t = self.thresholded
        det, area = t.detect_mask, t.mask
        if self.options.despeckle == "median":  # ImageJ: one binary, then a 3 x 3 median
            det = area = cleanup.despeckle_median(area)
        elif self.options.despeckle == "specks":
            det = cleanup.remove_specks(det)
        if self.options.min_area_um2:
            det = cleanup.remove_small_objects(
                det, min_area_px=self.options.min_area_um2 / self.pixel_size_um ** 2)
        if self.options.bridge_gaps:
            det = cleanup.bridge_gaps(det)
        filled = cleanup.fill_holes(det, max_hole_px=self.options.max_hole_px)
        area = (area & det) | (filled & ~det)
        return filled, area

    @property
    def object_mask(self):
        return self._masks[0]

    @property
    def area_mask(self):
        return self._masks[1]

    # stage 5
    @functools.cached_property
    def _labels(self):
        from .measure import label_cracks
        return label_cracks(self.object_mask)

    @property
    def labels(self):
        return self._labels[0]

    @property
    def n_objects(self):
        return self._labels[1]

    # stage 6
    @functools.cached_property
    def skeleton(self):
        from .skeleton import prune_spurs, skeletonize
        return prune_spurs(skeletonize(self.object_mask), self.object_mask)

    @functools.cached_property
    def objects(self):
        from .measure import crack_table, partial_volume_area
        t = crack_table(self.labels, self.n_objects, pixel_size_um=self.pixel_size_um,
                        skeleton=self.skeleton if self.options.length else None,
                        area_mask=self.area_mask, image_name=self.name)
        th = self.thresholded
        t["area_method"] = "count"
        if th.background is not None and t["thin"].any():
            # thin cracks never reach the midpoint: their area is their partial volume
            thin = t["thin"].to_numpy()
            ids = t["crack_id"].to_numpy()[thin]
            pv = partial_volume_area(self.smooth, self.labels, self.n_objects,
                                     background=th.background, crack_level=th.crack_level,
                                     ids=ids)
            px2 = self.pixel_size_um ** 2
            t.loc[thin, "area_px"] = pv[ids]
            t.loc[thin, "area_um2"] = pv[ids] * px2
            t.loc[thin, "mean_aperture_um"] = (pv[ids] / t.loc[thin, "length_px"].to_numpy()
                                               * self.pixel_size_um)
            t.loc[thin, "area_method"] = "partial_volume"
        return t

    @functools.cached_property
    def cracks(self):
        o = self.objects
        return o[~o["is_pore"]].reset_index(drop=True) if self.options.exclude_pores else o

    @functools.cached_property
    def crack_labels(self):
        """Labels of cracks only (pores set to 0); ids match ``cracks.crack_id``."""
        keep = np.zeros(self.n_objects + 1, bool)
        keep[self.cracks["crack_id"].to_numpy()] = True
        return np.where(keep[self.labels], self.labels, 0).astype(np.int32)

    def crack_rows(self) -> pd.DataFrame:
        """The rows this image contributes to ``cracks.csv``."""
        return self.cracks

    def summary(self) -> dict:
        """The row this image contributes to ``images.csv`` (``seconds`` is set by the caller)."""
        c = self.cracks
        o = self.objects
        pores = o[o["is_pore"]] if self.options.exclude_pores else o.iloc[:0]
        t = self.thresholded
        area = float(c["area_um2"].sum())
        image_area = float(self.image.size) * self.pixel_size_um ** 2
        nan = float("nan")
        # area_T/area_S/P (tensile and shear crack areas, P = A_T/A_S, Equ. 3-1) need the crack
        # types: they stay NaN here and are filled by the classification stage (issue #3).
        return dict(image=self.name, pixel_size_um=self.pixel_size_um,
                    pixel_size_source=self.pixel_size_source, threshold_method=t.method,
                    threshold_value=t.value, n_cracks=int(len(c)), crack_area_um2=area,
                    crack_length_um=float(c["length_um"].sum()) if self.options.length
                    else nan,
                    area_T_um2=nan, area_S_um2=nan, P=nan, seconds=nan,
                    image_area_um2=image_area, crack_area_fraction=area / image_area,
                    crack_density_per_mm=(float(c["length_um"].sum()) / image_area * 1e3
                                          if self.options.length else nan),
                    threshold_ok=bool(t.ok), threshold_note=t.note,
                    n_thin=int(c["thin"].sum()), n_pores=int(len(pores)),
                    pore_area_um2=float(pores["area_um2"].sum()),
                    width_px=int(self.image.shape[1]), height_px=int(self.image.shape[0]),
                    flatten=self.options.flatten, despeckle=self.options.despeckle, error="")


def analyse_image(image, *, pixel_size_um=config.DEFAULT_PIXEL_SIZE_UM, name="",
                  pixel_size_source="cli", **options) -> CrackAnalysis:
    """Analyse one grey image (lazy: stages run when their output is read).

    Parameters
    ----------
    image : (M, N) ndarray
        Grey (or RGB) image, cracks dark.
    pixel_size_um : float
    name : str
        Image name written in the tables.
    **options
        Fields of :class:`AnalysisOptions` (``threshold="auto"``, ``flatten=...``, ...).

    Returns
    -------
    analysis : CrackAnalysis
        ``analysis.cracks`` (per crack), ``analysis.summary()`` (per image),
        ``analysis.crack_labels`` and ``analysis.skeleton`` for later stages.

    Examples
    --------
    >>> img = np.full((64, 64), 180, np.uint8); img[20:24, 5:60] = 30
    >>> a = analyse_image(img, pixel_size_um=2.0, threshold="otsu", flatten="none")
    >>> len(a.cracks), float(a.cracks.area_um2.iloc[0])
    (1, 880.0)
    """
    return CrackAnalysis(image, pixel_size_um=pixel_size_um, pixel_size_source=pixel_size_source,
                         name=name, options=AnalysisOptions(**options))


def _failed_row(name, error, seconds):
    row = {c: np.nan for c in IMAGE_COLUMNS + _EXTRA_IMAGE_COLUMNS}
    row.update(image=name, error=error, seconds=seconds, n_cracks=0)
    return row


def analyse_file(path, *, manifest_row=None, pixel_size_um=None, overlay_dir=None,
                 options=None):
    """Analyse one image file; never raises for a bad image (the error goes in the row).

    Returns
    -------
    summary : dict
        The ``images.csv`` row (``error`` empty on success).
    cracks : DataFrame
        The ``cracks.csv`` rows.
    """
    from .io import load_image, write_image
    path = pathlib.Path(path)
    t0 = time.perf_counter()
    try:
        li = load_image(path, manifest_row=manifest_row, pixel_size_um=pixel_size_um)
        a = CrackAnalysis(li.image, pixel_size_um=li.pixel_size_um,
                          pixel_size_source=li.pixel_size_source, name=path.name,
                          options=options)
        cracks = a.crack_rows()
        row = a.summary()
        # --- issue #3: crack types, P, grains (semkit.damage.science_stage) ---
        from .damage import science_stage
        cracks, row = science_stage(a, cracks, row, manifest_row=manifest_row,
                                    overlay_dir=overlay_dir)
        # --- end issue #3 ---
        row["seconds"] = time.perf_counter() - t0
        if overlay_dir is not None:
            from .plot import overlay_cracks
            write_image(pathlib.Path(overlay_dir) / (path.stem + "_overlay.png"),
                        overlay_cracks(a.image, a.labels, pore_ids=a.objects.loc[
                            a.objects["is_pore"], "crack_id"].to_numpy()))
        return row, cracks
    except Exception as e:  # noqa: BLE001 (a failed image must not stop the batch)
        msg = str(e) if isinstance(e, InputError) else f"{type(e).__name__}: {e}"
        return _failed_row(path.name, msg.replace("\n", " "), time.perf_counter() - t0), None


def _write_tables(out, rows, cracks, order):
    from .io import write_csv_atomic
    imgs = pd.DataFrame([rows[k] for k in order if k in rows])
    cols = IMAGE_COLUMNS + [c for c in _EXTRA_IMAGE_COLUMNS if c in imgs.columns]
    cols += [c for c in imgs.columns if c not in cols]
    imgs = imgs.reindex(columns=cols)
    frames = [cracks[k] for k in order if cracks.get(k) is not None and len(cracks[k])]
    from .measure import CRACK_COLUMNS
    cr = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=CRACK_COLUMNS)
    write_csv_atomic(imgs, out / "images.csv")
    write_csv_atomic(cr, out / "cracks.csv")
    return imgs, cr


def _worker_init():
    """One OpenCV thread per worker process: the processes are the parallelism."""
    import cv2
    cv2.setNumThreads(1)


def analyse_folder(folder, out, *, jobs=None, progress=True, overlays=True, pixel_size_um=None,
                   labels=None, classes=None, **options):
    """Analyse every image of a folder; write ``images.csv``, ``cracks.csv`` and overlays.

    Parameters
    ----------
    folder : path
        Images (PNG/JPG/BMP/TIFF); ``manifest.csv`` beside them is used when present.
    out : path
        Output folder (created).
    jobs : int, optional
        Worker processes (default: CPU count, at most the number of images; 1 = in-process).
    progress : bool
        Show a tqdm progress bar.
    overlays : bool
        Write ``overlays/<name>_overlay.png``.
    pixel_size_um : float, optional
        Fallback pixel size (source ``cli``) when neither the manifest, the TIFF metadata nor
        the magnification gives one.
    labels : pandas.DataFrame, optional
        User crack labels ``image, crack_id, type`` (issue #3): they override the classified
        types, and P is recomputed.
    classes : str, optional
        Grain-size class edges for ``grains.csv`` (``"20,140"``, um; issue #3).
    **options
        Fields of :class:`AnalysisOptions`.

    Returns
    -------
    images : DataFrame
        One row per image (failed ones with ``error``).
    cracks : DataFrame
        One row per crack.

    Raises
    ------
    InputError
        ``folder`` is not a folder, holds no files, or its manifest is unreadable.
    """
    from .io import list_images, read_manifest
    folder = pathlib.Path(folder)
    out = pathlib.Path(out)
    opts = AnalysisOptions(**options)
    files = list_images(folder)
    if not files:
        raise InputError(f"{folder}: no image files found")
    man = read_manifest(folder)
    mrows = {}
    if man is not None:
        for r in man.to_dict("records"):
            mrows[str(r["image"])] = r
    out.mkdir(parents=True, exist_ok=True)
    ov = out / "overlays" if overlays else None
    order = [p.name for p in files]
    rows, cracks = {}, {}
    jobs = max(1, min(int(jobs or os.cpu_count() or 1), len(files)))
    kw = dict(pixel_size_um=pixel_size_um, overlay_dir=ov, options=opts)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(files), unit="img", desc="semkit analyse")
    last = 0.0
    try:
        if jobs == 1:
            for p in files:
                rows[p.name], cracks[p.name] = analyse_file(p, manifest_row=mrows.get(p.name), **kw)
                if bar:
                    bar.update()
                if time.monotonic() - last > 1.0:
                    _write_tables(out, rows, cracks, order)
                    last = time.monotonic()
        else:
            # forkserver: workers start from a clean process, never from a fork of one whose
            # OpenCV / numba thread pools are running (which can deadlock)
            import multiprocessing as mp
            ctx = mp.get_context("forkserver" if "forkserver" in mp.get_all_start_methods()
                                 else "spawn")
            with ProcessPoolExecutor(max_workers=jobs, mp_context=ctx,
                                     initializer=_worker_init) as ex:
                futs = {ex.submit(analyse_file, p, manifest_row=mrows.get(p.name), **kw): p.name
                        for p in files}
                for f in as_completed(futs):
                    name = futs[f]
                    try:
                        rows[name], cracks[name] = f.result()
                    except Exception as e:  # noqa: BLE001 (a worker died)
                        rows[name], cracks[name] = _failed_row(name, f"worker: {e}", np.nan), None
                    if bar:
                        bar.update()
                    if time.monotonic() - last > 1.0:
                        _write_tables(out, rows, cracks, order)
                        last = time.monotonic()
    finally:
        if bar:
            bar.close()
        # --- issue #3: per-image grain tables travel in cracks.attrs ---
        grain_tables = [cracks[k].attrs.get("grains") for k in order
                        if cracks.get(k) is not None]
        # --- end issue #3 ---
        images, cr = _write_tables(out, rows, cracks, order)
    # --- issue #3: labels, damage.csv, P_by_stage.png, grains.csv ---
    from .damage import write_science_outputs
    images, cr = write_science_outputs(out, images, cr, manifest=man, labels=labels,
                                       grain_tables=grain_tables, classes=classes)
    # --- end issue #3 ---
    return images, cr

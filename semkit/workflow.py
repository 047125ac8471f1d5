"""The folder loop: manifest -> load -> :class:`~semkit.analysis.CrackAnalysis` -> outputs.

:func:`analyse_folder` is the one loop over a folder of images; ``semkit analyse``, ``semkit
grains`` (:func:`analyse_grains_folder`), ``semkit classify --train``
(:func:`train_from_folder`) and ``gbmgen run`` all go through it or through
:func:`open_analysis`, the one place where a file and its manifest row become an analysis.

Folder runs use worker processes (``jobs``) with a tqdm bar; ``images.csv`` and ``cracks.csv``
are rewritten atomically as images finish (at most every ``CHECKPOINT_SECONDS``, and when the
run ends or is interrupted), so an interrupted run keeps what it finished. A failed image
becomes a row of ``images.csv`` with its ``error`` and the batch goes on.
"""
from __future__ import annotations

import os
import pathlib
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pandas as pd

from .analysis import EXTRA_IMAGE_COLUMNS, IMAGE_COLUMNS, CrackAnalysis
from .errors import InputError
from .io import list_folder, load_image, read_manifest, write_image
from .options import AnalysisOptions
from .outputs import write_science_outputs, write_tables

__all__ = ["open_analysis", "analyse_file", "analyse_folder", "analyse_grains_folder",
           "train_from_folder"]

#: the tables of a running folder are rewritten at most this often (s): the whole-table rewrite
#: runs in the parent process, beside the workers, so it must stay rare
CHECKPOINT_SECONDS = 10.0


def open_analysis(path, *, manifest_row=None, pixel_size_um=None, options=None, seed=None):
    """Load one image file and return its (lazy) analysis.

    Parameters
    ----------
    path : path
    manifest_row : dict, optional
        Its ``manifest.csv`` row (pixel size, magnification, loading stage).
    pixel_size_um : float, optional
        Fallback pixel size (source ``cli``).
    options : AnalysisOptions, optional
    seed : int, optional
        Seed of the grain stage.

    Returns
    -------
    analysis : CrackAnalysis
    """
    path = pathlib.Path(path)
    li = load_image(path, manifest_row=manifest_row, pixel_size_um=pixel_size_um)
    stage = None if manifest_row is None else manifest_row.get("stage")
    return CrackAnalysis(li.image, pixel_size_um=li.pixel_size_um,
                         pixel_size_source=li.pixel_size_source, name=path.name,
                         options=options, stage=stage, seed=seed)


def _failed_row(name, error, seconds):
    row = {c: np.nan for c in IMAGE_COLUMNS + EXTRA_IMAGE_COLUMNS}
    row.update(image=name, error=error, seconds=seconds, n_cracks=0)
    return row


def analyse_file(path, *, manifest_row=None, pixel_size_um=None, overlay_dir=None,
                 grain_map_dir=None, mask_dir=None, options=None, seed=None):
    """Analyse one image file; never raises for a bad image (the error goes in the row).

    Parameters
    ----------
    path : path
    manifest_row : dict, optional
    pixel_size_um : float, optional
    overlay_dir, grain_map_dir : path, optional
        Where ``<stem>_overlay.png`` and (with grains) ``<stem>_grains.png`` go.
    mask_dir : path, optional
        Where :func:`write_masks` writes the crack mask and label image.
    options : AnalysisOptions, optional
    seed : int, optional

    Returns
    -------
    summary : dict
        The ``images.csv`` row (``error`` empty on success).
    cracks : DataFrame or None
        The ``cracks.csv`` rows.
    grains : DataFrame or None
        The per-grain table (with grains).
    """
    path = pathlib.Path(path)
    t0, c0 = time.perf_counter(), time.process_time()
    try:
        a = open_analysis(path, manifest_row=manifest_row, pixel_size_um=pixel_size_um,
                          options=options, seed=seed)
        cracks = a.crack_rows()
        row = a.summary()
        row["seconds"] = time.perf_counter() - t0
        row["cpu_seconds"] = time.process_time() - c0
        if overlay_dir is not None:
            from .plot import overlay_cracks
            o = a.objects
            write_image(pathlib.Path(overlay_dir) / (path.stem + "_overlay.png"),
                        overlay_cracks(a.image, a.labels,
                                       pore_ids=o.loc[o["is_pore"], "crack_id"].to_numpy(),
                                       rejected_ids=a.rejected["crack_id"].to_numpy(),
                                       region=a.region.mask))
        if mask_dir is not None:
            write_masks(a, mask_dir, path.stem)
        grains = None
        if a.grain_map is not None:
            lab, ph, grains = a.grain_map
            if grain_map_dir is not None:
                import matplotlib.pyplot as plt

                from .grains import plot_grain_map
                pathlib.Path(grain_map_dir).mkdir(parents=True, exist_ok=True)
                plt.close(plot_grain_map(lab, ph, pathlib.Path(grain_map_dir)
                                         / f"{path.stem}_grains.png"))
        return row, cracks, grains
    except Exception as e:  # noqa: BLE001 (a failed image must not stop the batch)
        msg = str(e) if isinstance(e, InputError) else f"{type(e).__name__}: {e}"
        return _failed_row(path.name, msg.replace("\n", " "), time.perf_counter() - t0), None, \
            None


def write_masks(analysis, folder, stem):
    """``<stem>_cracks.png`` (0 background, 255 crack) and ``<stem>_labels.png`` (16-bit crack
    labels = ``crack_id`` of ``cracks.csv``; ``.tif`` 32-bit past 65535 cracks), in the raw
    image's size (a cropped data bar is 0).

    Parameters
    ----------
    analysis : CrackAnalysis
    folder : path
    stem : str
    """
    folder = pathlib.Path(folder)
    lab = analysis.full_size(analysis.crack_labels)
    write_image(folder / f"{stem}_cracks.png", np.where(lab > 0, 255, 0).astype(np.uint8))
    if lab.max() <= np.iinfo(np.uint16).max:
        write_image(folder / f"{stem}_labels.png", lab.astype(np.uint16))
    else:
        write_image(folder / f"{stem}_labels.tif", lab.astype(np.uint32))


#: glibc ``mallopt`` parameters: (M_TRIM_THRESHOLD, M_MMAP_THRESHOLD) and the values set.
_MALLOPT = ((-1, 1 << 30), (-3, 32 << 20))


def keep_freed_memory():
    """Let this process reuse the image-sized buffers it frees instead of returning them.

    Every stage allocates and frees image-sized arrays (megabytes each). glibc's defaults
    hand such blocks back to the kernel when they are freed, so the next one is faulted in
    and zeroed again page by page (3-11 % of the CPU, median 7 %, in five paired runs over
    20 of the speed benchmark's images in one process). Here freed heap memory is kept
    (trim threshold 1 GiB) and blocks up to 32 MiB come from the heap (``mallopt``), so a
    process analysing image after image stays at its peak footprint and reuses it.
    :func:`analyse_folder` sets it in its worker processes and in the calling process, which
    analyses images too; the setting lasts for the life of the process. Does nothing where
    the C library has no ``mallopt`` (not glibc).

    Returns
    -------
    bool
        Whether the settings were applied.
    """
    import ctypes
    import ctypes.util
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    return all(mallopt(param, value) == 1 for param, value in _MALLOPT)


def _worker_init():
    """One OpenCV thread per worker process (the processes are the parallelism); freed
    image buffers kept for the next image (:func:`keep_freed_memory`)."""
    import cv2
    cv2.setNumThreads(1)
    keep_freed_memory()


def _run_shared(files, jobs, kwargs_of, done):
    """Analyse ``files`` on ``jobs`` cores: ``jobs - 1`` worker processes and this one.

    The files are taken largest first (longest-processing-time-first: the last to finish are
    small, so no core idles long at the end). The workers are kept two images ahead
    (``Executor.submit``), never with the last file left, and between them this process
    takes the next file and analyses it itself: it has semkit imported already, so its core
    starts at once instead of waiting for one more worker to start (about 1 s: imports and
    numba's first loads). A pool that breaks (a worker killed) fails only the images it held;
    this process analyses the rest. ``done(name, result)`` is called in this thread, in the
    order results arrive.
    """
    import collections
    import multiprocessing as mp
    from concurrent.futures import FIRST_COMPLETED, wait
    from concurrent.futures.process import BrokenProcessPool

    import cv2
    # forkserver: workers start from a clean process, never from a fork of one whose
    # OpenCV / numba thread pools are running (which can deadlock)
    ctx = mp.get_context("forkserver" if "forkserver" in mp.get_all_start_methods()
                         else "spawn")
    todo = collections.deque(sorted(files, key=lambda p: -p.stat().st_size))
    ahead = 2 * (jobs - 1)
    running = {}
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)  # the processes are the parallelism, this one included
    try:
        with ProcessPoolExecutor(max_workers=jobs - 1, mp_context=ctx,
                                 initializer=_worker_init) as ex:
            broken = False

            def hand_out():
                nonlocal broken
                # the last file is left to this process (two files: one each)
                while len(todo) > 1 and not broken and len(running) < ahead:
                    p = todo.popleft()
                    try:
                        running[ex.submit(analyse_file, p, **kwargs_of(p))] = p
                    except BrokenProcessPool:
                        todo.appendleft(p)
                        broken = True

            def collect(fs):
                for f in fs:
                    p = running.pop(f)
                    try:
                        result = f.result()
                    except Exception as e:  # noqa: BLE001 (a worker died)
                        result = _failed_row(p.name, f"worker: {e}", np.nan), None, None
                    done(p.name, result)

            try:
                hand_out()
                while todo:
                    p = todo.popleft()
                    done(p.name, analyse_file(p, **kwargs_of(p)))
                    collect([f for f in list(running) if f.done()])
                    hand_out()
                while running:
                    collect(wait(list(running), return_when=FIRST_COMPLETED).done)
            except BaseException:  # interrupted: no worker starts another image
                ex.shutdown(wait=False, cancel_futures=True)
                raise
    finally:
        cv2.setNumThreads(threads)


def _preload_plotting():
    """Import matplotlib in a background thread while the workers run: the folder's figures
    (``P_by_stage.png``, grain histograms) need it at the end, when it would add its import time
    (~0.6 s) to the run."""
    import threading

    def load():  # the backend is left alone: the figures choose it when they are drawn
        import matplotlib.backends.backend_agg  # noqa: F401
        import matplotlib.figure  # noqa: F401

    threading.Thread(target=load, daemon=True).start()


def _manifest_rows(folder):
    man = read_manifest(folder)
    rows = {} if man is None else {str(r["image"]): r for r in man.to_dict("records")}
    return man, rows


def analyse_folder(folder, out, *, jobs=None, progress=True, overlays=True, pixel_size_um=None,
                   labels=None, classes=None, seed=None, crack_tables=True, save_masks=False,
                   **options):
    """Analyse every image of a folder; write the tables and figures of ``semkit analyse``.

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
        Write ``overlays/<name>_overlay.png`` (and with grains ``grain_maps/<name>_grains.png``).
    pixel_size_um : float, optional
        Fallback pixel size (source ``cli``) when neither the manifest, the TIFF metadata nor
        the magnification gives one.
    labels : pandas.DataFrame, optional
        User crack labels ``image, crack_id, type``: they override the classified types, and
        P is recomputed.
    classes : str, optional
        Grain-size class edges for ``grains.csv`` (``"20,140"``, um).
    seed : int, optional
        Seed of the grain stage.
    crack_tables : bool
        Write ``images.csv``, ``cracks.csv``, crack overlays and ``damage.csv`` (False: grain
        outputs only, ``semkit grains``).
    save_masks : bool
        Write ``masks/<stem>_cracks.png`` and ``masks/<stem>_labels.png`` (:func:`write_masks`).
    **options
        Fields of :class:`~semkit.options.AnalysisOptions`.

    Returns
    -------
    images : DataFrame
        One row per image (failed ones with ``error``); ``images.attrs["skipped"]`` lists the
        folder's other files (not images, not ``manifest.csv``), skipped.
    cracks : DataFrame
        One row per crack (and per rejected object, with ``rejected_as``).

    Raises
    ------
    InputError
        ``folder`` is not a folder, holds no image files, or its manifest is unreadable.
    """
    folder = pathlib.Path(folder)
    out = pathlib.Path(out)
    if not crack_tables:
        options["classify"] = False  # types are written nowhere without the crack tables
    opts = AnalysisOptions(**options)
    files, skipped = list_folder(folder)
    if not files:
        raise InputError(f"{folder}: no image files found")
    man, mrows = _manifest_rows(folder)
    out.mkdir(parents=True, exist_ok=True)
    kw = dict(pixel_size_um=pixel_size_um, options=opts, seed=seed,
              overlay_dir=out / "overlays" if overlays and crack_tables else None,
              grain_map_dir=out / "grain_maps" if overlays and opts.grains else None,
              mask_dir=out / "masks" if save_masks else None)
    order = [p.name for p in files]
    if (man is not None and crack_tables) or opts.grains:
        _preload_plotting()
    rows, cracks, grains = {}, {}, {}
    jobs = max(1, min(int(jobs or os.cpu_count() or 1), len(files)))
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(files), unit="img", desc="semkit analyse")
    last = time.monotonic()

    def done(name, result):
        nonlocal last
        rows[name], cracks[name], grains[name] = result
        if bar:
            bar.update()
        if crack_tables and time.monotonic() - last > CHECKPOINT_SECONDS:
            write_tables(out, rows, cracks, order)
            last = time.monotonic()

    keep_freed_memory()
    try:
        if jobs == 1:
            for p in files:
                done(p.name, analyse_file(p, manifest_row=mrows.get(p.name), **kw))
        else:
            _run_shared(files, jobs, lambda p: dict(kw, manifest_row=mrows.get(p.name)), done)
    finally:
        if bar:
            bar.close()
        if crack_tables:
            images, cr = write_tables(out, rows, cracks, order)
    if not crack_tables:
        images = pd.DataFrame([rows[k] for k in order if k in rows])
        cr = pd.concat([c for c in cracks.values() if c is not None and len(c)],
                       ignore_index=True) if any(c is not None and len(c)
                                                 for c in cracks.values()) else pd.DataFrame()
    images, cr = write_science_outputs(
        out, images, cr, manifest=man if crack_tables else None,
        labels=labels if crack_tables else None,
        grain_tables=[grains[k] for k in order if grains.get(k) is not None], classes=classes)
    images.attrs["skipped"] = [p.name for p in skipped]
    return images, cr


def analyse_grains_folder(folder, out, *, minerals=None, classes=None, pixel_size_um=None,
                          progress=False, seed=None, jobs=None, **options):
    """``semkit grains DIR``: grain map, per-grain table and ``grains.csv`` for a folder.

    Writes ``grains_per_grain.csv`` (every grain of every image), ``grains.csv`` (the
    grain-size table over all images), ``grain_maps/<name>_grains.png`` and
    ``grain_histograms.png`` to ``out``; no crack tables. Cracks are still detected: they are
    masked out before grains are measured.

    Parameters
    ----------
    folder, out : path
    minerals : str, optional
        ``--minerals`` value (names brightest-first, or a number of phases).
    classes : str, optional
        ``--classes`` value (``"20,140"``); default the automatic rule.
    pixel_size_um : float, optional
        Fallback pixel size.
    progress : bool
    seed : int, optional
    jobs : int, optional
    **options
        Crack-analysis options.

    Returns
    -------
    table : pandas.DataFrame
        The grain-size table written to ``grains.csv``.
    """
    options.update(grains=True, minerals=minerals)
    analyse_folder(folder, out, jobs=jobs, progress=progress, overlays=True,
                   pixel_size_um=pixel_size_um, classes=classes, seed=seed, crack_tables=False,
                   **options)
    path = pathlib.Path(out) / "grains.csv"
    if not path.exists():
        raise InputError(f"{folder}: no grains measured (every image failed)")
    return pd.read_csv(path)


def train_from_folder(folder, labels, *, pixel_size_um=None, seed=None, **options):
    """Fit a post-test model from ``labels.csv`` rows referring to a ``semkit analyse`` run.

    The images named in ``labels`` are re-analysed with the same options (crack ids are
    deterministic), and :func:`semkit.classify.train_post` fits the model on the labelled
    cracks.

    Parameters
    ----------
    folder : path
        The images (with ``manifest.csv`` if the analysis had one).
    labels : pandas.DataFrame
        ``image, crack_id, type`` (post-test types are used).
    pixel_size_um : float, optional
    seed : int, optional
    **options
        Fields of :class:`~semkit.options.AnalysisOptions`.

    Returns
    -------
    model : dict
    """
    from .classify import train_post
    folder = pathlib.Path(folder)
    post = labels[labels["type"].astype(str).isin(["tensile", "shear", "mixed"])]
    if post.empty:
        raise InputError("labels: no tensile/shear/mixed rows to train on")
    _, mrows = _manifest_rows(folder)
    opts = AnalysisOptions(**options)
    samples = []
    for name, g in post.groupby("image"):
        path = folder / str(name)
        if not path.is_file():
            raise InputError(f"labels: image {name!r} not found in {folder}")
        a = open_analysis(path, manifest_row=mrows.get(str(name)), pixel_size_um=pixel_size_um,
                          options=opts)
        samples.append((a.crack_labels, dict(zip(g["crack_id"].astype(int), g["type"])),
                        a.smooth))
    return train_post(samples, seed=seed)

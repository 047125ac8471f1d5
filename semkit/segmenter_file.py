"""Segmenter files: :func:`save_segmenter` / :func:`load_segmenter` (skops.io, no pickle) and
:func:`read_training_set` (image and label files for ``semkit train-segmenter``).

A segmenter file is a skops archive of one dict: ``format, version, features, threshold,
classes, training_images, label_counts, scores, seed, n_trees, max_depth`` and ``model`` (the
random forest). :func:`load_segmenter` reads the archive's type schema before anything is
built and refuses any type outside :data:`TRUSTED_TYPES`.
"""
from __future__ import annotations

import json
import os
import pathlib
import tempfile
import zipfile

import numpy as np

from .errors import InputError
from .segmenter import FORMAT, VERSION, Segmenter, labels_from_mask

__all__ = ["save_segmenter", "load_segmenter", "read_training_set", "TRUSTED_TYPES"]

#: Every type a segmenter file may contain (module.class as skops writes it in schema.json).
TRUSTED_TYPES = frozenset({
    "builtins.dict", "builtins.list", "builtins.tuple", "builtins.str", "builtins.int",
    "builtins.float", "builtins.bool", "builtins.NoneType",
    "numpy.ndarray", "numpy.dtype", "numpy.int64", "numpy.int32", "numpy.intp",
    "numpy.float64", "numpy.float32", "numpy.bool_",
    "sklearn.ensemble._forest.RandomForestClassifier",
    "sklearn.tree._classes.DecisionTreeClassifier",
    "sklearn.tree._tree.Tree",
})


def save_segmenter(segmenter, path):
    """Write a segmenter with :func:`skops.io.dump` (no pickle), atomically."""
    import skops.io as sio
    path = pathlib.Path(path)
    obj = segmenter.describe()
    obj["model"] = segmenter.model
    fd, tmp = tempfile.mkstemp(dir=path.parent if str(path.parent) else ".",
                               prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        sio.dump(obj, tmp, compression=zipfile.ZIP_DEFLATED)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def _file_types(path):
    """Every module.class named in a skops file's schema."""
    with zipfile.ZipFile(path) as z:
        schema = json.loads(z.read("schema.json"))
    found = set()
    stack = [schema]
    while stack:
        n = stack.pop()
        if isinstance(n, dict):
            if "__module__" in n and "__class__" in n:
                found.add(f"{n['__module__']}.{n['__class__']}")
            stack.extend(n.values())
        elif isinstance(n, list):
            stack.extend(n)
    return found


def load_segmenter(path, *, n_jobs=None):
    """Read a segmenter written by :func:`save_segmenter`, refusing any untrusted type.

    Raises
    ------
    InputError
        Missing or unreadable file, a type outside :data:`TRUSTED_TYPES`, or not a semkit
        segmenter.
    """
    import skops.io as sio
    path = pathlib.Path(path)
    if not path.is_file():
        raise InputError(f"{path}: segmenter file not found")
    try:
        types = _file_types(path)
    except (zipfile.BadZipFile, KeyError, ValueError, OSError) as e:
        raise InputError(f"{path}: not a skops segmenter file ({type(e).__name__})") from None
    bad = sorted(types - TRUSTED_TYPES)
    if bad:
        raise InputError(f"{path}: refusing to load untrusted type(s) {', '.join(bad)}")
    try:
        obj = sio.load(path, trusted=sorted(sio.get_untrusted_types(file=path)))
    except Exception as e:  # noqa: BLE001 (a damaged file of trusted types)
        raise InputError(f"{path}: cannot read segmenter ({type(e).__name__}: {e})") from None
    from sklearn.ensemble import RandomForestClassifier
    if (not isinstance(obj, dict) or obj.get("format") != FORMAT
            or not isinstance(obj.get("model"), RandomForestClassifier)):
        raise InputError(f"{path}: not a semkit segmenter (format {FORMAT!r} with a random "
                         "forest expected)")
    if obj.get("version") != VERSION:
        raise InputError(f"{path}: segmenter version {obj.get('version')!r}; this semkit "
                         f"reads version {VERSION}: retrain with semkit train-segmenter")
    feats = obj["features"]
    if feats.get("n_features") != obj["model"].n_features_in_:
        raise InputError(f"{path}: features record {feats.get('n_features')} features, the "
                         f"forest expects {obj['model'].n_features_in_}")
    return Segmenter(model=obj["model"], features=feats, threshold=float(obj["threshold"]),
                     classes=tuple(obj["classes"]), training_images=list(obj["training_images"]),
                     label_counts=dict(obj["label_counts"]), scores=dict(obj["scores"]),
                     seed=int(obj["seed"]), n_jobs=n_jobs)


def read_training_set(paths, labels_dir, *, binary_masks=False):
    """Images and their label images for :func:`semkit.segmenter.train_segmenter`.

    Parameters
    ----------
    paths : sequence of str or Path
        Image files and/or folders of images (every image of a folder that has a label file).
    labels_dir : str or Path
        Folder of label PNGs named like the images (``<stem>.png`` or ``<stem>_labels.png``):
        0 unlabelled, 1 crack, 2 not crack.
    binary_masks : bool
        The label files are painted crack masks (0 background, nonzero crack), converted by
        :func:`semkit.segmenter.labels_from_mask`.

    Returns
    -------
    images, labels, names : lists
        Grey images, label images (uint8 0/1/2) and image file names.
    skipped : list of str
        Images of the given folders without a label file.

    Raises
    ------
    InputError
        A missing path or label folder, an image given by name without a label file, a label
        image of another shape or with values other than 0, 1, 2, or no labelled image at all.
    """
    from .io import list_images, read_image
    labels_dir = pathlib.Path(labels_dir)
    if not labels_dir.is_dir():
        raise InputError(f"{labels_dir}: label folder not found")
    files, explicit = [], set()
    for p in map(pathlib.Path, paths):
        if p.is_dir():
            files.extend(list_images(p))
        elif p.is_file():
            files.append(p)
            explicit.add(p)
        else:
            raise InputError(f"{p}: no such image file or folder")
    images, labels, names, skipped = [], [], [], []
    for f in files:
        lab_path = next((c for c in (labels_dir / f"{f.stem}.png",
                                     labels_dir / f"{f.stem}_labels.png") if c.is_file()), None)
        if lab_path is None:
            if f in explicit:
                raise InputError(f"{f.name}: no label file {f.stem}.png in {labels_dir}")
            skipped.append(f.name)
            continue
        img = read_image(f)
        lab = read_image(lab_path)
        if lab.shape != img.shape:
            raise InputError(f"{lab_path.name}: label image shape {lab.shape} differs from "
                             f"{f.name} {img.shape}")
        if binary_masks:
            lab = labels_from_mask(img, lab > 0)
        elif lab.max() > 2:
            raise InputError(f"{lab_path.name}: label values must be 0 (unlabelled), "
                             f"1 (crack) or 2 (not crack); found {int(lab.max())} (use "
                             "--binary-masks for painted 0/255 masks)")
        images.append(img)
        labels.append(np.asarray(lab, np.uint8))
        names.append(f.name)
    if not images:
        raise InputError(f"{labels_dir}: no image has a label file")
    return images, labels, names, skipped

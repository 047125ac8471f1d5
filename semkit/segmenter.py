"""Trainable pixel classifier for cracks (a random forest on multi-scale filter features).

What Fiji's Trainable Weka Segmentation and ilastik users do for a new microscope or rock: label
a few pixels (scribbles) or whole masks, train, and segment the rest. Labels are images with
0 = unlabelled, 1 = crack, 2 = not crack. Every pixel is described by
:func:`skimage.feature.multiscale_basic_features` (Gaussian-smoothed intensity, gradient
magnitude and the two Hessian eigenvalues at ``num_sigma`` scales from ``sigma_min`` to
``sigma_max``) and a scikit-learn :class:`~sklearn.ensemble.RandomForestClassifier` gives
P(crack) per pixel.

Models are stored with :mod:`skops.io` (no pickle). :func:`load_segmenter` reads the file's type
schema first and refuses any type outside :data:`TRUSTED_TYPES` (the builtin containers, numpy
arrays and scalars, and the three scikit-learn types of a random forest).

Module constants (documented defaults of :func:`train_segmenter`):

- ``SIGMA_MIN_PX, SIGMA_MAX_PX = 0.5, 8``: five scales 0.5-8 px, 20 features. Cracks of 1-10 px
  are resolved; larger scales add cost (the Gaussian grows with sigma) and, near a sample's
  edge, mix the surround into every pixel's description.
- ``SAMPLES_PER_CLASS = 10000`` pixels of each kind per image: crack, not crack, and
  "hard" not crack (not-crack pixels darker than their local background, i.e. what a crack
  detector confuses with cracks: halos, dark grains, a sample's rim). Sampling keeps training
  fast and the forest small, and balances the rare crack class.
- ``N_TREES = 50``, ``MAX_DEPTH = 16``, ``MIN_SAMPLES_LEAF = 5``: a model of a few MB.
- ``TILE_ROWS = 256``: features are computed in bands of rows with a halo of 4 sigma_max, so
  memory stays bounded on large images and the result equals the whole-image computation.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError

__all__ = ["Segmenter", "train_segmenter", "labels_from_mask", "segmenter_features", "FORMAT",
           "VERSION"]

FORMAT = "semkit.segmenter"
VERSION = 1
CRACK, NOT_CRACK = 1, 2
CLASSES = ("unlabelled", "crack", "not_crack")
SIGMA_MIN_PX = 0.5
SIGMA_MAX_PX = 8.0
SAMPLES_PER_CLASS = 10000
N_TREES = 50
MAX_DEPTH = 16
MIN_SAMPLES_LEAF = 5
TILE_ROWS = 256
#: labels_from_mask: crack = painted and at least this much darker than the local background
#: (relative to it); the background is a median over BACKGROUND_PX.
MIN_CONTRAST = 0.15
BACKGROUND_PX = 15
#: labels_from_mask: not crack = farther than this from any painted pixel.
FAR_PX = 3.0
_TREES_PER_STEP = 10



def _as_unit_float(grey):
    """Grey image -> float32 in [0, 1] by its dtype's range (floats are taken as they are)."""
    g = np.asarray(grey)
    if g.ndim != 2:
        raise InputError(f"image: expected a 2-D grey array, got shape {g.shape}")
    if np.issubdtype(g.dtype, np.integer):
        return g.astype(np.float32) / np.float32(np.iinfo(g.dtype).max)
    if np.issubdtype(g.dtype, np.floating):
        return g.astype(np.float32)
    raise InputError(f"image: unsupported pixel type {g.dtype}")


def _feature_settings(sigma_min, sigma_max, num_sigma):
    if not 0 < sigma_min <= sigma_max:
        raise InputError(f"sigma_min/sigma_max: expected 0 < sigma_min <= sigma_max, got "
                         f"{sigma_min}, {sigma_max}")
    if num_sigma is None:
        num_sigma = int(np.log2(sigma_max / sigma_min) + 1)
    return {"function": "skimage.feature.multiscale_basic_features", "intensity": True,
            "edges": True, "texture": True, "sigma_min": float(sigma_min),
            "sigma_max": float(sigma_max), "num_sigma": int(num_sigma),
            "grey_scale": "dtype range to [0, 1]", "n_features": 4 * int(num_sigma)}


def segmenter_features(grey, features, *, tile_rows=TILE_ROWS, workers=None):
    """Per-pixel features of a grey image, computed in bands of rows.

    Parameters
    ----------
    grey : (M, N) ndarray
        Integers are scaled by their dtype's range to [0, 1]; floats are used as they are.
    features : dict
        Feature settings (``Segmenter.features``).
    tile_rows : int
        Rows per band; each band is computed with a halo of ``4 sigma_max + 2`` rows, so the
        result equals the whole-image computation.
    workers : int, optional
        Threads for the scales (``multiscale_basic_features(workers=)``).

    Returns
    -------
    F : (M, N, K) ndarray of float32
    """
    from skimage.feature import multiscale_basic_features
    g = _as_unit_float(grey)
    kw = dict(intensity=features["intensity"], edges=features["edges"],
              texture=features["texture"], sigma_min=features["sigma_min"],
              sigma_max=features["sigma_max"], num_sigma=features["num_sigma"],
              workers=workers)
    halo = int(np.ceil(4 * features["sigma_max"])) + 2
    out = np.empty(g.shape + (features["n_features"],), np.float32)
    for r0 in range(0, g.shape[0], tile_rows):
        r1 = min(r0 + tile_rows, g.shape[0])
        a, b = max(r0 - halo, 0), min(r1 + halo, g.shape[0])
        f = multiscale_basic_features(g[a:b], **kw)
        out[r0:r1] = f[r0 - a:r0 - a + (r1 - r0)]
    return out


@dataclass
class Segmenter:
    """A trained crack / not-crack pixel classifier.

    Attributes
    ----------
    model : sklearn.ensemble.RandomForestClassifier
        Classes 1 (crack) and 2 (not crack).
    features : dict
        The settings of :func:`skimage.feature.multiscale_basic_features`.
    threshold : float
        Pixels with P(crack) >= threshold are cracks.
    classes : tuple of str
        Label values 0, 1, 2 in order.
    training_images : list of str
        Names of the training images.
    label_counts : dict
        Labelled and sampled pixels per class.
    scores : dict
        Out-of-bag pixel scores on the sampled training pixels (optimistic: neighbouring
        pixels of one image are correlated) and any held-out scores added by the caller.
    seed : int
    n_jobs : int or None
        Threads for prediction (not stored).
    """

    model: object
    features: dict
    threshold: float = 0.5
    classes: tuple = CLASSES
    training_images: list = field(default_factory=list)
    label_counts: dict = field(default_factory=dict)
    scores: dict = field(default_factory=dict)
    seed: int = 0
    n_jobs: int | None = None

    def crack_probability(self, grey, *, tile_rows=TILE_ROWS):
        """P(crack) per pixel.

        Parameters
        ----------
        grey : (M, N) ndarray

        Returns
        -------
        p : (M, N) ndarray of float32 in [0, 1]
        """
        F = segmenter_features(grey, self.features, tile_rows=tile_rows)
        k = list(self.model.classes_).index(CRACK)
        self.model.n_jobs = self.n_jobs
        p = np.empty(F.shape[:2], np.float32)
        for r0 in range(0, F.shape[0], tile_rows):
            band = F[r0:r0 + tile_rows]
            p[r0:r0 + tile_rows] = self.model.predict_proba(
                band.reshape(-1, band.shape[-1]))[:, k].reshape(band.shape[:2])
        return p

    def crack_mask(self, grey):
        """Boolean crack mask: ``crack_probability(grey) >= threshold``."""
        return self.crack_probability(grey) >= self.threshold

    def describe(self):
        """The model file's record without the forest (JSON-serialisable dict)."""
        return {"format": FORMAT, "version": VERSION, "features": dict(self.features),
                "threshold": float(self.threshold), "classes": list(self.classes),
                "training_images": list(self.training_images),
                "label_counts": dict(self.label_counts), "scores": dict(self.scores),
                "seed": int(self.seed), "n_trees": int(self.model.n_estimators),
                "max_depth": self.model.max_depth}


def labels_from_mask(grey, mask, *, min_contrast=MIN_CONTRAST, background_px=BACKGROUND_PX,
                     far_px=FAR_PX):
    """Training labels from a painted (full) crack mask.

    Hand-painted masks are often wider than the dark crack, so not every painted pixel is
    crack: crack (1) = painted and darker than the local background (median over
    ``background_px``) by at least ``min_contrast`` of it; not crack (2) = farther than
    ``far_px`` from any painted pixel; everything else is unlabelled (0).

    Parameters
    ----------
    grey : (M, N) ndarray
    mask : (M, N) array, nonzero = painted crack

    Returns
    -------
    labels : (M, N) ndarray of uint8 (0, 1, 2)

    Examples
    --------
    >>> g = np.full((9, 9), 200, np.uint8); g[:, 4] = 50
    >>> m = np.zeros((9, 9), bool); m[:, 3:6] = True
    >>> labels_from_mask(g, m, far_px=1)[4].tolist()
    [2, 2, 0, 0, 1, 0, 0, 2, 2]
    """
    from scipy import ndimage as ndi
    g = _as_unit_float(grey)
    m = np.asarray(mask) > 0
    if m.shape != g.shape:
        raise InputError(f"mask: expected shape {g.shape}, got {m.shape}")
    bg = ndi.median_filter(g, size=background_px)
    lab = np.zeros(g.shape, np.uint8)
    lab[m & (g <= bg * (1 - min_contrast))] = CRACK
    lab[ndi.distance_transform_edt(~m) > far_px] = NOT_CRACK
    return lab


def _hard_negatives(g, lab, *, min_contrast=MIN_CONTRAST, background_px=BACKGROUND_PX):
    """Not-crack pixels darker than their local background (what a detector would confuse)."""
    from scipy import ndimage as ndi
    bg = ndi.median_filter(g, size=background_px)
    return (lab == NOT_CRACK) & (g <= bg * (1 - min_contrast))


def _sample(rng, where, n):
    idx = np.flatnonzero(where.ravel())
    return idx if idx.size <= n else np.sort(rng.choice(idx, n, replace=False))


def train_segmenter(images, labels, *, names=None, sigma_min=SIGMA_MIN_PX,
                    sigma_max=SIGMA_MAX_PX, num_sigma=None, n_trees=N_TREES,
                    max_depth=MAX_DEPTH, min_samples_leaf=MIN_SAMPLES_LEAF,
                    samples_per_class=SAMPLES_PER_CLASS, threshold=0.5, n_jobs=None,
                    progress=False, seed=0):
    """Train a crack / not-crack random forest from labelled images.

    Parameters
    ----------
    images : sequence of (M, N) ndarray
        Grey images (uint8, uint16 or float in [0, 1]).
    labels : sequence of (M, N) ndarray of int
        0 unlabelled, 1 crack, 2 not crack (sparse scribbles or full masks; see
        :func:`labels_from_mask` for painted binary masks).
    names : sequence of str, optional
        Image names recorded in the model.
    sigma_min, sigma_max, num_sigma : float, float, int
        Scales of the features (``num_sigma`` default: ``log2(sigma_max/sigma_min) + 1``).
    n_trees, max_depth, min_samples_leaf : int
        Random-forest settings.
    samples_per_class : int
        Pixels drawn per image for each of crack, not crack, and hard not crack.
    threshold : float
        Decision threshold on P(crack) recorded in the model, in (0, 1) (``semkit analyse
        --segmenter-threshold`` overrides it per run).
    n_jobs : int, optional
        Worker threads for training and prediction.
    progress : bool
        tqdm bars over images and trees.
    seed : int

    Returns
    -------
    Segmenter

    Raises
    ------
    InputError
        Mismatched shapes, label values outside {0, 1, 2}, no pixel of a class, or a
        threshold outside (0, 1).
    """
    from sklearn.ensemble import RandomForestClassifier
    from tqdm.auto import tqdm
    images, labels = list(images), list(labels)
    names = [f"image_{i}" for i in range(len(images))] if names is None else list(names)
    if not images or len(images) != len(labels) or len(names) != len(images):
        raise InputError(f"labels: expected one label image per image, got {len(images)} "
                         f"images and {len(labels)} label images")
    if not n_trees >= 1 or not samples_per_class >= 1:
        raise InputError(f"n_trees, samples_per_class: expected >= 1, got {n_trees}, "
                         f"{samples_per_class}")
    if not 0.0 < threshold < 1.0:
        raise InputError(f"threshold: expected a probability in (0, 1), got {threshold}")
    feats = _feature_settings(sigma_min, sigma_max, num_sigma)
    rng = np.random.default_rng(seed)
    X, y = [], []
    counts = {"crack_labelled": 0, "not_crack_labelled": 0, "crack_sampled": 0,
              "not_crack_sampled": 0}
    for img, lab, name in tqdm(list(zip(images, labels, names)), desc="features",
                               disable=not progress, unit="image"):
        lab = np.asarray(lab)
        if lab.shape != np.shape(img):
            raise InputError(f"{name}: labels shape {lab.shape} != image shape "
                             f"{np.shape(img)}")
        if lab.size and (lab.min() < 0 or lab.max() > NOT_CRACK):
            raise InputError(f"{name}: label values must be 0 (unlabelled), 1 (crack) or "
                             f"2 (not crack); found {lab.max()}")
        g = _as_unit_float(img)
        F = segmenter_features(g, feats).reshape(-1, feats["n_features"])
        hard = _hard_negatives(g, lab)
        picks = [(_sample(rng, lab == CRACK, samples_per_class), CRACK),
                 (_sample(rng, (lab == NOT_CRACK) & ~hard, samples_per_class), NOT_CRACK),
                 (_sample(rng, hard, samples_per_class), NOT_CRACK)]
        for idx, c in picks:
            X.append(F[idx])
            y.append(np.full(idx.size, c, np.uint8))
        counts["crack_labelled"] += int((lab == CRACK).sum())
        counts["not_crack_labelled"] += int((lab == NOT_CRACK).sum())
    X, y = np.concatenate(X), np.concatenate(y)
    counts["crack_sampled"] = int((y == CRACK).sum())
    counts["not_crack_sampled"] = int((y == NOT_CRACK).sum())
    if counts["crack_sampled"] == 0 or counts["not_crack_sampled"] == 0:
        raise InputError("labels: need pixels of both classes (1 crack, 2 not crack); got "
                         f"{counts['crack_sampled']} crack, {counts['not_crack_sampled']} "
                         "not crack")
    rf = RandomForestClassifier(n_estimators=0, max_depth=max_depth,
                                min_samples_leaf=min_samples_leaf, class_weight=None,
                                warm_start=True, n_jobs=n_jobs, random_state=seed)
    with tqdm(total=n_trees, desc="trees", disable=not progress, unit="tree") as bar:
        while rf.n_estimators < n_trees:
            step = min(_TREES_PER_STEP, n_trees - rf.n_estimators)
            rf.set_params(n_estimators=rf.n_estimators + step,
                          oob_score=rf.n_estimators + step == n_trees)
            with warnings.catch_warnings():  # few trees: some pixels have no OOB vote
                warnings.filterwarnings("ignore", "Some inputs do not have OOB scores")
                rf.fit(X, y)
            bar.update(step)
    scores = _oob_scores(rf, y, threshold)
    return Segmenter(model=rf, features=feats, threshold=float(threshold),
                     training_images=[str(n) for n in names], label_counts=counts,
                     scores=scores, seed=int(seed), n_jobs=n_jobs)


def _oob_scores(rf, y, threshold):
    """Out-of-bag pixel scores of the sampled training pixels; drops the per-sample arrays."""
    d = getattr(rf, "oob_decision_function_", None)
    out = {"kind": "out-of-bag, sampled training pixels", "n_pixels": int(y.size)}
    if d is not None:
        k = list(rf.classes_).index(CRACK)
        ok = np.isfinite(d[:, k])
        pred = d[ok, k] >= threshold
        true = y[ok] == CRACK
        tp = float((pred & true).sum())
        prec = tp / max(pred.sum(), 1)
        rec = tp / max(true.sum(), 1)
        out.update(accuracy=float((pred == true).mean()), crack_precision=prec,
                   crack_recall=rec, crack_f1=2 * prec * rec / max(prec + rec, 1e-12))
        del rf.oob_decision_function_
    for a in ("oob_score_",):
        if hasattr(rf, a):
            delattr(rf, a)
    rf.set_params(warm_start=False, oob_score=False, n_jobs=None)
    return out

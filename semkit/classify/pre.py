"""Pre-existing cracks against a grain map: inter-, intra- or trans-granular (He et al.).

A crack whose skeleton lies more than :data:`INTER_MIN_FRACTION` (86 %) along grain
boundaries is inter-granular; else, more than :data:`INTRA_MIN_FRACTION` (80 %) inside one
grain, intra-granular; else trans-granular. Both fractions are reported per crack.
"""
from __future__ import annotations

import numpy as np
import pandas as pd

from .. import config
from ..errors import InputError

__all__ = ["classify_pre", "INTER_MIN_FRACTION", "INTRA_MIN_FRACTION", "BOUNDARY_TOL_PX"]

#: He et al.: share of the crack along grain boundaries above which it is inter-granular.
INTER_MIN_FRACTION = config.INTER_MIN_FRACTION
#: He et al.: share of the crack inside one grain above which it is intra-granular.
INTRA_MIN_FRACTION = config.INTRA_MIN_FRACTION
#: a skeleton pixel is "on a boundary" within this many px beyond the local half-aperture.
BOUNDARY_TOL_PX = config.BOUNDARY_TOL_PX


def _fill_grains(grain_labels):
    g = np.asarray(grain_labels)
    if (g > 0).all():
        return g
    if not (g > 0).any():
        raise InputError("grain_labels: no grain pixels")
    from scipy import ndimage as ndi  # the grain stages only (its import costs ~0.2 s)
    _, idx = ndi.distance_transform_edt(g == 0, return_indices=True)
    return g[idx[0], idx[1]]


def classify_pre(crack_labels, grain_labels, *, skeleton=None,
                 inter_min=INTER_MIN_FRACTION, intra_min=INTRA_MIN_FRACTION,
                 boundary_tol_px=BOUNDARY_TOL_PX):
    """Classify pre-existing cracks as inter-, intra- or trans-granular (He et al.'s rule).

    Parameters
    ----------
    crack_labels : (M, N) ndarray of int
        Crack objects, 0 = none.
    grain_labels : (M, N) ndarray of int
        Grain map, 1..G (0 where unknown, e.g. under cracks: filled by the nearest grain).
    skeleton : (M, N) ndarray of bool, optional
        Crack skeleton (computed when absent).
    inter_min, intra_min : float
        The rule's thresholds (0.86, 0.80).
    boundary_tol_px : float
        A skeleton pixel is on a boundary when its distance to the nearest grain boundary is
        at most its local half-aperture + this tolerance.

    Returns
    -------
    table : pandas.DataFrame
        One row per crack object: ``crack_id, boundary_fraction, max_grain_fraction,
        n_grains, type_pre, confidence``.
    type_image : (M, N) ndarray of int8
        Type per pixel (the object's): 0 none, 1 inter, 2 intra, 3 trans.

    Raises
    ------
    InputError
        Shapes disagree.

    Notes
    -----
    Per crack object: f_b = n(skeleton px on boundaries) / n(skeleton px); f_g = the largest
    share of skeleton px in one grain. inter if f_b > 0.86, else intra if f_g > 0.80, else
    trans. The confidence is the distance of the deciding fraction from its threshold, scaled
    to [0.5, 1].
    """
    lab = np.asarray(crack_labels)
    g = np.asarray(grain_labels)
    if lab.shape != g.shape or lab.ndim != 2:
        raise InputError(f"grain_labels: expected shape {lab.shape}, got {g.shape}")
    g = _fill_grains(g)
    mask = lab > 0
    if skeleton is None:
        from skimage.morphology import skeletonize
        skeleton = skeletonize(mask)
    skel = np.asarray(skeleton, bool) & mask
    # pixels whose 4-neighbourhood has another grain: the boundary, both sides
    bnd = np.zeros(g.shape, bool)
    bnd[:, 1:] |= g[:, 1:] != g[:, :-1]
    bnd[:, :-1] |= g[:, 1:] != g[:, :-1]
    bnd[1:, :] |= g[1:, :] != g[:-1, :]
    bnd[:-1, :] |= g[1:, :] != g[:-1, :]
    from scipy import ndimage as ndi
    d_bnd = ndi.distance_transform_edt(~bnd)
    half = ndi.distance_transform_edt(mask)
    rr, cc = np.nonzero(skel)
    on_img = np.zeros(lab.shape, bool)
    on_img[rr, cc] = d_bnd[rr, cc] <= half[rr, cc] + boundary_tol_px
    ids = lab[rr, cc]
    n = int(lab.max())
    rows = []
    code_of = np.zeros(n + 1, np.int8)
    names = {1: "inter", 2: "intra", 3: "trans"}
    for cid in np.unique(lab[mask]):
        sel = ids == cid
        if sel.any():
            on = on_img[rr[sel], cc[sel]]
            gg = g[rr[sel], cc[sel]]
        else:  # no skeleton pixel (cannot happen for a non-empty object): use all pixels
            pr, pc = np.nonzero(lab == cid)
            on = d_bnd[pr, pc] <= half[pr, pc] + boundary_tol_px
            gg = g[pr, pc]
        f_b = float(on.mean())
        counts = np.bincount(gg)
        f_g = float(counts.max() / counts.sum())
        if f_b > inter_min:
            k, conf = 1, 0.5 + 0.5 * (f_b - inter_min) / (1 - inter_min)
        elif f_g > intra_min:
            k, conf = 2, 0.5 + 0.5 * (f_g - intra_min) / (1 - intra_min)
        else:
            k = 3
            conf = 0.5 + 0.5 * min((inter_min - f_b) / inter_min, (intra_min - f_g) / intra_min)
        code_of[cid] = k
        rows.append(dict(crack_id=int(cid), boundary_fraction=f_b, max_grain_fraction=f_g,
                         n_grains=int((counts > 0).sum()), type_pre=names[k],
                         confidence=float(np.clip(conf, 0.5, 1.0))))
    cols = ["crack_id", "boundary_fraction", "max_grain_fraction", "n_grains", "type_pre",
            "confidence"]
    return pd.DataFrame(rows, columns=cols), code_of[lab]

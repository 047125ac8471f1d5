"""Where the laboratory tests read strain and stress: the central gauge and the boundary layers.

Two readings, as in a laboratory (compression positive everywhere):

- the **gauge**: the particles whose centres lie in the middle half of the height, across 90 %
  of the width (:data:`GAUGE_FRACTION`), like an extensometer on the central length of a
  laboratory specimen: its mean stress is that of the whole cross-section less a skin of 5 %
  on each free side (where the packing is softer), so it samples the specimen's grains rather
  than the few of its centre. Its strain is the affine least-squares fit
  of their displacements (:func:`gauge_strains`), its stress the mean (virial) stress of the
  same particles over the area of their Voronoi cells (:func:`gauge_stress`,
  :func:`cell_area`). Stress and strain of one region obey the material's elastic law at every
  instant, whatever the platens do, so moduli read from the gauge do not depend on the loading
  speed or its changes (a crack crossing the gauge does change them: :func:`crack_crosses`);
- the **boundary layers**: the end layers are the particles the platens touch
  (:func:`end_indices`); their mean distance gives the axial strain over the whole height
  without the platen contact compliance (:func:`layer_strain`). The side layers, the particles
  within one mean diameter of a side face, give the lateral strain over the whole height.
"""
from __future__ import annotations

import numpy as np

__all__ = ["GAUGE_FRACTION", "gauge_indices", "gauge_box", "side_indices", "end_indices",
           "bonded_only",
           "gauge_strains", "layer_strain", "cell_area", "gauge_stress", "crack_crosses"]

#: The strain gauge is the central region spanning these fractions of the width and height.
GAUGE_FRACTION = (0.9, 0.5)


def _fractions(fraction):
    fx, fy = (fraction, fraction) if isinstance(fraction, (int, float)) else fraction
    return float(fx), float(fy)


def gauge_indices(x, y, box, *, fraction=None, margin: float = 0.0, min_count: int = 6):
    """Particles whose centres lie in the central ``fraction`` (of the width, of the height:
    a pair or one number for both; default :data:`GAUGE_FRACTION`) of the box, and at least
    ``margin`` (m) from its side faces (:func:`gauge_box`).

    Returns
    -------
    idx : (G,) ndarray of int64

    Raises
    ------
    ValueError
        Fewer than ``min_count`` particles in the gauge.
    """
    gx0, gx1, gy0, gy1 = gauge_box(box, fraction, margin)
    idx = np.nonzero((x >= gx0) & (x <= gx1) & (y >= gy0) & (y <= gy1))[0]
    if idx.size < min_count:
        raise ValueError(f"strain gauge holds {idx.size} particles, expected >= {min_count}: "
                         f"the specimen is too small for gauge fraction "
                         f"{GAUGE_FRACTION if fraction is None else fraction}")
    return idx


def gauge_box(box, fraction=None, margin: float = 0.0):
    """(xmin, xmax, ymin, ymax) of the gauge region of ``box`` (``fraction`` as in
    :func:`gauge_indices`; the region keeps ``margin`` from the side faces, so the cells of
    its particles stay inside the packing).

    Examples
    --------
    >>> gauge_box([0.0, 10.0, 0.0, 20.0]).tolist()
    [0.5, 9.5, 5.0, 15.0]
    >>> gauge_box([0.0, 10.0, 0.0, 20.0], margin=1.0).tolist()
    [1.0, 9.0, 5.0, 15.0]
    >>> gauge_box([0.0, 10.0, 0.0, 20.0], margin=4.0).tolist()
    [2.5, 7.5, 5.0, 15.0]
    """
    fx, fy = _fractions(GAUGE_FRACTION if fraction is None else fraction)
    xmin, xmax, ymin, ymax = (float(v) for v in box)
    cx, cy = 0.5 * (xmin + xmax), 0.5 * (ymin + ymax)
    w = xmax - xmin
    hx = min(0.5 * fx * w, max(0.5 * w - margin, 0.25 * w))   # never below half the width
    hy = 0.5 * fy * (ymax - ymin)
    return np.array([cx - hx, cx + hx, cy - hy, cy + hy])


def side_indices(x, r, box, *, depth=None):
    """Particles within ``depth`` (m, default one mean diameter) of the left and right faces."""
    d = 2.0 * float(np.mean(r)) if depth is None else depth
    return np.nonzero(x - r <= box[0] + d)[0], np.nonzero(x + r >= box[1] - d)[0]


def end_indices(y, r, box, *, depth=None):
    """Particles within ``depth`` (m, default a quarter of the mean radius) of the bottom and
    top faces: the layers the platens touch."""
    d = 0.25 * float(np.mean(r)) if depth is None else depth
    return np.nonzero(y - r <= box[2] + d)[0], np.nonzero(y + r >= box[3] - d)[0]


def bonded_only(specimen, *layers):
    """The particles of each layer that hold a bond at generation.

    An unbonded particle in a boundary layer is not tied to the specimen: pressed by a platen
    it slips into the packing (one corner particle of a 10 x 20 mm specimen moved 41 um while
    the platen moved 12 um), and a layer's mean position then reads a strain the specimen does
    not have. A specimen without bonds, or a layer with no bonded particle, keeps its layers.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> s = SimpleNamespace(bond_i=np.array([0, 1]), bond_j=np.array([1, 3]))
    >>> [a.tolist() for a in bonded_only(s, np.array([0, 2]), np.array([2]))]
    [[0], [2]]
    """
    bonded = np.union1d(specimen.bond_i, specimen.bond_j)
    kept = [np.asarray(idx)[np.isin(idx, bonded)] for idx in layers]
    return tuple(k if k.size else np.asarray(idx) for k, idx in zip(kept, layers))


def gauge_strains(x0, y0, x, y, idx):
    """Mean strain of a particle region by a least-squares affine fit of the displacements.

    Fits ``u = c + A (X - X̄)`` to the displacements of the particles ``idx``.

    Parameters
    ----------
    x0, y0, x, y : (N,) ndarray of float64, m
        Reference and current positions.
    idx : (G,) ndarray of int

    Returns
    -------
    eps_xx, eps_yy : float
        Normal strains, **compression positive** (``-du_x/dX``, ``-du_y/dY``).

    Examples
    --------
    >>> X, Y = np.meshgrid(np.arange(3.0), np.arange(3.0))
    >>> X, Y = X.ravel(), Y.ravel()
    >>> exx, eyy = gauge_strains(X, Y, X * 1.001, Y * 0.998, np.arange(9))
    >>> round(exx, 12), round(eyy, 12)
    (-0.001, 0.002)
    """
    X, Y = x0[idx], y0[idx]
    M = np.c_[np.ones(idx.size), X - X.mean(), Y - Y.mean()]
    c = np.linalg.lstsq(M, np.c_[x[idx] - X, y[idx] - Y], rcond=None)[0]
    return -float(c[1, 0]), -float(c[2, 1])


def layer_strain(p0, p, lo, hi) -> float:
    """Strain between two particle layers from their mean positions along one axis
    (compression positive).

    Examples
    --------
    >>> layer_strain(np.array([0.0, 10.0]), np.array([0.5, 9.5]), [0], [1])
    0.1
    """
    l0 = p0[hi].mean() - p0[lo].mean()
    return float((l0 - (p[hi].mean() - p[lo].mean())) / l0)


def cell_area(x, y, idx) -> float:
    """Total area of the Voronoi cells of the particles ``idx`` (interior particles), m².

    The virial stress of a particle set is exact over the area its cells tile (a regular
    lattice: n √3/2 s²); the cells of particles on the edge of the packing are open, so
    ``idx`` must lie inside it (the gauge does).

    Raises
    ------
    ValueError
        A particle of ``idx`` has an open cell.
    """
    from scipy.spatial import Voronoi
    vor = Voronoi(np.c_[x, y])
    total = 0.0
    for i in np.asarray(idx):
        reg = vor.regions[vor.point_region[i]]
        if not reg or -1 in reg:
            raise ValueError(f"particle {int(i)} of the gauge lies on the edge of the packing")
        px, py = vor.vertices[reg, 0], vor.vertices[reg, 1]
        total += 0.5 * abs(float(np.dot(px, np.roll(py, 1)) - np.dot(py, np.roll(px, 1))))
    return total


def gauge_stress(sim, mask, area) -> tuple:
    """Mean stress (σxx, σyy), Pa, compression positive, of the particles where ``mask`` is
    true over ``area`` (the Love–Weber virial of their pair forces)."""
    from ..measure import virial_stress
    s = virial_stress(sim.state, mask, area)
    return float(s[0, 0]), float(s[1, 1])


def crack_crosses(cx, cy, gbox, link: float) -> bool:
    """Whether a connected set of cracks spans the gauge ``gbox`` from side to side or from
    top to bottom.

    Cracks (bond-break positions ``cx``, ``cy`` inside ``gbox``) are connected when they lie
    within ``link`` of each other (bonds that share a particle: about one particle diameter).
    A set spans the gauge when its extent reaches the gauge's width (or height) less ``link``.

    Examples
    --------
    >>> x = np.linspace(0.05, 0.95, 10)
    >>> crack_crosses(x, np.full(10, 0.5), np.array([0, 1, 0, 1.0]), 0.12)
    True
    >>> crack_crosses(x[::2], np.full(5, 0.5), np.array([0, 1, 0, 1.0]), 0.12)
    False
    """
    cx, cy = np.asarray(cx, float), np.asarray(cy, float)
    inside = (cx >= gbox[0]) & (cx <= gbox[1]) & (cy >= gbox[2]) & (cy <= gbox[3])
    cx, cy = cx[inside], cy[inside]
    if cx.size < 2:
        return False
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree
    pairs = cKDTree(np.c_[cx, cy]).query_pairs(link, output_type="ndarray")
    n = cx.size
    g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    _, lab = connected_components(g, directed=False)
    wx, wy = gbox[1] - gbox[0] - link, gbox[3] - gbox[2] - link
    for k in np.unique(lab):
        sel = lab == k
        if np.ptp(cx[sel]) >= wx or np.ptp(cy[sel]) >= wy:
            return True
    return False

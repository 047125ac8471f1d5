"""Exports of a specimen: PFC geometry (``.geom``) of the grain polygons, and legacy VTK.

PFC geometry file (``ITASCA GEOMETRY3D``, what PFC's ``geometry import`` / ``geometry export``
use), as written here::

    ITASCA GEOMETRY3D
    ; gbmgen <version>: grain polygons of <specimen>, z = 0, metres
    NODES
    1 (0.0,0.0,0.0)
    ...
    EDGES
    1 1 2
    ...
    POLYS
    1 NODE 1 2 3 4 5 6 GROUP 'pyroxene' SLOT 'mineral'
    ...

Nodes are the distinct polygon vertices (shared by neighbouring grains), numbered from 1;
EDGES are the distinct boundary segments (for a DFN / smooth-joint install, App. E); each POLYS
line is one grain, its nodes counter-clockwise, with the mineral as group in slot ``mineral``.
Lines starting with ``;`` are comments. :func:`read_geom` reads this back.

VTK: ``<prefix>_particles.vtk`` (vertex cells with point data radius, mineral, grain) and
``<prefix>_grains.vtk`` (polygon cells with cell data mineral, grain_class, grain), legacy ASCII
UNSTRUCTURED_GRID, readable by ParaView and meshio (in ParaView, show the particles with the
"Point Gaussian" representation scaled by ``radius``).
"""
from __future__ import annotations

import os
import re
import tempfile

import numpy as np

from . import __version__
from .errors import InputError

__all__ = ["export_geom", "read_geom", "export_vtk"]


def _atomic_write(path, text):
    path = os.fspath(path)
    d = os.path.dirname(os.path.abspath(path))
    os.makedirs(d, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=d, suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def _nodes(xy, tol):
    """Distinct vertices (merged within tol) -> (unique (U, 2), index (K,))."""
    key = np.round(xy / tol).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return xy[first], inv.ravel()


def export_geom(spec, path, *, name="specimen"):
    """Write the grain polygons of a specimen as a PFC geometry file.

    Parameters
    ----------
    spec : sim.Specimen
        With grains (``grain_xy``, ``grain_offsets``, ``grain_mineral``).
    path : str or path-like
    name : str
        Written in the header comment.

    Returns
    -------
    counts : dict
        ``nodes``, ``edges``, ``polys``.

    Raises
    ------
    InputError
        The specimen has no grain polygons.
    """
    if spec.n_grains == 0:
        raise InputError(f"{name}: field 'grain_offsets' is empty; nothing to export as .geom")
    xy = spec.grain_xy
    off = spec.grain_offsets
    L = float(max(spec.box[1] - spec.box[0], spec.box[3] - spec.box[2]))
    nodes, idx = _nodes(xy, 1e-10 * L)
    lines = ["ITASCA GEOMETRY3D",
             f"; gbmgen {__version__}: grain polygons of {name}, z = 0, metres",
             "NODES"]
    lines += [f"{k + 1} ({x!r},{y!r},0.0)" for k, (x, y) in enumerate(nodes.tolist())]
    a = idx
    nxt = np.arange(idx.size) + 1
    nxt[off[1:] - 1] = off[:-1]
    b = idx[nxt]
    e = np.unique(np.sort(np.c_[a, b], axis=1), axis=0)
    e = e[e[:, 0] != e[:, 1]]
    lines.append("EDGES")
    lines += [f"{k + 1} {i + 1} {j + 1}" for k, (i, j) in enumerate(e.tolist())]
    lines.append("POLYS")
    names = [str(s) for s in spec.mineral_names]
    for g in range(spec.n_grains):
        ids = " ".join(str(v + 1) for v in idx[off[g]:off[g + 1]])
        grp = names[int(spec.grain_mineral[g])]
        if "'" in grp:
            raise InputError(f"mineral_names: {grp!r} contains a quote")
        lines.append(f"{g + 1} NODE {ids} GROUP '{grp}' SLOT 'mineral'")
    _atomic_write(path, "\n".join(lines) + "\n")
    return {"nodes": int(nodes.shape[0]), "edges": int(e.shape[0]), "polys": int(spec.n_grains)}


_NODE = re.compile(r"^\s*(\d+)\s+\(\s*([^,]+),\s*([^,]+),\s*([^)]+)\)")
_POLY = re.compile(r"^\s*(\d+)\s+NODE\s+([\d\s]+?)"
                   r"(?:\s+GROUP\s+'([^']*)'(?:\s+SLOT\s+'([^']*)')?)?\s*$", re.IGNORECASE)


def read_geom(path):
    """Read a geometry file written by :func:`export_geom` (2D: z ignored).

    Returns
    -------
    geom : dict
        ``nodes`` (U, 2) float64; ``edges`` (E, 2) int64 (0-based node indices); ``xy`` (K, 2)
        and ``offsets`` (G+1,) polygons; ``groups`` list of G group names.

    Raises
    ------
    InputError
        Not an ``ITASCA GEOMETRY3D`` file, or a malformed line (named by number).
    """
    path = os.fspath(path)
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read().splitlines()
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc})") from None
    if not text or text[0].strip().upper() != "ITASCA GEOMETRY3D":
        raise InputError(f"{path}: line 1 is not 'ITASCA GEOMETRY3D'")
    section = None
    node_id, node_xy, edges, polys, groups = {}, [], [], [], []
    for ln, raw in enumerate(text[1:], start=2):
        line = raw.split(";", 1)[0].strip()
        if not line:
            continue
        head = line.split()[0].upper()
        if head in ("NODES", "EDGES", "POLYS"):
            section = head
            continue
        if section == "NODES":
            m = _NODE.match(line)
            if not m:
                raise InputError(f"{path}: line {ln}: expected 'id (x,y,z)', got {raw!r}")
            node_id[int(m.group(1))] = len(node_xy)
            node_xy.append((float(m.group(2)), float(m.group(3))))
        elif section == "EDGES":
            parts = line.split()
            try:
                edges.append((node_id[int(parts[1])], node_id[int(parts[2])]))
            except (IndexError, ValueError, KeyError):
                raise InputError(f"{path}: line {ln}: expected 'id node1 node2' of known nodes, "
                                 f"got {raw!r}") from None
        elif section == "POLYS":
            m = _POLY.match(line)
            if not m:
                raise InputError(f"{path}: line {ln}: expected 'id NODE n1 n2 ... [GROUP 'g']', "
                                 f"got {raw!r}")
            try:
                polys.append([node_id[int(v)] for v in m.group(2).split()])
            except KeyError:
                raise InputError(f"{path}: line {ln}: unknown node id") from None
            groups.append(m.group(3))
        else:
            raise InputError(f"{path}: line {ln}: data before a NODES/EDGES/POLYS keyword")
    nodes = np.array(node_xy, float).reshape(-1, 2)
    offsets = np.zeros(len(polys) + 1, np.int64)
    offsets[1:] = np.cumsum([len(p) for p in polys])
    xy = nodes[np.concatenate(polys)] if polys else np.zeros((0, 2))
    return {"nodes": nodes, "edges": np.array(edges, np.int64).reshape(-1, 2), "xy": xy,
            "offsets": offsets, "groups": groups}


def export_vtk(spec, prefix):
    """Write ``<prefix>_particles.vtk`` and ``<prefix>_grains.vtk`` (legacy ASCII).

    Returns
    -------
    paths : list of str
    """
    prefix = os.fspath(prefix)
    n = spec.n_particles
    p = ["# vtk DataFile Version 3.0", f"gbmgen {__version__} particles (m)", "ASCII",
         "DATASET UNSTRUCTURED_GRID", f"POINTS {n} double"]
    p += [f"{x!r} {y!r} 0.0" for x, y in zip(spec.x.tolist(), spec.y.tolist())]
    p.append(f"CELLS {n} {2 * n}")
    p += [f"1 {i}" for i in range(n)]
    p.append(f"CELL_TYPES {n}")
    p += ["1"] * n  # VTK_VERTEX
    p += [f"POINT_DATA {n}", "SCALARS radius double 1", "LOOKUP_TABLE default"]
    p += [repr(v) for v in spec.r.tolist()]
    for key in ("mineral", "grain"):
        p += [f"SCALARS {key} int 1", "LOOKUP_TABLE default"]
        p += [str(v) for v in getattr(spec, key).tolist()]
    out = [f"{prefix}_particles.vtk"]
    _atomic_write(out[0], "\n".join(p) + "\n")
    if spec.n_grains:
        xy, off = spec.grain_xy, spec.grain_offsets
        g = spec.n_grains
        q = ["# vtk DataFile Version 3.0", f"gbmgen {__version__} grains (m)", "ASCII",
             "DATASET UNSTRUCTURED_GRID", f"POINTS {xy.shape[0]} double"]
        q += [f"{x!r} {y!r} 0.0" for x, y in xy.tolist()]
        q.append(f"CELLS {g} {xy.shape[0] + g}")
        for k in range(g):
            q.append(" ".join([str(off[k + 1] - off[k])]
                              + [str(v) for v in range(off[k], off[k + 1])]))
        q.append(f"CELL_TYPES {g}")
        q += ["7"] * g  # VTK_POLYGON
        q += [f"CELL_DATA {g}", "SCALARS mineral int 1", "LOOKUP_TABLE default"]
        q += [str(v) for v in spec.grain_mineral.tolist()]
        q += ["SCALARS grain_class int 1", "LOOKUP_TABLE default"]
        q += [str(v) for v in spec.grain_class.tolist()]
        q += ["SCALARS grain int 1", "LOOKUP_TABLE default"]
        q += [str(v) for v in range(g)]
        out.append(f"{prefix}_grains.vtk")
        _atomic_write(out[1], "\n".join(q) + "\n")
    return out

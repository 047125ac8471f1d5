"""CrackLog: one record per bond break (DESIGN.md §7)."""
from __future__ import annotations

import numpy as np

COLUMNS = ("step", "time", "x", "y", "kind", "mode", "relation", "mineral_i", "mineral_j",
           "grain_i", "grain_j", "size_m", "angle_deg", "bond")
_KIND = np.array(["pb", "sj"])
_MODE = np.array(["", "tension", "shear"])
_REL = np.array(["intra", "inter"])


class CrackLog:
    """Bond-break events, appended by :class:`sim.Simulation` after every compiled chunk.

    Notation: K events. Each event is one broken bond: ``kind`` 'pb' (parallel bond, inside a
    grain: relation 'intra') or 'sj' (smooth joint, grain boundary: 'inter'); ``mode`` 'tension'
    or 'shear'; ``x, y`` the contact point (m); ``size_m`` the bond diameter 2R̄ (crack area is
    size × t); ``angle_deg`` the direction of the crack-plane normal (ball–ball line for a parallel
    bond, joint normal for a smooth joint) from +x, in [0, 180); ``bond`` the specimen bond index.
    """

    def __init__(self):
        self._cols = {c: [] for c in COLUMNS}

    def __len__(self) -> int:
        return sum(len(a) for a in self._cols["step"])

    def append(self, **cols) -> None:
        """Append arrays of equal length, one per column (internal)."""
        for c in COLUMNS:
            self._cols[c].append(np.asarray(cols[c]))

    def arrays(self) -> dict:
        """Columns as numpy arrays (kind, mode, relation as str)."""
        out = {}
        for c in COLUMNS:
            parts = self._cols[c]
            out[c] = np.concatenate(parts) if parts else np.zeros(0)
        for c in ("kind", "mode", "relation"):
            out[c] = out[c].astype(str)
        return out

    def to_frame(self):
        """pandas DataFrame, one row per bond break, columns :data:`COLUMNS`."""
        import pandas as pd
        return pd.DataFrame(self.arrays(), columns=list(COLUMNS))

    def counts(self) -> dict:
        """``{pb_tension, pb_shear, sj_tension, sj_shear}`` counts (DESIGN.md §4 summary)."""
        a = self.arrays()
        return {f"{k}_{m}": int(np.sum((a["kind"] == k) & (a["mode"] == m)))
                for k in ("pb", "sj") for m in ("tension", "shear")}

    # --- persistence (plain arrays, no pickle) --------------------------------------------
    def to_npz_dict(self, prefix="crack__") -> dict:
        return {prefix + c: v for c, v in self.arrays().items()}

    @classmethod
    def from_npz_dict(cls, d, prefix="crack__") -> "CrackLog":
        log = cls()
        if prefix + "step" in d and len(d[prefix + "step"]):
            log.append(**{c: np.array(d[prefix + c]) for c in COLUMNS})
        return log


def crack_records(kind, mode, **cols) -> dict:
    """Translate integer kind (0/1) and mode (1/2) codes into the CrackLog string columns."""
    kind = np.asarray(kind, int)
    cols.update(kind=_KIND[kind], mode=_MODE[np.asarray(mode, int)], relation=_REL[kind])
    return cols

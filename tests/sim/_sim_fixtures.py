"""Hand-made specimens with known answers (tests only)."""
import numpy as np

from sim import Specimen


def disks(x, y, r, *, mineral=None, density=(2650.0,), emod=(1e9,), kratio=(2.0,), fric=(0.5,),
          pb_emod=(1e9,), pb_kratio=(2.0,), pb_ten=(1e100,), pb_coh=(1e100,), pb_fa=(0.0,),
          pb_rmul=(1.0,), bonds=(), kinds=None, joint_normals=None, sj=None):
    """A Specimen from explicit particles, mineral tables and bonds."""
    x = np.asarray(x, float)
    n = x.size
    m = len(density)
    bonds = np.asarray(bonds, np.int64).reshape(-1, 2)
    b = len(bonds)
    kinds = np.zeros(b, np.int8) if kinds is None else np.asarray(kinds, np.int8)
    jn = np.full((b, 2), np.nan) if joint_normals is None else np.asarray(joint_normals, float)
    sj = sj or {}
    one = lambda v: np.array([v], float)  # noqa: E731
    r = np.broadcast_to(np.asarray(r, float), (n,)).copy()
    return Specimen(
        x=x, y=np.asarray(y, float), r=r,
        mineral=np.zeros(n, np.int32) if mineral is None else np.asarray(mineral),
        grain=np.full(n, -1), mineral_names=np.array([f"m{k}" for k in range(m)]),
        density=np.array(density, float), emod=np.array(emod, float),
        kratio=np.array(kratio, float), fric=np.array(fric, float),
        pb_emod=np.array(pb_emod, float), pb_kratio=np.array(pb_kratio, float),
        pb_ten=np.array(pb_ten, float), pb_coh=np.array(pb_coh, float),
        pb_fa=np.array(pb_fa, float), pb_rmul=np.array(pb_rmul, float),
        sj_kn=one(sj.get("kn", 0.0)), sj_ks=one(sj.get("ks", 0.0)),
        sj_ten=one(sj.get("ten", 0.0)), sj_coh=one(sj.get("coh", 0.0)),
        sj_fa=one(sj.get("fa", 0.0)), sj_fric=one(sj.get("fric", 0.0)),
        bond_i=bonds[:, 0], bond_j=bonds[:, 1], bond_kind=kinds,
        joint_nx=jn[:, 0], joint_ny=jn[:, 1],
        box=np.array([x.min() - r.max(), x.max() + r.max(), np.min(y) - r.max(),
                      np.max(y) + r.max()])).validate()

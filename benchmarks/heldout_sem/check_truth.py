"""Self-checks of the generator's truth (coverage sum, straight-crack length, mask vs area)."""
# ruff: noqa: E501  (kept as written apart from semkit)
import os
import sys

import numpy as np
from skimage.morphology import skeletonize

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import sem_generator as gen  # noqa: E402

cap = {}
_orig = gen._render


def _spy(rng, shape, st, cov_t, cov_s, cov_p, cracks, debris, bar_h):
    cap.update(cov_t=cov_t.copy(), cov_s=cov_s.copy(), cov_p=cov_p.copy())
    return _orig(rng, shape, st, cov_t, cov_s, cov_p, cracks, debris, bar_h)


gen._render = _spy
print('(a) coverage sum vs area_px, (c) mask count vs area_px')
for seed, shape in [(0, (768, 1024)), (1, (768, 1024)), (2, (1536, 2048)), (5, (768, 1024)), (9, (768, 1024))]:
    r = gen.make_image(shape, seed)
    cov = cap['cov_t'] + cap['cov_s']
    ta = sum(c['tensile_area_px'] for c in r['cracks'])
    print(f"  seed {seed} {shape}: n={len(r['cracks'])} area_px={r['area_px']:.3f} sum(cov)={cov.sum():.3f} "
          f"max(cov)={cov.max():.3f} max(cov+pores)={(cov + cap['cov_p']).max():.3f} "
          f"tens={ta:.1f}=sum(cov_t)={cap['cov_t'].sum():.1f} mask={r['crack_mask'].sum()} "
          f"mask/area={r['crack_mask'].sum() / r['area_px']:.4f} bar={r['settings']['bar']} "
          f"ps={r['pixel_size_um']:.4f}" + (f" label={r['settings']['bar_label_um']}um bar_px={r['settings']['bar_px']}"
                                           f" -> {r['settings']['bar_label_um'] / r['settings']['bar_px']:.4f}"
                                           if r['settings']['bar'] else ''))
    assert not (r['crack_mask'] & (cap['cov_p'] > 0)).any()

print('(b) straight tensile cracks of known length')
rng = np.random.default_rng(123)
for L, ang, w0, rough in [(300.0, 0.0, 6.0, 0.0), (200.0, 0.7, 3.0, 0.0), (250.0, 2.1, 8.0, 0.0),
                          (300.0, 0.4, 5.0, 0.8)]:
    p0 = np.array([350.3, 350.7]) - L / 2 * np.array([np.cos(ang), np.sin(ang)])
    pts, nrm, s = gen._path(rng, p0, ang, L, 0.0)
    wb = np.full_like(s, w0)
    g = np.minimum(gen._smoothstep(s / 12), gen._smoothstep((L - s) / 12))
    wb = 1.2 + (wb - 1.2) * g
    tr = gen._trace(rng, pts, nrm, s, wb, np.zeros_like(s), rough, 8, 0)
    truth = gen._trace_length(tr)
    y0, x0, ct, cs = gen._rasterise([tr], (700, 700))
    m = ct >= 0.5
    ys, xs = np.nonzero(ct > 0)
    u = np.array([np.cos(ang), np.sin(ang)])
    proj = (xs + x0) * u[0] + (ys + y0) * u[1]
    # coverage-weighted extent along the axis: area / mean opening over the flat part
    sk = skeletonize(m)
    yy, xx = np.nonzero(sk)
    p = np.sort((xx + x0) * u[0] + (yy + y0) * u[1])
    skel_len = p[-1] - p[0]
    print(f"  L={L} angle={ang} w0={w0} rough={rough}: length_px={truth:.2f} "
          f"(err {100 * (truth / L - 1):+.2f}% vs drawn L), skeleton axial extent={skel_len:.1f} "
          f"(+~w at tips), pixel axial extent={np.ptp(proj) + 1:.1f}, area={ct.sum():.1f} "
          f"mask={m.sum()} mask/area={m.sum() / ct.sum():.4f}")

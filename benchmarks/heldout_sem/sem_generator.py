"""A second held-out generator: SEM micrographs of cracked rock with exact truth, written apart
from semkit (its author read none of semkit's code, nor `benchmarks/heldout`).

Cracks are void polygons between two walls, rasterised by 8x8 supersampling so
every pixel gets an exact void coverage ``c``.  The grey image before blur and
noise is ``background * (1 - c) + void_grey * c``.  Truth:

* ``area_px``   : sum of crack coverage (pores excluded);
* ``length_px`` : length of the centreline (mid-line between the walls) of every
  open trace; stretches with opening < 0.3 px are closed (not drawn, not counted);
* ``P``         : tensile area / shear area (nan if no shear area).
"""
# ruff: noqa: E501  (kept as written apart from semkit)
import cv2
import numpy as np
from scipy import ndimage as ndi
from scipy.signal import lfilter
from scipy.spatial import cKDTree

SS = 8            # supersampling factor per axis
DS = 0.5          # arc-length step of traces (px)
W_CLOSE = 0.3     # openings below this are closed
GAP = 5           # dilation radius used for the >= 4 px separation rule


def _noise1d(rng, n, corr, amp):
    """Smooth 1-D Gaussian noise of ``n`` samples, correlation ``corr`` samples, std ``amp``."""
    pad = int(3 * corr) + 2
    sig = max(corr, 0.5)
    x = ndi.gaussian_filter1d(rng.standard_normal(n + 2 * pad), sig)[pad:pad + n]
    return amp * x * np.sqrt(2 * np.sqrt(np.pi) * sig)     # theoretical unit std


def _field(rng, shape, scale):
    """Smooth 2-D random field (zero mean, unit std) with correlation length ``scale`` px."""
    h, w = shape
    f = max(1, int(scale / 4))
    small = ndi.gaussian_filter(rng.standard_normal((h // f + 4, w // f + 4)), scale / f)
    big = cv2.resize(small.astype(np.float32), ((w // f + 4) * f, (h // f + 4) * f),
                     interpolation=cv2.INTER_CUBIC)[:h, :w]
    return (big - big.mean()) / (big.std() + 1e-12)


def _path(rng, p0, theta, length, curv):
    """Gently curved centre path: points, unit normals and arc length."""
    n = max(int(round(length / DS)) + 1, 3)
    k = _noise1d(rng, n, n / 3, curv) if curv > 0 else np.zeros(n)
    th = theta + np.cumsum(k) * DS
    step = DS * np.stack([np.cos(th), np.sin(th)], 1)
    pts = p0 + np.vstack([[0, 0], np.cumsum(step[:-1], 0)])
    # exact arc length of the path is (n-1)*DS; rescale so it equals `length`
    s = np.arange(n) * DS
    pts = p0 + (pts - p0) * (length / s[-1])
    nrm = np.stack([-np.sin(th), np.cos(th)], 1)
    return pts, nrm, s * length / s[-1]


def _smoothstep(x):
    x = np.clip(x, 0, 1)
    return x * x * (3 - 2 * x)


def _trace(rng, pts, nrm, s, wbase, m, rough, corr, shift):
    """Build a trace (walls, mid-line, opening, label) from a path.

    Wall A = mid-path + n*(rA + wbase/2), wall B = mid-path + n*(rB - wbase/2), with
    rA the rough profile and rB = rA (matched, tensile, m=0) blended to rA(s - shift)
    (walls offset along the trace, shear, m=1).
    """
    n = len(s)
    k = int(round(shift / DS)) + 1
    r = _noise1d(rng, n + k, corr / DS, rough)
    rA = r[k:]
    rB_sh = np.interp(s - shift, np.arange(-k, n) * DS, r)
    rB = rA * (1 - m) + rB_sh * m
    w = np.minimum(wbase + rA - rB, np.maximum(wbase, 0) + 1.0)
    w = np.where(w >= W_CLOSE, w, 0.0)
    # close open runs shorter than 2 px (they would be sub-pixel specks)
    lab, nr = ndi.label(w > 0)
    for i in range(1, nr + 1):
        if (lab == i).sum() * DS < 2.0:
            w[lab == i] = 0.0
    mid = pts + nrm * ((rA + rB) / 2)[:, None]
    return dict(mid=mid, A=mid + nrm * (w / 2)[:, None], B=mid - nrm * (w / 2)[:, None],
                w=w, label=np.where(m < 0.5, 1, 2), nrm=nrm)


def _trace_length(tr):
    """Centreline length over open stretches (both ends of a segment open)."""
    seg = np.hypot(*np.diff(tr['mid'], axis=0).T)
    op = (tr['w'][1:] > 0) & (tr['w'][:-1] > 0)
    return float(seg[op].sum())


def _rasterise(traces, shape):
    """Exact coverage (8x8 supersampled) of a crack's traces.

    Returns (y0, x0, cov_tensile, cov_shear) for a bounding box, or None if the
    crack leaves the image.
    """
    allp = np.vstack([np.vstack([t['A'], t['B']]) for t in traces])
    x0, y0 = np.floor(allp.min(0)).astype(int) - 2
    x1, y1 = np.ceil(allp.max(0)).astype(int) + 3
    if x0 < 0 or y0 < 0 or x1 > shape[1] or y1 > shape[0]:
        return None
    can = np.zeros(((y1 - y0) * SS, (x1 - x0) * SS), np.uint8)
    org = np.array([x0, y0], float)
    for lab_val in (1, 2):                       # shear drawn last: owns shared edges
        for t in traces:
            opn = t['w'] > 0
            runs, nr = ndi.label(opn)
            for i in range(1, nr + 1):
                idx = np.flatnonzero(runs == i)
                sel = idx[t['label'][idx] == lab_val]
                if len(sel) == 0:
                    continue
                a, b = sel[0], sel[-1]
                a = max(a - 1, idx[0]) if lab_val == 2 else a   # share boundary vertex
                b = min(b + 1, idx[-1]) if lab_val == 1 else b
                poly = np.vstack([t['A'][a:b + 1], t['B'][a:b + 1][::-1]])
                q = np.round(((poly - org + 0.5) * SS - 0.5) * 16).astype(np.int32)
                cv2.fillPoly(can, [q], lab_val, lineType=cv2.LINE_8, shift=4)
    hh, ww = y1 - y0, x1 - x0
    cov = [(can == v).reshape(hh, SS, ww, SS).sum((1, 3)) / SS ** 2 for v in (1, 2)]
    return y0, x0, cov[0], cov[1]


def _min_gap(traces):
    """Smallest distance between the open walls of two different traces."""
    walls = [np.vstack([t['A'][t['w'] > 0], t['B'][t['w'] > 0]]) for t in traces]
    gap = np.inf
    for i in range(len(walls)):
        for j in range(i + 1, len(walls)):
            if len(walls[i]) and len(walls[j]):
                gap = min(gap, cKDTree(walls[i]).query(walls[j])[0].min())
    return gap


def _make_crack(rng, kind, p0, theta, length, curv):
    """Return list of traces for one crack of type kind (tensile/shear/mixed)."""
    pts, nrm, s = _path(rng, p0, theta, length, curv)
    L = s[-1]
    traces, sub = [], None
    if kind == 'tensile':
        w0, tip = rng.uniform(2, 10), rng.uniform(1.0, 1.5)
        w = np.maximum(w0 * (1 + _noise1d(rng, len(s), 30 / DS, rng.uniform(0.05, 0.2))), 1.2)
        t1, t2 = rng.uniform(5, 20, 2)
        g = np.minimum(_smoothstep(s / t1), _smoothstep((L - s) / t2))
        wb = tip + (w - tip) * g
        traces.append(_trace(rng, pts, nrm, s, wb, np.zeros_like(s),
                             rng.uniform(0.3, 1.5), rng.uniform(4, 14), 0))
    elif kind == 'shear':
        sub = rng.choice(['single', 'stepped', 'layered'], p=[0.35, 0.35, 0.3])
        w0 = rng.uniform(0.8, 2.5)
        if sub == 'layered':
            nl, sp = rng.integers(2, 4), rng.uniform(max(3, w0 + 2.5), 7)
            pieces = [(0, L, (i - (nl - 1) / 2) * sp) for i in range(nl)]
        elif sub == 'stepped':
            ns, sp = rng.integers(2, 5), rng.uniform(3, 6) * rng.choice([-1, 1])
            cuts = np.linspace(0, L, ns + 1)
            ov = rng.uniform(3, 10)
            pieces = [(max(cuts[i] - ov, 0), min(cuts[i + 1] + ov, L), i * sp) for i in range(ns)]
        else:
            pieces = [(0, L, 0.0)]
        for a, b, off in pieces:
            a, b = a + rng.uniform(0, 8) * (a > 0 or sub == 'layered'), b
            sel = (s >= a) & (s <= b)
            if sel.sum() * DS < 15:
                continue
            ss = s[sel] - s[sel][0]
            tt = rng.uniform(3, 10)
            wb = (w0 * (1 + _noise1d(rng, len(ss), 20 / DS, 0.15))
                  * np.minimum(_smoothstep(ss / tt), _smoothstep((ss[-1] - ss) / tt)))
            traces.append(_trace(rng, pts[sel] + nrm[sel] * off, nrm[sel], ss, wb,
                                 np.ones_like(ss), rng.uniform(0.2, 0.6),
                                 rng.uniform(2, 8), rng.uniform(2, 10)))
        if len(traces) > 1 and _min_gap(traces) < 1.5:
            return [], sub                       # traces touch: reject, caller retries
    else:  # mixed: tensile over [0, sc], shear over the rest (or reversed)
        sc, tr = rng.uniform(0.3, 0.7) * L, rng.uniform(5, 15)
        m = _smoothstep((s - sc + tr / 2) / tr)
        if rng.random() < 0.5:
            m = m[::-1]
        wt, ws, tip = rng.uniform(2, 8), rng.uniform(0.8, 2.5), rng.uniform(1, 1.5)
        t1 = rng.uniform(5, 20)
        wb = wt * (1 - m) + ws * m
        gt = np.minimum(_smoothstep(s / t1), _smoothstep((L - s) / t1))
        wb = np.where(m < 0.5, tip + (wb - tip) * gt, wb * gt)
        traces.append(_trace(rng, pts, nrm, s, wb, m, rng.uniform(0.3, 0.8),
                             rng.uniform(3, 8), rng.uniform(2, 8)))
    return traces, sub


def _ellipse_cov(cx, cy, a, b, ang, shape):
    """Exact coverage of a rotated ellipse (supersampled) in a bounding box."""
    t = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    pts = np.stack([cx + a * np.cos(t) * np.cos(ang) - b * np.sin(t) * np.sin(ang),
                    cy + a * np.cos(t) * np.sin(ang) + b * np.sin(t) * np.cos(ang)], 1)
    half = len(t) // 2
    A, B = pts[:half + 1], np.vstack([pts[half:], pts[:1]])[::-1]
    tr = dict(A=A, B=B, w=np.ones(len(A)), label=np.ones(len(A), int))
    return _rasterise([tr], shape)


def _background(rng, shape, st):
    """Mineral grain mosaic (grey levels, 8-bit scale) and grain-boundary map."""
    h, w = shape
    gs = st['grain_px']
    nseed = max(int(h * w / gs ** 2 * 1.3), 4)
    seeds = rng.uniform([0, 0], [h, w], (nseed, 2))
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    amp = gs * rng.uniform(0.1, 0.3)
    yy += amp * _field(rng, shape, gs / 2)
    xx += amp * _field(rng, shape, gs / 2)
    _, lab = cKDTree(seeds).query(np.stack([yy.ravel(), xx.ravel()], 1), workers=-1)
    lab = lab.reshape(h, w)
    greys = np.sort(rng.uniform(90, 230, st['n_phases']))
    phase = rng.choice(st['n_phases'], nseed, p=rng.dirichlet(np.ones(st['n_phases']) * 2))
    gvar = rng.normal(0, rng.uniform(1, 6), nseed)
    bg = (greys[phase] + gvar)[lab].astype(np.float32)
    bnd = (np.diff(lab, axis=0, append=lab[-1:]) != 0) | (np.diff(lab, axis=1, append=lab[:, -1:]) != 0)
    bnd = ndi.gaussian_filter(bnd.astype(np.float32), 0.7)
    if st['dark_phase']:
        dark = np.zeros(shape, np.uint8)
        n = int(rng.uniform(3, 12) * h * w / 786432)
        for _ in range(n):
            c = (int(rng.uniform(0, w)), int(rng.uniform(0, h)))
            if st['dark_phase'] == 'laths':
                ax = (int(rng.uniform(10, 45)), int(rng.uniform(2, 6)))
            else:
                ax = (int(rng.uniform(6, 25)),) * 2
            cv2.ellipse(dark, c, ax, rng.uniform(0, 180), 0, 360, 1, -1)
        darkf = ndi.gaussian_filter(dark.astype(np.float32), 0.8)
        bg = bg * (1 - darkf) + st['dark_grey'] * darkf
        bnd = np.maximum(bnd, ndi.gaussian_filter((np.abs(np.diff(dark.astype(np.int8), axis=1, append=0))).astype(np.float32), 0.7))
    bg += rng.uniform(1.5, 6) * _field(rng, shape, rng.uniform(2, 8))
    return bg, bnd


def _stamp(shape, pts, sigma):
    """Sum of unit-peak Gaussian stamps at (x, y) points."""
    a = np.zeros(shape, np.float32)
    for x, y in pts:
        xi, yi = int(round(x)), int(round(y))
        if 0 <= yi < shape[0] and 0 <= xi < shape[1]:
            a[yi, xi] = 1.0
    return np.clip(ndi.gaussian_filter(a, sigma) * 2 * np.pi * sigma ** 2, 0, 1)


def _render(rng, shape, st, cov_t, cov_s, cov_p, cracks, debris, bar_h):
    """Compose background, voids, debris and SEM artefacts; return the result dict."""
    h, w = shape
    bg, bnd = _background(rng, shape, st)
    c = np.clip(cov_t + cov_s + cov_p, 0, 1)
    if st['mode'] == 'SE':                      # weak Z contrast, topography, edge effect
        st.update(se_contrast=float(rng.uniform(0.3, 0.6)), halo_px=float(rng.uniform(1, 3)),
                  halo_amp=float(rng.uniform(40, 90)), shade_amp=float(rng.uniform(4, 14)))
        mu = bg.mean()
        bg = mu + (bg - mu) * st['se_contrast']
        gy, gx = np.gradient(_field(rng, shape, rng.uniform(15, 60)))
        az = rng.uniform(0, 2 * np.pi)
        sh = gx * np.cos(az) + gy * np.sin(az)
        bg += st['shade_amp'] * sh / (sh.std() + 1e-9)
        d = ndi.distance_transform_edt(c < 0.5)
        bg += st['halo_amp'] * np.exp(-np.maximum(d - 0.5, 0) / st['halo_px']) * (d > 0)
        bg += rng.uniform(8, 25) * bnd
    else:
        bg -= rng.uniform(3, 12) * bnd
    void = st['void_grey'] + 2.0 * np.abs(_field(rng, shape, 20))
    img = bg * (1 - c) + void * c
    # crushed debris: bright specks inside shear stretches, dark chips beside them
    pin = [m for k, m, n, ww in debris if k == 'in']
    pout = [m + n * rng.choice([-1, 1]) * (ww / 2 + rng.uniform(2.5, 4)) for k, m, n, ww in debris if k == 'out']
    a_in = _stamp(shape, pin, 0.6) * rng.uniform(0.4, 0.7)
    img = img * (1 - a_in) + rng.uniform(130, 210) * a_in
    img *= 1 - rng.uniform(0.25, 0.45) * _stamp(shape, pout, rng.uniform(0.7, 1.2))
    if st['charging']:                          # bright spots with smear to the right
        n = int(rng.integers(3, 16))
        spots = _stamp(shape, rng.uniform([0, 0], [w, h - bar_h], (n, 2)), rng.uniform(1, 3))
        img = np.maximum(img, 250 * spots)
        a = np.exp(-1 / rng.uniform(20, 150))
        streak = lfilter([1 - a], [1, -a], spots, axis=1)
        img += rng.uniform(40, 120) * streak / (streak.max() + 1e-9)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    if st['illum'] == 'linear':
        t = rng.uniform(0, 2 * np.pi)
        g = xx * np.cos(t) + yy * np.sin(t)
    else:
        g = -np.hypot(xx - rng.uniform(0, w), yy - rng.uniform(0, h)) ** 2
    g = (g - g.min()) / (g.max() - g.min() + 1e-9)
    g = 1 + (st['illum_ratio'] - 1) * g
    img *= g / g.mean()
    if st['curtain']:                           # vertical streaks fading from the top
        col = np.zeros(w, np.float32)
        idx = rng.integers(0, w, int(rng.integers(10, 60)))
        col[idx] = rng.uniform(-12, 12, len(idx))
        col = ndi.gaussian_filter1d(col, rng.uniform(0.8, 2)) * 3
        env = np.exp(-yy[:, :1] / rng.uniform(0.3, 1.5) / h)
        img += col[None, :] * env
    img = ndi.gaussian_filter(img, st['blur'])
    sig = st['noise_sigma']
    if st['noise'] == 'gauss':
        img += sig * rng.standard_normal(shape)
    else:
        img += sig * np.sqrt(np.maximum(img, 1) / img.mean()) * rng.standard_normal(shape)
    if st['jitter']:
        img += rng.normal(0, rng.uniform(1, 4), (h, 1))
    img = 255 * np.clip(img / 255, 0, 1) ** st['gamma']
    img = rng.uniform(-10, 10) + rng.uniform(0.85, 1.15) * img
    maxv = (65535 if rng.random() < 0.5 else 4095) if st['uint16'] else 255
    st['max_value'] = maxv
    out = np.round(np.clip(img, 0, 255) / 255 * maxv).astype(np.uint16 if st['uint16'] else np.uint8)
    if bar_h:                                   # drawn on an 8-bit overlay, then scaled
        fg = 255 if rng.random() < 0.6 else 0
        ov = np.full((bar_h, w), 255 - fg, np.uint8)
        ps, font = st['pixel_size_um'], cv2.FONT_HERSHEY_SIMPLEX
        mag = int(round(127000 / (ps * w), -1)) or 1
        txt = f"WD {rng.uniform(5, 15):.1f}mm  HV {int(rng.choice([5, 10, 15, 20, 25]))}kV  mag {mag}x"
        fs = 0.4 * bar_h / 22
        x0 = w - int(0.03 * w) - st['bar_px']
        while cv2.getTextSize(txt, font, fs, 1)[0][0] > x0 - 0.05 * w:
            fs *= 0.9
        th = max(1, int(fs * 2))
        cv2.putText(ov, txt, (int(0.02 * w), bar_h // 2 + int(8 * fs)), font, fs, fg, th, cv2.LINE_AA)
        yb, bt = bar_h - int(bar_h * 0.3), max(2, bar_h // 10)
        cv2.rectangle(ov, (x0, yb), (x0 + st['bar_px'] - 1, yb + bt - 1), fg, -1)
        lab = f"{st['bar_label_um']} um"
        tw = cv2.getTextSize(lab, font, fs, th)[0][0]
        cv2.putText(ov, lab, (x0 + (st['bar_px'] - tw) // 2, yb - int(bar_h * 0.15)), font, fs, fg, th,
                    cv2.LINE_AA)
        out[h - bar_h:] = np.round(ov.astype(np.float64) / 255 * maxv).astype(out.dtype)
        st.update(bar_text=txt, bar_fg=('white' if fg else 'black'))
    ta = sum(k['tensile_area_px'] for k in cracks)
    sa = sum(k['shear_area_px'] for k in cracks)
    return dict(image=out, pixel_size_um=float(st['pixel_size_um']),
                area_px=float(ta + sa), length_px=float(sum(k['length_px'] for k in cracks)),
                P=float(ta / sa) if sa > 0 else float('nan'), cracks=cracks,
                crack_mask=(cov_t + cov_s) >= 0.5, settings=st)


def make_image(shape=(768, 1024), seed=0):
    """Generate one synthetic SEM image of cracked rock with exact truth.

    Parameters
    ----------
    shape : tuple of int
        (height, width) in pixels.
    seed : int
        Seed of ``np.random.default_rng``; output is fully deterministic.

    Returns
    -------
    dict
        image (uint8 or uint16), pixel_size_um, area_px, length_px, P, cracks
        (list of dict: type, area_px, length_px, tensile_area_px, shear_area_px,
        subtype), crack_mask (coverage >= 0.5), settings (drawn appearance).
    """
    rng = np.random.default_rng(seed)
    h, w = shape
    f2 = h * w / (768 * 1024)
    st = dict(mode='SE' if rng.random() < 0.25 else 'BSE', n_phases=int(rng.integers(2, 6)),
              grain_px=float(rng.uniform(20, 120)), void_grey=float(rng.uniform(0, 50)),
              dark_phase=rng.choice(['', 'laths', 'blobs'], p=[0.55, 0.25, 0.2]).item(),
              dark_grey=float(rng.uniform(55, 85)), bar=bool(rng.random() < 0.2),
              charging=bool(rng.random() < 0.3), jitter=bool(rng.random() < 0.35),
              curtain=bool(rng.random() < 0.25), illum=rng.choice(['linear', 'radial']).item(),
              illum_ratio=float(rng.uniform(1, 2)), blur=float(rng.uniform(0.4, 1.3)),
              noise=rng.choice(['gauss', 'poisson']).item(), noise_sigma=float(rng.uniform(2, 8)),
              gamma=float(rng.uniform(0.75, 1.35)), uint16=bool(rng.random() < 0.25),
              pixel_size_um=float(rng.uniform(0.2, 3.0)))
    # ---- info bar geometry / pixel size --------------------------------------
    bar_h = int(round(h * rng.uniform(0.06, 0.09))) if st['bar'] else 0
    if st['bar']:
        nice = np.array([1, 2, 5, 10, 20, 25, 50, 100, 200, 250, 500, 1000, 2000])
        px = nice / st['pixel_size_um']
        ok = np.flatnonzero((px > 0.08 * w) & (px < 0.3 * w))
        lab_um = int(nice[ok[0]] if len(ok) else nice[np.argmin(np.abs(px - 0.15 * w))])
        bar_px = int(round(lab_um / st['pixel_size_um']))
        st['pixel_size_um'] = lab_um / bar_px
        st.update(bar_label_um=lab_um, bar_px=bar_px, bar_h=bar_h)
    h_use = h - bar_h - (3 if bar_h else 0)
    # ---- cracks --------------------------------------------------------------
    wts = rng.dirichlet([1.5, 1.2, 0.8]) if rng.random() > 0.05 else np.array([1.0, 0, 0])
    st['type_weights'] = wts.round(3).tolist()
    n_target = int(round(rng.integers(6, 31) * f2))
    cov_t, cov_s, cov_p = (np.zeros(shape, np.float32) for _ in range(3))
    occ = np.zeros(shape, bool)
    kern = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * GAP + 1,) * 2)
    cracks, placed, debris = [], [], []

    def _try_add(traces, kind, sub):
        res = _rasterise(traces, (h_use, w))
        if res is None:
            return False
        y0, x0, ct, cs = res
        c = ct + cs
        box = np.s_[y0:y0 + c.shape[0], x0:x0 + c.shape[1]]
        if c.sum() == 0 or (occ[box] & (c > 0)).any():
            return False
        occ[box] |= cv2.dilate((c > 0).astype(np.uint8), kern).astype(bool)
        cov_t[box] += ct
        cov_s[box] += cs
        cracks.append(dict(type=kind, subtype=sub, area_px=float(c.sum()),
                           length_px=float(sum(_trace_length(t) for t in traces)),
                           tensile_area_px=float(ct.sum()), shear_area_px=float(cs.sum())))
        placed.append(traces)
        return True

    tries = 0
    while len(cracks) < n_target and tries < 60 * n_target:
        tries += 1
        kind = ['tensile', 'shear', 'mixed'][rng.choice(3, p=wts)]
        length = float(np.clip(np.exp(rng.normal(np.log(110), 0.6)), 30, 450) * f2 ** 0.25)
        curv = rng.uniform(0, 0.6) / length      # total turning ~ N(0, <0.6 rad)
        if placed and rng.random() < 0.15:       # branch off an existing crack
            kind = 'tensile' if rng.random() < 0.7 else kind
            ptr = placed[rng.integers(len(placed))][0]
            i = int(rng.uniform(0.2, 0.8) * len(ptr['w']))
            side = rng.choice([-1, 1])
            tang = np.array([ptr['nrm'][i, 1], -ptr['nrm'][i, 0]]) * rng.choice([-1, 1])
            p0 = ptr['mid'][i] + side * ptr['nrm'][i] * (ptr['w'][i] / 2 + GAP + 2.5)
            a = rng.uniform(0.35, 0.9)
            d = tang * np.cos(a) + side * ptr['nrm'][i] * np.sin(a)
            theta, length, sub_br = float(np.arctan2(d[1], d[0])), length * 0.6, True
        else:
            p0 = rng.uniform([0, 0], [w, h_use])
            theta, sub_br = rng.uniform(0, 2 * np.pi), False
        traces, sub = _make_crack(rng, kind, p0, theta, length, curv)
        if traces and _try_add(traces, kind, ('branch ' if sub_br else '') + (sub or '')):
            for t in traces:                     # debris along shear stretches
                sh = np.flatnonzero((t['label'] == 2) & (t['w'] > 0))
                for j in sh[rng.random(len(sh)) < DS / 25]:
                    debris.append(('in', t['mid'][j], t['nrm'][j], t['w'][j]))
                for j in sh[rng.random(len(sh)) < DS / 40]:
                    debris.append(('out', t['mid'][j], t['nrm'][j], t['w'][j]))
    # ---- pores -----------------------------------------------------------------
    n_pores, npl = int(round(rng.integers(2, 9) * f2)), 0
    for _ in range(20 * n_pores):
        if npl >= n_pores:
            break
        r = rng.uniform(3, 12)
        res = _ellipse_cov(rng.uniform(0, w), rng.uniform(0, h_use), r, r * rng.uniform(0.5, 1),
                           rng.uniform(0, np.pi), (h_use, w))
        if res is not None:
            y0, x0, c, _ = res
            box = np.s_[y0:y0 + c.shape[0], x0:x0 + c.shape[1]]
            if not (occ[box] & (c > 0)).any():
                occ[box] |= cv2.dilate((c > 0).astype(np.uint8), kern).astype(bool)
                cov_p[box] += c
                npl += 1
    st['n_pores'] = npl
    return _render(rng, shape, st, cov_t, cov_s, cov_p, cracks, debris, bar_h)

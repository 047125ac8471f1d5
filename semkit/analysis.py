"""The analysis of one image: :class:`CrackAnalysis`, every stage a lazily computed attribute.

Each stage runs on first access (``functools.cached_property``), so a stage whose output is not
asked for never runs: without ``length`` there is no skeleton; without ``grains`` no grain map;
a pre-test image is never typed tensile / shear. The folder loop (:mod:`semkit.workflow`), the
CLI and ``gbmgen run`` all go through this one object.
"""
from __future__ import annotations

import functools
import typing

import numpy as np
import pandas as pd

from . import config
from .errors import InputError
from .options import AnalysisOptions

__all__ = ["CrackAnalysis", "analyse_image", "IMAGE_COLUMNS", "EXTRA_IMAGE_COLUMNS",
           "LOADED_STAGES"]

#: images.csv columns (DESIGN.md §4) in order; more follow.
IMAGE_COLUMNS = ["image", "pixel_size_um", "pixel_size_source", "threshold_method",
                 "threshold_value", "n_cracks", "crack_area_um2", "crack_length_um",
                 "area_T_um2", "area_S_um2", "P", "seconds"]
#: images.csv columns after :data:`IMAGE_COLUMNS`.
EXTRA_IMAGE_COLUMNS = ["valid", "valid_note", "image_area_um2", "crack_area_fraction",
                       "crack_density_per_mm", "threshold_ok", "threshold_note",
                       "contrast_to_noise", "scan_line_sigma", "roi",
                       "roi_fraction", "roi_ok", "data_bar_rows", "pixel_size_note", "n_thin",
                       "n_rejected", "n_pores", "pore_area_um2", "width_px", "height_px", "flatten",
                       "despeckle", "error"]
#: manifest stages of a loaded specimen (post-test cracks: tensile / shear typing applies).
LOADED_STAGES = tuple(s for s in config.STAGE_ORDER if s != "pre-test")


def _stage_name(stage):
    if stage is None or (isinstance(stage, float) and np.isnan(stage)):
        return None
    return str(stage)


def _centreline_px(cracks):
    """Each object's centreline length, px: ``length_px`` without its parallel traces
    (``n_traces``), so the validity shares weigh what was detected, not how many layers a
    merged band was read to hold."""
    return cracks["length_px"].to_numpy(float) / cracks["n_traces"].to_numpy(float)


class _FirstReading(typing.NamedTuple):
    """The rejection rules' reading of the objects before :attr:`CrackAnalysis.labels` cuts
    any: the evidence and verdicts of those objects, per new label where each came from
    (:func:`semkit.reject.split_zone_objects`; None when nothing was cut) and the zone relief
    (:func:`semkit.reject.zone_relief`)."""

    evidence: pd.DataFrame
    rejected_as: pd.Series
    origin: np.ndarray | None
    relief: np.ndarray


class CrackAnalysis:
    """Lazy analysis of one grey image; each attribute is one stage.

    Notation: M x N image, n objects after cleaning (cracks and pores), labels 1..n.

    Attributes (computed on first access)
    -------------------------------------
    flat, field : (M, N) float32
        Flattened image and illumination field (stage 2).
    smooth : (M, N) float32
        Denoised flattened image.
    thresholded : ThresholdResult
        Stage 3.
    object_mask, area_mask : (M, N) bool
        Cleaned objects (stage 4) and the pixels counted for area.
    labels : (M, N) int32 ; n_objects : int
        Crack (and pore) objects (stage 5). ``crack_labels`` has pores removed.
    skeleton : (M, N) bool
        Thin skeleton of ``object_mask`` (stage 6; only when ``options.length``).
    objects : DataFrame
        One row per object (:func:`semkit.measure.crack_table`), ``is_pore`` flags pores.
    cracks : DataFrame
        ``objects`` without pores, with the object label in ``crack_id``.
    grain_map : tuple or None
        ``(grain_labels, phase_labels, grains)`` when ``options.grains`` (stage 8).
    typed_cracks : DataFrame
        ``cracks`` with types, confidences and features (stage 7).
    """

    def __init__(self, image, *, pixel_size_um=config.DEFAULT_PIXEL_SIZE_UM,
                 pixel_size_source="cli", name="", options=None, stage=None, seed=None):
        from .io import to_grey
        img = to_grey(np.asarray(image))
        if img.ndim != 2 or img.size == 0:
            raise InputError(f"{name or 'image'}: expected a non-empty 2-D image")
        self._no_data = None
        #: the continuation pieces the ridge stage adds (set with the detection)
        self._continuations = None
        if img.dtype.kind == "f" and not np.isfinite(img).all():
            # NaN / inf pixels hold no data (a CT export's outside, a masked stitch): outside
            # the sample region, filled with the finite median until the region fills them
            finite = np.isfinite(img)
            if not finite.any():
                raise InputError(f"{name or 'image'}: image holds no finite pixel (all NaN "
                                 "or inf)")
            self._no_data = ~finite
            img = np.where(finite, img, np.median(img[finite])).astype(img.dtype)
        if not pixel_size_um > 0:
            raise InputError(f"pixel_size_um: expected > 0, got {pixel_size_um}")
        from .io import working_grey
        img = working_grey(img)
        self.options = options or AnalysisOptions()
        if self.options.bright_cracks:
            from .io import invert_grey
            img = invert_grey(img)
        self.raw_image = img
        self.pixel_size_um = float(pixel_size_um)
        self.pixel_size_source = pixel_size_source
        self.pixel_size_note = ""
        self.name = name
        self.stage = _stage_name(stage)
        self.seed = seed
        self.data_bar = self.scale_bar = None
        if self.options.roi == "auto":
            self._crop_data_bar()
        else:
            self.image = img
        if self.pixel_size_source == "default" and not self.pixel_size_note:
            self.pixel_size_note = _default_pixel_note(self.pixel_size_um, self.data_bar)

    # stage 1b: SEM data bar (cropped) and its scale bar
    def _crop_data_bar(self):
        from .databar import crop_data_bar
        c = crop_data_bar(self.raw_image, pixel_size_um=self.pixel_size_um,
                          pixel_size_source=self.pixel_size_source)
        self.image, self.data_bar, self.scale_bar = c.image, c.bar, c.scale_bar
        if self._no_data is not None and c.bar is not None:
            b = c.bar
            self._no_data = self._no_data[b.row1:] if b.side == "top" else \
                self._no_data[:b.row0]
        self.pixel_size_um, self.pixel_size_source = c.pixel_size_um, c.pixel_size_source
        self.pixel_size_note = c.note

    # stage 1c: sample region
    @functools.cached_property
    def region(self):
        """The sample region (:class:`semkit.roi.SampleRegion`) of ``image``; pixels that
        hold no data (NaN or inf in a float image) are outside it, whatever ``roi``."""
        from .roi import SampleRegion, find_sample_region, read_roi_mask, without_no_data
        roi = self.options.roi
        if roi == "none":
            r = SampleRegion(np.ones(self.image.shape, bool), "none", 1.0)
        elif roi != "auto":
            r = read_roi_mask(roi, self.image.shape)
        else:
            r = find_sample_region(self.image)
        return r if self._no_data is None else without_no_data(r, self._no_data)

    @functools.cached_property
    def _work_image(self):
        """``image`` with the pixels outside the sample region filled (see :mod:`semkit.roi`)."""
        from .roi import fill_outside
        r = self.region
        if r.fraction >= 1.0:
            return self.image
        out = fill_outside(self.image, r.mask)
        if self.image.dtype.kind in "ui":  # keep the input dtype
            out = np.rint(out).astype(self.image.dtype)
        return out

    # stage 2
    @functools.cached_property
    def _flat_field(self):
        from .illumination import flatten_illumination
        img = self._work_image
        if self.options.flatten == "none":
            return img.astype(np.float32), np.ones(img.shape, np.float32)
        return flatten_illumination(img, method=self.options.flatten)

    @property
    def flat(self):
        return self._flat_field[0]

    @property
    def field(self):
        return self._flat_field[1]

    @functools.cached_property
    def _scan_lines(self):
        """``(image, ScanLines or None)``: ``flat`` with its scan-line offsets removed when it
        has them (:mod:`semkit.scanlines`)."""
        if not self.options.scan_lines:
            return self.flat, None
        from .scanlines import remove_scan_lines
        return remove_scan_lines(self.flat)

    @functools.cached_property
    def smooth(self):
        from .cleanup import denoise
        return denoise(self._scan_lines[0], sigma_px=self.options.denoise_sigma_px)

    # stage 3
    @functools.cached_property
    def thresholded(self):
        from .threshold import crack_mask
        img = self.smooth
        if float(np.ptp(img)) == 0.0:
            raise InputError(f"{self.name or 'image'}: image is uniform (no contrast)")
        return crack_mask(img, method=self.options.threshold)

    @property
    def _segmenter_threshold(self):
        """The decision level on P(crack): ``segmenter_threshold`` when given, else the
        segmenter's own."""
        t = self.options.segmenter_threshold
        return float(self.options.segmenter.threshold if t is None else t)

    @property
    def _threshold(self):
        """:attr:`thresholded`, or None with a segmenter (its decision replaces the threshold's
        levels and background)."""
        return None if self.options.segmenter is not None else self.thresholded

    @functools.cached_property
    def ridge(self):
        """``(mask, depth)`` of thin dark lines (:func:`semkit.ridge.ridge_mask`), or None
        when the ridge detector is off or the threshold found no crack grey."""
        t = self.thresholded
        if not self.options.ridge or t.method != "auto" or not np.isfinite(t.crack_level):
            return None
        from .ridge import ridge_mask
        mask, depth, self._ridge_components = ridge_mask(
            self.smooth, crack_level=t.crack_level, region=self.region.mask,
            return_components=True)
        return mask, depth

    @functools.cached_property
    def detection(self):
        """``(detect_mask, area_mask)`` before cleaning: the threshold fused with the ridge
        lines, or the segmenter's decision when one is given; nothing outside the region."""
        seg = self.options.segmenter
        if seg is not None:
            # the segmenter sees the image as it was trained on (surround unfilled: a filled
            # surround shifts its wide-scale features tens of pixels into the sample)
            p = seg.crack_probability(self.image)
            det = area = np.asarray(p) >= self._segmenter_threshold
        else:
            t = self.thresholded
            det, area = t.detect_mask, t.mask
            if self.ridge is not None:
                from .ridge import add_ridge_lines
                det, area, self._continuations = add_ridge_lines(
                    det, area, *self.ridge, components=self._ridge_components,
                    return_continuations=True)
                if self.options.link:
                    det, area = self._linked(det, area)
        inside = self.region.mask
        return det & inside, area & inside

    #: stages the unlinked first pass shares with this analysis (all before detection)
    _SHARED = ("region", "_work_image", "_flat_field", "_scan_lines", "smooth", "thresholded",
               "ridge")

    @functools.cached_property
    def unlinked(self):
        """This analysis without linking (:mod:`semkit.link`): the first pass, whose accepted
        objects seed the lines and whose rejected ones no line may join. Shares the stages
        up to the ridge lines; None when nothing is linked."""
        if not self.options.link or self.options.segmenter is not None or self.ridge is None:
            return None
        import dataclasses
        first = CrackAnalysis.__new__(CrackAnalysis)
        first.__dict__.update({k: v for k, v in self.__dict__.items()
                               if not isinstance(getattr(CrackAnalysis, k, None),
                                                 functools.cached_property)
                               or k in self._SHARED})
        first.options = dataclasses.replace(self.options, link=False)
        return first

    def _linked(self, det, area):
        """``det, area`` with the lines (:func:`semkit.link.link_lines`) that continue or join
        the first pass's accepted cracks. Objects it rejected for their own shape (and pores)
        may be passed through; those rejected for their surroundings
        (``LINK_EXCLUDE_RULES``) are kept ``LINK_EXCLUDE_PX`` away from."""
        import cv2

        from .link import add_link_lines, link_lines
        first = self.unlinked
        o = first._classified_objects
        ids = o["crack_id"].to_numpy()
        rej = o["rejected_as"].to_numpy()
        kind = np.zeros(first.n_objects + 1, np.int8)  # 0 seed, 1 passable, 2 excluded
        kind[ids[rej != ""]] = 1
        if self.options.exclude_pores:
            kind[ids[o["is_pore"].to_numpy(bool)]] = 1
        kind[ids[np.isin(rej, config.LINK_EXCLUDE_RULES)]] = 2
        objects = first.object_mask
        k_obj = kind[first.labels]
        excluded = objects & (k_obj == 2)
        k = 2 * config.LINK_EXCLUDE_PX + 1
        near = cv2.dilate(excluded.view(np.uint8), np.ones((k, k), np.uint8)).view(bool)
        lines = link_lines(self.smooth, objects & (k_obj == 0),
                           crack_level=self.thresholded.crack_level,
                           passable=objects & (k_obj == 1), exclude=near,
                           region=self.region.mask, detected=first.detection[0])
        return add_link_lines(det, area, lines, self.smooth, self.ridge[1],
                              crack_level=self.thresholded.crack_level)

    # stage 4
    @functools.cached_property
    def _masks(self):
        from . import cleanup
        det, area = self.detection
        if self.options.despeckle == "median":  # ImageJ: one binary, then a 3 x 3 median
            det = area = cleanup.despeckle_median(area)
        elif self.options.despeckle == "specks":
            det = cleanup.remove_specks(det)
        if self.options.min_area_um2:
            det = cleanup.remove_small_objects(
                det, min_area_px=self.options.min_area_um2 / self.pixel_size_um ** 2)
        if self.options.bridge_gaps:
            det = cleanup.bridge_gaps(det)
        filled = cleanup.fill_holes(det, max_hole_px=self.options.max_hole_px)
        area = (area & det) | (filled & ~det)
        inside = self.region.mask
        return filled & inside, area & inside

    @property
    def object_mask(self):
        return self._masks[0]

    @property
    def area_mask(self):
        return self._masks[1]

    # stage 5
    @functools.cached_property
    def _labels(self):
        """Objects: the 8-connected components of the cleaned mask, with those rejected as
        ``dark_phase`` cut where they leave the dark phase (:func:`semkit.reject.
        split_zone_objects`; the pieces in clear rock are judged on their own), and the
        rules' first reading (:class:`_FirstReading`; None without the rules)."""
        from .measure import label_cracks
        lab, n = label_cracks(self.object_mask)
        if not self.options.reject or n == 0:
            return lab, n, None
        from .reject import reject_objects, split_zone_objects, zone_relief
        relief = zone_relief(self.smooth, self.crack_level, self.region.mask)
        ev = self._object_evidence(lab, n, relief)
        why = reject_objects(ev)
        cut = split_zone_objects(lab, n, why.to_numpy(), relief)
        if cut is None:
            return lab, n, _FirstReading(ev, why, None, relief)
        lab, n, origin = cut
        return lab, n, _FirstReading(ev, why, origin, relief)

    @property
    def labels(self):
        return self._labels[0]

    @property
    def n_objects(self):
        return self._labels[1]

    # stage 6
    @functools.cached_property
    def skeleton(self):
        from .skeleton import prune_spurs, skeletonize
        return prune_spurs(skeletonize(self.object_mask), self.object_mask)

    @functools.cached_property
    def objects(self):
        from .measure import crack_table, mixed_area, partial_volume_area
        t = crack_table(self.labels, self.n_objects, pixel_size_um=self.pixel_size_um,
                        skeleton=self.skeleton if self.options.length else None,
                        area_mask=self.area_mask, image_name=self.name)
        t["area_method"] = "count"
        th = self._threshold
        if th is None or th.background is None or not len(t):
            return t
        px = self.pixel_size_um
        if self.options.area == "mixed":
            # partial volume on every cross-section whose core is not resolved, also inside
            # wide cracks; the midpoint count on the others
            area, pv = mixed_area(self.smooth, self.labels, self.n_objects,
                                  skeleton=self.skeleton, background=th.background,
                                  crack_level=self.void_level[0], area_mask=self.area_mask)
            ids = t["crack_id"].to_numpy()
            t["area_px"] = area[ids]
            t["area_um2"] = area[ids] * px * px
            with np.errstate(divide="ignore", invalid="ignore"):
                t["mean_aperture_um"] = np.where(t["length_px"] > 0,
                                                 area[ids] / t["length_px"].to_numpy(),
                                                 np.nan) * px
            t["area_method"] = np.where(pv[ids] >= 1.0, "partial_volume",
                                        np.where(pv[ids] > 0.0, "mixed", "count"))
        elif t["thin"].any():
            # thin cracks never reach the midpoint: their area is their partial volume
            thin = t["thin"].to_numpy()
            ids = t["crack_id"].to_numpy()[thin]
            pv = partial_volume_area(self.smooth, self.labels, self.n_objects,
                                     background=th.background, crack_level=self.void_level[0],
                                     ids=ids)
            t.loc[thin, "area_px"] = pv[ids]
            t.loc[thin, "area_um2"] = pv[ids] * px * px
            t.loc[thin, "mean_aperture_um"] = (pv[ids] / t.loc[thin, "length_px"].to_numpy()
                                               * px)
            t.loc[thin, "area_method"] = "partial_volume"
        if self.options.length:
            # a layered crack's traces, merged into one object, each count in its length;
            # read before denoising, whose blur merges traces 2.5-3 px apart
            from .measure import parallel_traces
            raw = self._scan_lines[0]
            f = parallel_traces(raw, self.labels, self.n_objects, skeleton=self.skeleton,
                                background=th.background, crack_level=th.crack_level,
                                samples=self._trace_samples)[t["crack_id"].to_numpy()]
            t["n_traces"] = f
            t["length_px"] *= f
            t["length_um"] *= f
            t["mean_aperture_um"] /= f
        return t

    @functools.cached_property
    def _trace_samples(self):
        """The cross-sections read for parallel traces (:func:`semkit.measure.trace_samples`,
        on the image before denoising, whose blur merges traces 2.5-3 px apart)."""
        from .measure import trace_samples
        from .threshold import noise_sigma
        th = self._threshold
        raw = self._scan_lines[0]
        return trace_samples(raw, self.labels, skeleton=self.skeleton, background=th.background,
                             crack_level=th.crack_level, noise=noise_sigma(raw))

    @functools.cached_property
    def void_level(self):
        """``(grey, note)``: the void grey the areas are measured against, and why it differs
        from the threshold's ``void_level`` (else "").

        A void read on plateaus is checked against the cracks' cross-sections: when nearly
        all the crack pixels at that grey (within the plateau band) lie on cross-sections
        read as two or more traces (``LAYERED_VOID_MIN_SHARE``), the plateau is a layered
        crack's traces merged by the denoising into a band of partial-volume grey, and the
        void is taken as when no crack shows its core (``THIN_ONLY_CRACK_RATIO`` of the
        darkest mineral at most). None without the ``auto`` threshold."""
        th = self._threshold
        if th is None or th.background is None:
            return None, ""
        void = float(th.void_level)
        if not (th.void_read and np.isfinite(void)) or self.n_objects == 0:
            return void, ""
        from .measure import layered_share
        mineral = th.crack_level + th.contrast
        band = max(config.VOID_PLATEAU_BAND * th.noise,
                   config.VOID_PLATEAU_CONTRAST * (mineral - void))
        share = layered_share(self.object_mask & (self.smooth <= void + band),
                              *self._trace_samples)
        if not share >= config.LAYERED_VOID_MIN_SHARE:
            return void, ""
        assumed = min(void, config.THIN_ONLY_CRACK_RATIO * mineral)
        return assumed, (
            f"the void grey read on plateaus ({void:.4g}) lies {share:.0%} on cross-sections "
            "of two or more traces: a layered crack's traces merged by the denoising, not the "
            f"void; areas are measured against a void taken as {assumed:.4g}, at most "
            f"{config.THIN_ONLY_CRACK_RATIO:g} x the darkest mineral")

    @functools.cached_property
    def crack_level(self):
        """Crack core grey (the ``auto`` threshold's, else the dark-class analysis's)."""
        t = self._threshold
        if t is not None and np.isfinite(t.crack_level):
            return float(t.crack_level)
        from .threshold import dark_class_levels
        lv = dark_class_levels(self.smooth)
        return float(lv.crack) if np.isfinite(lv.crack) else float(np.percentile(
            self.smooth[self.region.mask], config.DARKEST_PERCENT))

    def _object_evidence(self, labels, n, relief=None):
        from .reject import object_evidence
        from .threshold import noise_sigma
        t = self._threshold
        return object_evidence(labels, n, self.smooth, crack_level=self.crack_level,
                               noise=noise_sigma(self.smooth),
                               void_level=None if t is None else t.void_level,
                               skeleton=self.skeleton if self.options.length else None,
                               region=self.region.mask, relief=relief)

    @functools.cached_property
    def evidence(self):
        """Shape and surroundings of every object (:func:`semkit.reject.object_evidence`).
        Objects that :attr:`labels` left as they were keep their first reading (cut pieces
        next to them would otherwise count as neighbours of theirs)."""
        labels, n, first = self._labels
        if first is not None and first.origin is None:
            return first.evidence
        ev = self._object_evidence(labels, n, None if first is None else first.relief)
        if first is not None:
            origin = first.origin[1:]
            keep = origin > 0
            ev.iloc[np.flatnonzero(keep)] = first.evidence.loc[origin[keep]].to_numpy()
        return ev

    @functools.cached_property
    def rejected_as(self):
        """Per object (index = label): why it is not a crack, ``""`` when it is one (the rest
        of an object cut by :attr:`labels` keeps the verdict of the whole)."""
        if not self.options.reject or self.n_objects == 0:
            return pd.Series("", index=np.arange(1, self.n_objects + 1), dtype=object)
        first = self._labels[2]
        if first.origin is None:
            return first.rejected_as
        from .reject import reject_objects
        why = reject_objects(self.evidence)
        why[first.origin[1:] < 0] = "dark_phase"
        return why

    @functools.cached_property
    def _classified_objects(self):
        o = self.objects.copy()
        o["rejected_as"] = self.rejected_as.reindex(o["crack_id"]).fillna("").to_numpy()
        if self.options.exclude_pores:
            o.loc[o["is_pore"].to_numpy(bool), "rejected_as"] = ""
        return o

    @functools.cached_property
    def cracks(self):
        """Objects that are cracks: no pore (with ``exclude_pores``), nothing rejected."""
        o = self._classified_objects
        keep = o["rejected_as"] == ""
        if self.options.exclude_pores:
            keep &= ~o["is_pore"]
        return o[keep].reset_index(drop=True)

    @functools.cached_property
    def rejected(self):
        """Objects rejected as not cracks, with ``rejected_as`` (see :mod:`semkit.reject`)."""
        o = self._classified_objects
        return o[o["rejected_as"] != ""].reset_index(drop=True)

    @functools.cached_property
    def crack_labels(self):
        """Labels of cracks only (pores set to 0); ids match ``cracks.crack_id``."""
        keep = np.zeros(self.n_objects + 1, bool)
        keep[self.cracks["crack_id"].to_numpy()] = True
        if keep[1:].all():
            return self.labels
        from ._kernels import lookup
        return np.where(lookup(keep, self.labels), self.labels, 0).astype(np.int32, copy=False)

    # stage 8: grains
    @functools.cached_property
    def grain_map(self):
        """``(grain_labels, phase_labels, grains)`` or None without ``options.grains``."""
        if not self.options.grains:
            return None
        from .grains import grains_stage, parse_minerals
        names, n = parse_minerals(self.options.minerals)
        lab, ph, g = grains_stage(self.flat, mask=self.object_mask | ~self.region.mask,
                                  pixel_size_um=self.pixel_size_um, names=names, n_phases=n,
                                  seed=self.seed, alt_image=self._work_image)
        g.insert(0, "image", self.name)
        return lab, ph, g

    # stage 7: crack types
    @property
    def typing_post(self):
        """True when this image's cracks are typed tensile / shear / mixed (see
        :attr:`AnalysisOptions.classify`: by default only on loaded stages of the manifest)."""
        c = self.options.classify
        if c is None:
            return self.stage in LOADED_STAGES
        return bool(c) and self.stage != "pre-test"

    @functools.cached_property
    def typed_cracks(self):
        """``cracks`` with types, confidences, features and ``area_pv_um2`` (stage 7)."""
        if not (self.typing_post or self.grain_map is not None):
            return self.cracks
        from .classify import classify_stage, load_model
        model = load_model(self.options.crack_model) if self.options.crack_model else None
        th = self._threshold
        return classify_stage(self.cracks, self.crack_labels, grey=self.smooth,
                              pixel_size_um=self.pixel_size_um, model=model,
                              post=self.typing_post,
                              grain_labels=None if self.grain_map is None else self.grain_map[0],
                              skeleton=self.skeleton,
                              background=None if th is None else th.background,
                              crack_level=None if th is None else th.crack_level,
                              void_level=self.void_level[0])

    def full_size(self, a):
        """``a`` (an array of ``image``'s shape) padded back to the raw image's shape: the
        cropped data bar rows are 0."""
        bar = self.data_bar
        if bar is None:
            return a
        out = np.zeros(self.raw_image.shape, a.dtype)
        if bar.side == "top":
            out[bar.row1:] = a
        else:
            out[:bar.row0] = a
        return out

    def crack_rows(self) -> pd.DataFrame:
        """The rows this image contributes to ``cracks.csv``: the cracks, then the rejected
        objects (``rejected_as`` says why; they count in no sum)."""
        rej = self.rejected
        if not len(rej):
            return self.typed_cracks
        rej = rej.assign(type_post="unknown", type_pre="unknown", confidence=np.nan)
        return pd.concat([self.typed_cracks, rej], ignore_index=True)

    def _damage_fields(self):
        nan = float("nan")
        status = "pre-test" if self.stage == "pre-test" else None
        if not self.typing_post:
            return dict(area_T_um2=nan, area_S_um2=nan, area_M_um2=nan, P=nan,
                        P_status=status or "not_classified")
        c = self.typed_cracks
        if not len(c):
            return dict(area_T_um2=0.0, area_S_um2=0.0, area_M_um2=0.0, P=nan,
                        P_status="no_cracks")
        from .damage import image_damage
        d = image_damage(c.assign(image=self.name)).iloc[0]
        return dict(area_T_um2=float(d.area_T_um2), area_S_um2=float(d.area_S_um2),
                    area_M_um2=float(d.area_mixed_um2), P=float(d.P), P_status=d.P_status,
                    P_low=float(d.get("P_low", nan)), P_high=float(d.get("P_high", nan)),
                    P_note=str(d.get("P_note", "")))

    def summary(self) -> dict:
        """The row this image contributes to ``images.csv`` (``seconds`` is set by the caller).

        ``area_T_um2, area_S_um2, area_M_um2, P, P_status`` come from the crack types
        (P = A_T/A_S, Equ. 3-1); NaN with a status when the image is not typed. A P that
        the typing supports is still ``low_confidence`` when the row is not ``valid``: its
        areas are what the flags question.
        """
        c = self.cracks
        o = self.objects
        pores = o[o["is_pore"] & (self._classified_objects["rejected_as"] == "")] \
            if self.options.exclude_pores else o.iloc[:0]
        area = float(c["area_um2"].sum())
        reg = self.region
        image_area = float(reg.mask.sum()) * self.pixel_size_um ** 2
        nan = float("nan")
        length = float(c["length_um"].sum()) if self.options.length else nan
        row = dict(image=self.name, pixel_size_um=self.pixel_size_um,
                   pixel_size_source=self.pixel_size_source, **self._threshold_fields(),
                   n_cracks=int(len(c)), crack_area_um2=area,
                   crack_length_um=length, area_T_um2=nan, area_S_um2=nan, P=nan, seconds=nan,
                   image_area_um2=image_area, crack_area_fraction=area / image_area,
                   crack_density_per_mm=length / image_area * 1e3,
                   n_thin=int(c["thin"].sum()), n_pores=int(len(pores)),
                   n_rejected=int(len(self.rejected)),
                   pore_area_um2=float(pores["area_um2"].sum()),
                   width_px=int(self.image.shape[1]), height_px=int(self.image.shape[0]),
                   flatten=self.options.flatten, despeckle=self.options.despeckle, error="")
        bar = self.data_bar
        sl = self._scan_lines[1]
        row["scan_line_sigma"] = sl.sigma if sl is not None and sl.removed else float("nan")
        row.update(roi=reg.kind, roi_fraction=reg.fraction, roi_ok=reg.ok,
                   data_bar_rows=f"{bar.row0}-{bar.row1}" if bar else "",
                   pixel_size_note=self.pixel_size_note)
        row.update(self._damage_fields())
        row.update(self._validity(row))
        if not row["valid"] and row["P_status"] == "ok":
            # P = A_T / A_S rests on the areas the flags call into question
            row["P_status"] = "low_confidence"
            row["P_note"] = "the image's figures are not valid (valid_note)"
        return row

    def _threshold_fields(self):
        seg = self.options.segmenter
        if seg is not None:
            return dict(threshold_method="segmenter", threshold_value=self._segmenter_threshold,
                        threshold_ok=True, threshold_note="", contrast_to_noise=float("nan"))
        t = self.thresholded
        note = "; ".join(n for n in (t.note, self.void_level[1]) if n)
        return dict(threshold_method=t.method, threshold_value=t.value, threshold_ok=bool(t.ok),
                    threshold_note=note, contrast_to_noise=t.contrast_to_noise)

    def _validity(self, row):
        """``valid`` and ``valid_note``: False with the reasons when a number of the row is
        not to be trusted (threshold check failed, sample region too small, ...)."""
        notes = []
        if not row["threshold_ok"]:
            notes.append(f"threshold: {row['threshold_note']}")
        if not row["roi_ok"]:
            notes.append(f"roi: {self.region.note}")
        if row["pixel_size_note"]:
            notes.append(f"pixel size: {row['pixel_size_note']}")
        sat = self._saturated_share()
        if sat >= config.SATURATED_MAX_SHARE:
            notes.append(f"saturated: {sat:.1%} of the sample is at its brightest grey "
                         "(clipped): cracks through those grains read narrow or are lost")
        cnr = row["contrast_to_noise"]
        if cnr < config.MIN_CONTRAST_TO_NOISE and row["n_cracks"] > 0:
            notes.append(f"noise: the crack contrast is {cnr:.1f} sigmas of the fine-scale "
                         f"noise (under {config.MIN_CONTRAST_TO_NOISE:g}, noise specks pass for "
                         "cracks and faint cracks are lost)")
        walls = self._bright_walls()
        if walls >= config.BRIGHT_WALLS_MIN_LIFT:
            notes.append(f"bright walls: the grey beside the cracks lies {walls:.2f} of the crack "
                         "contrast above the rock around them (median), an edge effect "
                         "(secondary electrons) or a phase-contrast fringe: partial-volume "
                         "widths read narrow and thin cracks between bright walls are lost")
        faint = self._faint_length_share()
        if faint >= config.FAINT_MAX_LENGTH_SHARE:
            notes.append(f"faint lines: {faint:.0%} of the crack centreline lies less than "
                         f"{config.FAINT_LINE_DEPTH:g} of the crack contrast below its "
                         "surroundings (grain boundaries or faint cracks): check the overlay")
        thin = self._thin_length_share()
        if thin >= config.THIN_MAX_LENGTH_SHARE:
            notes.append(f"thin cracks: {thin:.0%} of the crack centreline lies in cracks under "
                         f"{config.THIN_POPULATION_WIDTH_PX:g} px wide: the cracks reach the "
                         "detection limit (a thin crack under blur is faint), so thinner ones "
                         "are likely missed (length is then a lower bound) and areas rest on "
                         "partial volumes")
        speck = self._speckle_length_share()
        if speck >= config.SPECKLE_MAX_LENGTH_SHARE:
            win = config.ZONE_NEIGHBOUR_WINDOW_PX
            notes.append(f"specks: {speck:.0%} of the crack centreline lies in short objects "
                         f"(under {config.SPECKLE_MAX_LENGTH_PX:g} px) with "
                         f"{config.SPECKLE_MIN_NEIGHBOURS} or more others in the "
                         f"{win} x {win} px window around them: a speckled texture (dusty "
                         "or altered grains, inclusions), not a crack pattern: check the "
                         "overlay")
        cont = self._continuation_share()
        if cont >= config.CONTINUATION_MAX_SHARE:
            notes.append(f"faint continuations: ridge lines carry on from the detected cracks "
                         f"({cont:.2f} px per px of crack centreline) where the threshold found "
                         "nothing: faint parts of the cracks or grain boundaries they meet "
                         "(pieces at least 0.2 of the contrast deep are counted as crack): "
                         "check the overlay")
        phase = self.thresholded.dark_phase_share if self.options.segmenter is None else 0.0
        gap = self._void_gap() if phase >= config.DARK_PHASE_MIN_SHARE else 0.0
        if gap >= config.DARK_PHASE_MAX_GAP:
            notes.append(f"dark phase: the dark class's grey lies {gap:.2f} of the contrast "
                         f"above the void grey of the open cracks, and {phase:.0%} of its flat "
                         "cores are plateaus brighter than the void: a brighter dark phase "
                         "(laths, a dark mineral) is in the dark class and may be counted as "
                         "crack: check the overlay")
        share, by_rule = self._zone_rejected_share()
        if share >= config.REJECT_MAX_ZONE_SHARE:
            rules = ", ".join(f"{k} {v:.0%}" for k, v in by_rule.items())
            kept = "; lone_line: kept, a lone line in a dark zone" if "lone_line" in by_rule \
                else ""
            notes.append(f"rejection: {share:.0%} of the dark area was judged by the zone and "
                         f"shape rules ({rules}{kept}); the figures depend on them: check the "
                         "overlay")
        if row["n_cracks"] == 0 and self.options.reject and len(self.rejected):
            kinds = self.rejected["rejected_as"].value_counts()
            notes.append(f"nothing kept: the rules rejected every dark object detected "
                         f"({', '.join(f'{v} {k}' for k, v in kinds.items())}), so the "
                         "crack-free reading rests on them: check the overlay")
        return dict(valid=not notes, valid_note="; ".join(notes))

    def _saturated_share(self):
        """Share of the sample region (every other pixel) at the image's brightest grey: a
        plateau there is clipping (detector saturation), not a mineral."""
        r = self.region.mask[::2, ::2]
        v = self.image[::2, ::2][r]
        return float(np.count_nonzero(v == v.max())) / v.size if v.size else 0.0

    def _bright_walls(self):
        """How far the grey beside the accepted cracks (``BRIGHT_WALLS_NEAR_PX`` from them)
        lies above the rock around the same place: the median, over those wall pixels, of the
        grey minus the mean grey of the rock ``BRIGHT_WALLS_FAR_PX`` from every detected object
        within ``BRIGHT_WALLS_WINDOW_PX`` of the pixel, as a share of the crack contrast (the
        sample's median local background minus the void grey). Each wall pixel is compared with
        the rock of its own neighbourhood, so grains of other greys beside a crack weigh as
        little as they do around it. Read on the image at half size (2 x 2 blocks: a block is
        crack or object when any of its pixels is; its grey, every other pixel's). NaN without
        the ``auto`` threshold, with a segmenter, or with fewer than
        ``BRIGHT_WALLS_MIN_WALL_PX`` wall pixels compared. The blurred wall of a crack is
        darker than the rock; an edge effect or a fringe makes it brighter."""
        th = self._threshold
        if self.options.segmenter is not None or th is None or th.background is None \
                or self.cracks.empty:
            return float("nan")
        import cv2

        def free(labels):   # half-size blocks holding no object pixel, as uint8
            m = cv2.dilate((labels > 0).view(np.uint8), np.ones((2, 2), np.uint8),
                           anchor=(0, 0))[::2, ::2]
            return np.ascontiguousarray(m ^ 1)

        d = 2.0 * cv2.distanceTransform(free(self.crack_labels), cv2.DIST_L2, 3)
        d_all = d if self.crack_labels is self.labels else \
            2.0 * cv2.distanceTransform(free(self.labels), cv2.DIST_L2, 3)
        region = self.region.mask[::2, ::2]
        img = np.ascontiguousarray(np.asarray(self.smooth, np.float32)[::2, ::2])
        (n0, n1), (f0, f1) = config.BRIGHT_WALLS_NEAR_PX, config.BRIGHT_WALLS_FAR_PX
        rock = ((d >= f0) & (d <= f1) & (d_all >= f0) & region).astype(np.float32)
        win = (config.BRIGHT_WALLS_WINDOW_PX // 2) | 1
        total = cv2.boxFilter(img * rock, -1, (win, win), normalize=False)
        count = cv2.boxFilter(rock, -1, (win, win), normalize=False)
        wall = (d >= n0) & (d <= n1) & region & (count >= config.BRIGHT_WALLS_MIN_PX)
        if np.count_nonzero(wall) < config.BRIGHT_WALLS_MIN_WALL_PX:
            return float("nan")
        contrast = self._background_grey - float(self.void_level[0])
        if not contrast > 0:
            return float("nan")
        return float(np.median(img[wall] - total[wall] / count[wall])) / contrast

    def _faint_length_share(self):
        """Share of the crack centreline length (:func:`_centreline_px`) in objects whose core
        lies less than ``FAINT_LINE_DEPTH`` of the contrast below their darker side
        (``side_depth``); 0 when the rejection rules are off (no evidence is measured then).
        The objects rejected as ``phase_edge`` (all faint) count with the cracks: the rule
        removes the boundary segments on a step between phases, not the evidence that
        boundaries in this image are as dark as faint cracks (a stress image whose boundaries
        read length +103 % fell from 21 % to under the flag without them). So do those
        rejected as ``noise`` and ``faint_texture``, for the same reason."""
        if not self.options.reject or self.cracks.empty or not self.options.length:
            return 0.0
        o = self._classified_objects
        c = o[o["rejected_as"].isin(["", "phase_edge", "faint_texture", "noise"])]
        depth = self.evidence["side_depth"].reindex(c["crack_id"]).to_numpy()
        length = _centreline_px(c)
        total = float(length.sum())
        return float(length[depth < config.FAINT_LINE_DEPTH].sum()) / total if total > 0 else 0.0

    def _speckle_length_share(self):
        """Share of the crack centreline length (:func:`_centreline_px`) in short objects
        (centreline under ``SPECKLE_MAX_LENGTH_PX``) with ``SPECKLE_MIN_NEIGHBOURS`` or more
        other objects around them (``neighbours`` of :func:`semkit.reject.object_evidence`);
        0 when the rejection rules are off (no evidence is measured then). Cracks, even a
        network with its debris, are few long objects; specks in a dusty or altered grain are
        many short ones together. The objects rejected as ``noise`` and ``faint_texture``
        count with the cracks: the rules remove the specks, not the evidence that the image
        is speckled."""
        if not self.options.reject or self.cracks.empty or not self.options.length:
            return 0.0
        o = self._classified_objects
        keep = o["rejected_as"].isin(["", "faint_texture", "noise"])
        if self.options.exclude_pores:  # pores are no cracks here, as in self.cracks
            keep &= ~o["is_pore"]
        c = o[keep]
        length = _centreline_px(c)
        crowd = self.evidence["neighbours"].reindex(c["crack_id"]).to_numpy()
        short = (length < config.SPECKLE_MAX_LENGTH_PX) & (crowd >= config.SPECKLE_MIN_NEIGHBOURS)
        total = float(length.sum())
        return float(length[short].sum()) / total if total > 0 else 0.0

    def _thin_length_share(self):
        """Share of the crack centreline length (:func:`_centreline_px`) in cracks whose mean
        width (``area_px`` over centreline) is under ``THIN_POPULATION_WIDTH_PX``: how much of
        the crack population lies near the detection limit (0 without a length)."""
        if self.cracks.empty or not self.options.length:
            return 0.0
        c = self.cracks
        length = _centreline_px(c)
        width = c["area_px"].to_numpy(float) / np.maximum(length, 1.0)
        total = float(length.sum())
        return float(length[width < config.THIN_POPULATION_WIDTH_PX].sum()) / total \
            if total > 0 else 0.0

    def _continuation_share(self):
        """Pixels of ridge lines that touch a detected object but run on more than 2 px
        from every detected pixel, per px of crack centreline (:func:`_centreline_px`; 0
        without the ridge detector, a segmenter or a length): how much of the cracks'
        continuation was left out. Objects the rules rejected count as detected: a crack in a
        dark mineral rejected as ``dark_phase`` and carried on by a ridge line is a crack found
        in part (development seed 10: 0.18; counting accepted cracks only, 0.07). The
        continuation pieces the ridge stage added (:func:`semkit.ridge.add_ridge_lines`) count
        as left out: they rest on the ridge response alone, and a grain boundary carries a
        line on as well as a crack (a test image of 30-px grains: three boundary pieces
        added)."""
        if self.ridge is None or self.options.segmenter is not None \
                or not self.options.length:
            return 0.0
        import cv2

        from ._kernels import lookup
        ridge, _ = self.ridge
        lab, keep = self._ridge_components
        det = (self.detection[0] & ~self._continuations).view(np.uint8)
        near = cv2.dilate(det, np.ones((3, 3), np.uint8)).view(bool)
        touching = np.zeros(keep.size, bool)
        touching[lab[near & ridge]] = True
        touching[0] = False
        far = ridge & lookup(touching, lab) & ~cv2.dilate(det, np.ones((5, 5), np.uint8)).view(bool)
        length = float(_centreline_px(self.cracks).sum()) if not self.cracks.empty else 0.0
        return float(np.count_nonzero(far)) / length if length > 0 else 0.0

    @functools.cached_property
    def _background_grey(self):
        """The sample's median local background grey (the ``auto`` threshold's, every 4th
        pixel of the region; NaN without it)."""
        th = self._threshold
        if th is None or th.background is None:
            return float("nan")
        return float(np.median(th.background[::4, ::4][self.region.mask[::4, ::4]]))

    def _void_gap(self):
        """How far the dark class's median grey (``crack_level``) lies above the void grey
        (``void_level``), as a share of the contrast from it to the sample's median local
        background (read on every 4th pixel; 0 without the ``auto`` threshold or with a
        segmenter). A dark class made of open cracks stays within a tenth of the contrast of
        its void; one that holds a brighter dark phase, or the partly resolved cores of many
        thin cracks, is pulled up."""
        if self.options.segmenter is not None:
            return 0.0
        t = self.thresholded
        if t.method != "auto" or not (np.isfinite(t.crack_level) and np.isfinite(t.void_level)) \
                or t.background is None or not t.mask.any():
            return 0.0
        return float((t.crack_level - t.void_level)
                     / max(self._background_grey - t.crack_level, 1e-3))

    def _zone_rejected_share(self):
        """Share of the dark objects' area (pores aside) that the zone and shape rules
        decided: rejected, in all and per rule (``phase_rim``, ``phase_edge`` and
        ``faint_texture``, boundary segments and rim bits, are not counted; ``noise`` is), and
        kept only as lone lines in a dark zone (``lone_line``,
        :func:`semkit.reject.kept_lone_lines`): either way the figures rest on the rules."""
        o = self._classified_objects
        o = o[~o["is_pore"].to_numpy(bool)] if self.options.exclude_pores else o
        total = float(o["area_px"].sum())
        if total <= 0 or not self.options.reject:
            return 0.0, {}
        from .reject import kept_lone_lines
        lone = kept_lone_lines(self.evidence, self.rejected_as)
        lone_ids = lone.index[lone.to_numpy(bool)]
        is_lone = o["crack_id"].isin(lone_ids).to_numpy()
        why = o["rejected_as"].where(~is_lone, "lone_line")
        zone = o[~why.isin(["", "phase_rim", "phase_edge", "faint_texture"]).to_numpy()]
        if zone.empty:
            return 0.0, {}
        by_rule = (zone.groupby(why[zone.index])["area_px"].sum() / total).to_dict()
        return float(zone["area_px"].sum()) / total, by_rule


def _default_pixel_note(pixel_size_um, data_bar):
    """The ``pixel_size_note`` of an image whose pixel size is the default: every length and
    area in µm is then in pixels scaled by a guess (the row is flagged)."""
    where = ("a data bar was found but no scale bar in it" if data_bar is not None
             else "no data bar or scale bar was found")
    return (f"not known ({where}; none given in the manifest or on the command line, none "
            f"in the file's metadata): {pixel_size_um:g} um/px assumed, figures in um and "
            "per mm are in pixels scaled by it (give --pixel-size-um or a manifest)")


def analyse_image(image, *, pixel_size_um=config.DEFAULT_PIXEL_SIZE_UM, name="",
                  pixel_size_source="cli", stage=None, seed=None, **options) -> CrackAnalysis:
    """Analyse one grey image (lazy: stages run when their output is read).

    Parameters
    ----------
    image : (M, N) ndarray
        Grey (or RGB) image, cracks dark.
    pixel_size_um : float
    name : str
        Image name written in the tables.
    pixel_size_source : str
        Where the pixel size came from (written in ``images.csv``).
    stage : str, optional
        Loading stage (``manifest.csv``): ``pre-test`` images are not typed tensile / shear.
    seed : int, optional
        Seed of the grain stage.
    **options
        Fields of :class:`AnalysisOptions` (``threshold="auto"``, ``flatten=...``, ...).

    Returns
    -------
    analysis : CrackAnalysis
        ``analysis.cracks`` (per crack), ``analysis.summary()`` (per image),
        ``analysis.crack_labels`` and ``analysis.skeleton`` for later stages.

    Examples
    --------
    >>> img = np.full((64, 64), 180, np.uint8); img[20:24, 5:60] = 30
    >>> a = analyse_image(img, pixel_size_um=2.0, threshold="otsu", flatten="none")
    >>> len(a.cracks), float(a.cracks.area_um2.iloc[0])
    (1, 880.0)
    """
    return CrackAnalysis(image, pixel_size_um=pixel_size_um, pixel_size_source=pixel_size_source,
                         name=name, options=AnalysisOptions(**options), stage=stage, seed=seed)

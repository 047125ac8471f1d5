"""Options of the analysis (:class:`AnalysisOptions`), checked once when they are made."""
from __future__ import annotations

import dataclasses

from . import config
from .errors import InputError

__all__ = ["AnalysisOptions"]


@dataclasses.dataclass(frozen=True)
class AnalysisOptions:
    """Options of the crack analysis; each maps 1:1 to a CLI flag (kebab-case).

    Attributes
    ----------
    threshold : str
        ``auto`` (default), ``otsu``, ``local`` or ``manual:VALUE`` (see :mod:`semkit.threshold`).
    flatten : str
        Illumination flattening: ``polynomial`` (default), ``gaussian`` or ``none``.
    denoise_sigma_px : float
        Gaussian denoising of the grey image before thresholding, px (0 = off).
    despeckle : str
        ``specks`` (default: remove isolated compact specks only), ``median`` (ImageJ 3 x 3
        median on the binary: erases 1-px cracks) or ``none``.
    min_area_um2 : float or None
        Remove objects smaller than this (µm²) after despeckling.
    max_hole_px : int or None
        Fill enclosed holes up to this area (px); None fills all (ImageJ).
    length : bool
        Skeletonise and measure lengths (``--no-length`` skips the skeleton).
    exclude_pores : bool
        Report round compact objects as pores, not cracks.
    bridge_gaps : bool
        Close 1-px gaps along thin cracks (3 x 3 closing) so a 1-px crack whose blurred core
        dips under the detection level stays one object.
    classify : bool or None
        Post-test typing (tensile / shear / mixed), ``type_post``, ``confidence``, P. None
        (default): only images whose ``manifest.csv`` stage is a loaded one (initiating,
        propagation, failure); True: every image not marked pre-test; False: none.
    crack_model : str or None
        JSON model from ``semkit classify --train`` (default: the built-in one).
    grains : bool
        Mineral phases, grains, ``type_pre`` and ``grains.csv``.
    minerals : str or None
        Mineral names brightest-first (``"a,b,c"``) or a number of phases.
    ridge : bool
        Fuse the ``auto`` threshold with the multi-scale ridge detector (thin, faint cracks;
        :mod:`semkit.ridge`).
    link : bool
        Join the pieces of faint, beaded cracks with an oriented line response, from the
        objects a first pass accepted (:mod:`semkit.link`; needs ``ridge``).
    reject : bool
        Reject dark objects that are not cracks by shape and surroundings
        (:mod:`semkit.reject`); they stay in ``cracks.csv`` with ``rejected_as``.
    segmenter : object or None
        A trained pixel classifier (``crack_probability(grey) -> P(crack)`` and ``threshold``,
        e.g. from ``semkit.segmenter.load_segmenter``) used instead of threshold and ridge.
    segmenter_threshold : float or None
        Decision level on P(crack), in (0, 1), in place of the one the segmenter records
        (``segmenter.threshold``): lower finds more of the faint cracks and more of what is not
        crack. Only with ``segmenter``.
    roi : str
        Sample region: ``auto`` (data bar cropped, black / white surround removed), ``none``
        (whole image) or the path of a mask image (non-zero = sample); see :mod:`semkit.roi`.
    scan_lines : bool
        Find row-to-row grey offsets of a raster scan and remove them when they stand above
        pixel noise (:mod:`semkit.scanlines`); an image without them is left as it is.
    area : str
        How a crack's area is measured (``auto`` threshold only): ``mixed`` (default) the
        midpoint count only on resolved cross-sections and the partial volume on every thin
        stretch, also inside wide cracks (:func:`semkit.measure.mixed_area`; docs/semkit.md,
        step 5); ``midpoint`` the pixels past the midpoint between background and void grey,
        with the partial volume for thin cracks (mean width < ``THIN_WIDTH_PX``).
    bright_cracks : bool
        Cracks are brighter than the rock (fluorescent-dye impregnated thin sections under
        UV / blue light; some CT): the grey image is inverted before everything else
        (:func:`semkit.io.invert_grey`), so overlays and masks show it inverted.
    """

    threshold: str = "auto"
    flatten: str = "polynomial"
    denoise_sigma_px: float = config.DENOISE_SIGMA_PX
    despeckle: str = "specks"
    min_area_um2: float | None = None
    max_hole_px: int | None = config.FILL_HOLES_MAX_PX
    length: bool = True
    exclude_pores: bool = True
    bridge_gaps: bool = True
    classify: bool | None = None
    crack_model: str | None = None
    grains: bool = False
    minerals: str | None = None
    roi: str = "auto"
    ridge: bool = True
    scan_lines: bool = True
    link: bool = False
    reject: bool = True
    segmenter: object = None
    segmenter_threshold: float | None = None
    bright_cracks: bool = False
    area: str = "mixed"

    def __post_init__(self):
        from .classify import load_model
        from .roi import parse_roi
        from .threshold import parse_method
        parse_roi(self.roi)
        parse_method(self.threshold)
        if self.crack_model is not None:
            load_model(self.crack_model)
        if self.minerals is not None:
            from .grains import parse_minerals  # the grain stages import scipy.ndimage
            parse_minerals(self.minerals)
        if self.flatten not in ("polynomial", "gaussian", "none"):
            raise InputError(f"flatten: expected polynomial, gaussian or none, "
                             f"got {self.flatten!r}")
        if self.area not in ("midpoint", "mixed"):
            raise InputError(f"area: expected midpoint or mixed, got {self.area!r}")
        if self.despeckle not in ("specks", "median", "none"):
            raise InputError(f"despeckle: expected specks, median or none, got {self.despeckle!r}")
        if not (self.denoise_sigma_px >= 0):
            raise InputError(f"denoise_sigma_px: expected >= 0, got {self.denoise_sigma_px}")
        if self.min_area_um2 is not None and not self.min_area_um2 >= 0:
            raise InputError(f"min_area_um2: expected >= 0, got {self.min_area_um2}")
        seg = self.segmenter
        if seg is not None and not (callable(getattr(seg, "crack_probability", None))
                                    and hasattr(seg, "threshold")):
            raise InputError("segmenter: expected an object with crack_probability(grey) and "
                             "threshold")
        t = self.segmenter_threshold
        if t is not None:
            if seg is None:
                raise InputError("segmenter_threshold: needs a segmenter (--segmenter)")
            if not 0.0 < t < 1.0:
                raise InputError(f"segmenter_threshold: expected a probability in (0, 1), got {t}")

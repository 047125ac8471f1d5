"""Numeric constants and tolerances of :mod:`semkit`, in one place.

Tests read the same values (house rule 12), so a tolerance is changed here or nowhere.
"""

# --- pixel size -------------------------------------------------------------------------------
#: SEM magnification -> pixel size in µm (thesis, 1024-px-wide frames).
MAGNIFICATION_TABLE_UM = {100: 2.78, 200: 1.43, 500: 0.56}
#: pixel size used when nothing else is known; recorded as source "default".
DEFAULT_PIXEL_SIZE_UM = 1.0
#: image file suffixes that :func:`semkit.io.read_image` accepts.
IMAGE_SUFFIXES = (".tif", ".tiff", ".png", ".jpg", ".jpeg", ".bmp")

# --- illumination -----------------------------------------------------------------------------
#: the illumination field is fitted on the image shrunk so that its long side has this many px.
FLATTEN_FIT_SIZE_PX = 96
#: degree of the 2-D polynomial fitted to log(grey) for the illumination field.
FLATTEN_POLY_DEGREE = 2
#: Gaussian background: sigma as a fraction of the image's short side.
FLATTEN_GAUSS_FRACTION = 0.15

# --- threshold ------------------------------------------------------------------------------
#: a mineral phase must hold at least this share of the pixels to count as a grey-level peak.
MINERAL_MIN_FRACTION = 0.02
#: an image whose darkest mineral phase lies largely (this share of its pixels, on the
#: closed image) in long, narrow objects (principal axes at least LINE_PHASE_ELONGATION to 1,
#: at most LINE_PHASE_MAX_WIDTH_PX wide) is flagged: cracks wider than the closing (15-40 px,
#: 6-7 % of the image) pass for the darkest mineral, nothing is darker, and the image read no
#: crack, valid. Their phase: 0.43-0.87 of it in such objects; minerals' 0-0.25. Development
#: image 6's dark mineral, closed into an elongated cluster of grains, is 145 px wide
LINE_PHASE_MIN_SHARE = 0.35
LINE_PHASE_ELONGATION = 3.0
LINE_PHASE_MAX_WIDTH_PX = 80.0
#: the dark-tail seed lies this many noise sigmas below the darkest mineral peak.
DARK_TAIL_SIGMAS = 5.0
DARK_TAIL_NOISE_SIGMAS = 8.0
#: `auto`: a pixel is crack when it is this far (fraction) from the local background toward the
#: crack core grey level. 0.5 is the partial-volume midpoint, which makes area unbiased.
AUTO_AREA_FRACTION = 0.5
#: `auto`: thin cracks never reach the midpoint once blurred, so objects are *detected* at a
#: weaker level (fraction of the contrast, and at least AUTO_DETECT_NOISE noise sigmas deep)
#: and kept when they hold a *seed* pixel (hysteresis); area is still counted at the midpoint.
AUTO_DETECT_FRACTION = 0.27
AUTO_SEED_FRACTION = 0.33
#: the same depths in pixel-to-pixel noise sigmas (semkit.threshold.noise_sigma), where single
#: pixels are tested: the local background's candidates, the darkest-pixel crack grey, the
#: narrow dark lines of the no-dark-tail branch
AUTO_DETECT_SIGMAS = 4.0
AUTO_SEED_SIGMAS = 6.0
#: ... and the detect / seed depths are at least this many sigmas of the fine-scale noise of
#: the smoothed image (semkit.threshold.field_noise_sigma: what a speck-sized dip of noise
#: reaches; the pixel-to-pixel sigma reads it 1.3-1.6 x low once the noise is smoothed). On
#: development images with the noise raised to 24 and 30 grey, the pixel-sigma tests let
#: noise specks through (length up to +114 and +123 %, 160-410 objects); these read -36 to
#: +39 % (and the contrast-to-noise flag below marks them).
AUTO_DETECT_NOISE = 4.0
AUTO_SEED_NOISE = 6.0
#: an image whose crack contrast (darkest mineral minus crack grey) is less than this many
#: fine-scale noise sigmas is not valid: noise specks pass for cracks and faint cracks are lost
#: (development images below 12: errors up to 28 % on their own and 39 % with added noise)
MIN_CONTRAST_TO_NOISE = 12.0
#: an image with at least this share of its sample region at its brightest grey is saturated
#: (clipped): the partial volumes of cracks through those grains are lost (development images
#: with their bright mineral clipped: area -17 to -23 %, length to -16 %; the development
#: family, micro-CT, sample, granite, Obara and shale images: <= 0.2 %)
SATURATED_MAX_SHARE = 0.01
#: bright crack walls: the grey BRIGHT_WALLS_NEAR_PX px from the accepted cracks lies, by its
#: median over those pixels, at least BRIGHT_WALLS_MIN_LIFT of the crack contrast above the mean
#: grey of the rock BRIGHT_WALLS_FAR_PX px from every detected object in the
#: BRIGHT_WALLS_WINDOW_PX window around each (at least BRIGHT_WALLS_MIN_PX px of it; at least
#: BRIGHT_WALLS_MIN_WALL_PX wall pixels compared): an edge effect (secondary electrons) or a
#: phase-contrast fringe brightens the walls, partial-volume widths read narrow and thin cracks
#: between bright walls are lost (read at half size: px here are full-size px, counts half-size
#: ones). Blur alone makes the walls darker than the rock, never brighter. Images without the
#: effect read <= 0.033 (development, drawn, line, polyline, stress, speed-set, first held-out
#: generator, shale and Obara images), those with it 0.014-0.32 (docs/semkit.md, Validity)
BRIGHT_WALLS_NEAR_PX = (2.0, 4.0)
BRIGHT_WALLS_FAR_PX = (6.0, 12.0)
BRIGHT_WALLS_WINDOW_PX = 25
BRIGHT_WALLS_MIN_PX = 5
BRIGHT_WALLS_MIN_WALL_PX = 50
BRIGHT_WALLS_MIN_LIFT = 0.035

# --- scan-line noise (semkit.scanlines) ---
#: rows are compared with their vertical Gaussian smoothing of this sigma (rows)
SCAN_LINE_SIGMA_ROWS = 3.0
#: row offsets are removed when their robust std is at least this many times what pixel noise
#: gives (development family 1.0-1.3, sample images 1.1-1.3, micro-CT 1.3-2.3, shale tiles
#: 0.9-1.5; the granite 3.6 and Obara micrographs 4.4-6.6 are corrected; row noise of 1 grey
#: on development image 4, pixel noise 3: 4.2)
SCAN_LINE_MIN_RATIO = 3.0
#: rows further out than this many robust sigmas (a crack along the row) keep their grey
SCAN_LINE_OUTLIER = 4.0
#: when no crack is wide enough to show its core grey, the core is taken as this share of the
#: darkest mineral's grey at most (BSE: epoxy/void is near black).
THIN_ONLY_CRACK_RATIO = 0.3
#: a crack shows its core grey when at least this many of the dark class's interior pixels sit
#: in a flat 3 x 3 neighbourhood (grey range within FLAT_CORE_SIGMAS noise sigmas, or
#: FLAT_CORE_CONTRAST of the contrast): a plateau. Across a blurred 1-3 px crack the grey rises
#: on both sides of its darkest pixel, so it has no flat core, and its darkest grey is a partial
#: volume, not the void grey (read as the crack grey, it inflated the areas of the hairline
#: images of benchmarks/line_family.py by 6-285 %, median 63 %).
MIN_FLAT_CORE_PX = 10
#: when the dark class shows no plateau, the void grey is read on the detected objects' pixels
#: at least this far (px) from their edge (the cores of cracks >= 5 px wide)
DETECTED_CORE_PX = 2.5
#: ... and one object must hold at least this many flat core pixels: a plateau. Where blurred
#: 3-px lines cross (benchmarks/line_family.py hairlines) the flat spot holds <= 28 px of partial
#: volume; the cracks >= 4.6 px wide of development images 9, 15, 18 hold 70-282 px
DETECTED_PLATEAU_MIN_PX = 50
#: components of the dark class whose plateau (median of their flat-core pixels) lies more than
#: VOID_PLATEAU_BAND noise sigmas, and VOID_PLATEAU_CONTRAST of the mineral-to-void contrast,
#: above the darkest open (non-pore) plateau of at least VOID_PLATEAU_MIN_PX pixels (the pores'
#: when no open one has that many) are a dark phase's laths: left out of the crack and void greys
VOID_PLATEAU_MIN_PX = 20
VOID_PLATEAU_BAND = 6.0
VOID_PLATEAU_CONTRAST = 0.15
#: ... and no plateau holds the void when at least this share of the dark class's non-pore
#: pixels (and VOID_PLATEAU_MIN_PX) lie more than that band below the darkest one: partial
#: volumes are brighter than the void, never darker, so the plateaus are a dark phase (the
#: drawn family with 12 dark laths: 31-40 % of the pixels undercut the laths' plateau; the
#: development, line and drawn families without laths 0; JPEG ringing 0.3 %, crack grey 80
#: stress images <= 1.3 %)
VOID_UNDERCUT_SHARE = 0.05
#: the void grey is unconfirmed when every plateau pixel holding it lies in a compact blob:
#: principal axes less than VOID_COMPACT_ASPECT apart, filling at least VOID_COMPACT_FILL of
#: its equivalent ellipse (a pore, a round or lens-shaped grain), whether its component of the
#: dark class is one or, opened by REJECT_COMPACT_WIDTH_PX so that thin cracks joined to it fall
#: away, holds the pixel in one (``semkit.threshold._compact_void``). An opaque grain or organic
#: lens can be as dark as the void and no crack wide enough to show its core confirms the grey:
#: the image is flagged. No development, polyline, line-family or real image is flagged; drawn
#: scene 50006, six stress images and held-out 7018, 13019, 13047, 17042 are (docs/semkit.md,
#: step 3)
VOID_COMPACT_ASPECT = 4.0
VOID_COMPACT_FILL = 0.6
FLAT_CORE_SIGMAS = 4.0
FLAT_CORE_CONTRAST = 0.15
#: when nothing is darker than the darkest mineral, the crack grey is this low percentile.
DARKEST_PERCENT = 0.2
#: no pixel darker than the darkest mineral: narrow dark lines in the rock
#: (:func:`semkit.threshold.line_crack_level`) are read as cracks when they hold at least this
#: share of the image (crack-free images with a dark mineral: 0.07-0.18 %, from its grain
#: corners and rims; cracked ones >= 2.5 %), and the result is flagged when they hold more
#: than ``LINE_WARN_SHARE`` but too little to be read
LINE_CRACK_MIN_SHARE = 0.005
LINE_WARN_SHARE = 0.002
#: ... in components of at least this many px
LINE_MIN_COMPONENT_PX = 20
#: ... and the crack grey is this percentile of the line pixels
LINE_CRACK_PERCENTILE = 5.0
#: background of an excluded pixel: mean of its known neighbours within this many noise
#: sigmas of the darkest one (one phase, never a mix across a phase boundary).
BACKGROUND_BAND_SIGMAS = 4.0
#: a narrow dark line (grey closing minus image) deeper than this share of the contrast is a
#: crack candidate (thin cracks ~0.4 once blurred; faint grain boundaries ~0.15).
CANDIDATE_LINE_FRACTION = 0.25
#: Gaussian pre-smoothing (px) of the grey image before thresholding (denoise, not despeckle).
DENOISE_SIGMA_PX = 0.7
#: a threshold that puts more than this share of the image in the dark class is suspect.
MAX_DARK_FRACTION = 0.25
#: `local`: block size (px, odd) and offset (fraction of the local mean).
LOCAL_BLOCK_PX = 51
LOCAL_OFFSET_FRACTION = 0.25

# --- cleanup ----------------------------------------------------------------------------------
#: an object whose bounding box fits in this many px on both sides and whose area is below
#: SPECK_MAX_AREA_PX is an isolated speck (dust, noise), not a crack.
SPECK_MAX_SIDE_PX = 5
SPECK_MAX_AREA_PX = 16
#: holes enclosed by a crack are filled up to this area (px); larger ones (a grain ringed by
#: cracks) are left open. ImageJ fills all (``max_hole_px=None``).
FILL_HOLES_MAX_PX = 100

# --- length -------------------------------------------------------------------------------
#: Kulpa (1977) weights for an 8-connected chain: unbiased length for random orientations.
KULPA_STRAIGHT = 0.948
KULPA_DIAGONAL = 1.343
#: Vossepoel & Smeulders (1982) corner-count estimator: even, odd and corner weights.
VS_STRAIGHT = 0.980
VS_DIAGONAL = 1.406
VS_CORNER = 0.091
#: a skeleton stops short of its object's ends: each end adds the object's reach beyond the
#: circle inscribed there (``semkit.skeleton.tip_extension``), along the chord from the
#: skeleton pixel TIP_BACK_PX links back; inscribed radii are read up to TIP_MAX_RADIUS_PX.
TIP_BACK_PX = 6
TIP_MAX_RADIUS_PX = 12.0
#: spurs (junction-to-end skeleton branches) shorter than this many local half-widths, plus
#: SPUR_EXTRA_PX, are edge noise and are pruned.
SPUR_HALF_WIDTHS = 2.0
SPUR_EXTRA_PX = 2.0
#: parallel traces (``semkit.measure.parallel_traces``): a layered crack's traces, merged into
#: one object, each count in its length. Across a centreline pixel a trace is a grey valley at
#: least TRACE_MIN_DEPTH of the way from the local background to the crack grey; two valleys
#: are two traces when the depth between them is TRACE_MIN_RISE of the shallower one's depth
#: less than it (a share: thin traces are shallow by partial volume); cross-sections of
#: half-width under TRACE_MIN_HALF_WIDTH_PX hold one trace; a skeleton branch read at
#: TRACE_MIN_BRANCH_SAMPLES or more centreline pixels counts its mean number of traces when at
#: least TRACE_MIN_SHARE of them cross two or more (chosen on the drawn-crack family; the
#: rise on the drawn and development families: 0.3 left blurred layers 4-5 px apart, parted
#: by a rise of 0.17-0.3, counted once).
TRACE_MIN_DEPTH = 0.25
TRACE_MIN_RISE = 0.15
TRACE_MIN_HALF_WIDTH_PX = 1.5
TRACE_MIN_SHARE = 0.3
TRACE_MIN_BRANCH_SAMPLES = 5
TRACE_MAX_REACH_PX = 8.0
#: the cross-sections are read on the image before denoising (whose blur merges traces 2.5-3
#: px apart), each sample the mean of 2 * TRACE_ALONG_PX + 1 points 1 px apart along the
#: line: averaged along the traces, not across them (under noise of a fifth of the contrast,
#: an 8-px void read without this average split in two at four angles of four, with 1 px at
#: one, with 2 px at none; chosen on the renderings of ``tests/semkit/test_parallel_traces.py``)
TRACE_ALONG_PX = 2
#: ... and two valleys count apart only when the rise between them is also at least this many
#: sigmas of the noise of a difference of two such samples (taken as the pixel noise times
#: sqrt(2 / (2 * TRACE_ALONG_PX + 1)), an upper bound): a void's noisy floor is one trace
#: (stress set, cracks of grey 80 at the development family's noise: seed 1 read +23 % at 0
#: sigmas, +4 % at 2)
TRACE_NOISE_Z = 2.0
#: a void grey read on plateaus is a layered crack's merged band, not the void, when at least
#: LAYERED_VOID_MIN_SHARE of the pixels of the crack objects within the plateau band of it lie
#: within LAYERED_VOID_REACH_PX of a cross-section read as two or more traces
#: (``semkit.measure.layered_share``): a 0.7-px denoising merges two 1.2-px traces 2.5-3 px
#: apart into a flat band at a partial-volume grey (analytic pairs 0.99-1.0; 0.58-0.84 at
#: 15-75 degrees under a 1-px blur, missed; development and drawn families at most 0.30, the
#: micro-CT slices 1-10 at most 0.74); the areas are then
#: measured against the void assumed as when no crack shows its core (THIN_ONLY_CRACK_RATIO)
LAYERED_VOID_MIN_SHARE = 0.9
LAYERED_VOID_REACH_PX = 3
#: a crack whose mean width (area / length) is below this many px is flagged `thin`.
THIN_WIDTH_PX = 1.6
#: area (``semkit.measure.mixed_area``): a crack cross-section counts as resolved when its
#: centreline pixel has a pixel within 1 px at least AREA_RESOLVED_DEPTH of the way from the
#: background to the void grey; resolved cross-sections are measured by the midpoint pixel
#: count, the others by the partial-volume coverage of their pixels and a 1-px rim.
AREA_RESOLVED_DEPTH = 0.8

# --- accuracy targets (issue #2; tests assert these) -----------------------------------------
AREA_TOL_MEDIAN = 0.03
AREA_TOL_MAX = 0.08
LENGTH_TOL_MEDIAN = 0.03
LENGTH_TOL_MAX = 0.08
THIN_LENGTH_TOL = 0.15
SPURIOUS_AREA_MAX = 0.01

# --- issue #3: crack types, grains, P (semkit.classify / grains / damage) -----------------
# classify
#: He et al.: share of the crack along grain boundaries above which it is inter-granular.
INTER_MIN_FRACTION = 0.86
#: He et al.: share of the crack inside one grain above which it is intra-granular.
INTRA_MIN_FRACTION = 0.80
#: a skeleton pixel is "on a boundary" within this many px beyond the local half-aperture.
BOUNDARY_TOL_PX = 1.5
#: half-size of the feature window around each skeleton pixel, px.
WINDOW_PX = 10
#: a small object (debris, fragment) within this distance (px) of a large crack takes its type.
LINK_PX = 8
#: objects with fewer pixels than this are "small" (debris, fragments).
SMALL_OBJECT_PX = 40
#: running-mean window (px) along a branch before runs are measured (and of the per-pixel
#: decision of traces too short for the trace model).
RUN_SMOOTH_PX = 15
#: shortest run (px) of one type that counts as a segment of a mixed crack.
MIN_RUN_PX = 25
#: skeleton branches shorter than this (px) are spurs/steps: typed by their neighbours.
SHORT_BRANCH_PX = 12
#: branches meeting at a junction within this angle of a straight continuation are one trace
#: (chosen with GAP_PX on the training seeds 100-111; docs/semkit_science.md).
CONTINUE_DEG = 55.0
#: branch ends closer than this (px) meet at one junction.
JUNCTION_PX = 4.0
#: branch ends of different objects up to this far apart (px), facing each other within
#: CONTINUE_DEG, continue one trace across the gap (a crack broken by the threshold).
GAP_PX = 12.0
# grains
#: automatic class edges: these count percentiles of the equivalent diameters of each mineral.
AUTO_CLASS_PERCENTILES = (10.0, 90.0)
#: Gaussian denoising (px) before boundary detection.
GRAIN_DENOISE_SIGMA_PX = 1.0
#: median filter (px, odd) before phase classification: removes 1-2 px boundary lines.
PHASE_MEDIAN_PX = 5
#: Gaussian denoising (px) after the median, before phase classification.
PHASE_SIGMA_PX = 0.0
#: scale (px) of the dark-ridge filter that finds faint boundaries inside one phase.
RIDGE_SIGMA_PX = 1.0
#: h of the h-maxima transform of the distance map that seeds the watershed, in px.
MARKER_H_PX = 2.0
#: a pixel whose boundary strength (gradient or ridge response over its image median, i.e. in
#: units of the noise level) exceeds this is "boundary" when seeding the watershed.
BOUNDARY_LEVEL = 6.0
#: EM iterations of the 1-D Gaussian mixture.
GMM_ITERATIONS = 100
# damage
#: Order of the loading stages on the P-by-stage plot and in ``damage.csv``.
STAGE_ORDER = ("pre-test", "initiating", "propagation", "failure")
#: the tensile-versus-shear direction (tensile, shear, mixed) of an image's common log-odds lean:
#: fitted by semkit.classify.model.fit_image_shift, drawn by semkit.damage_confidence.
TYPE_SHIFT_DIRECTION = (0.5, -0.5, 0.0)
#: Modified z-score above which an image's P is flagged as an outlier.
OUTLIER_Z = 3.5
#: Fewest finite P values in a test for the outlier rule to apply.
OUTLIER_MIN_N = 5
#: band (px) around the crack objects over which partial-volume darkness is summed.
PV_BAND_PX = 2
#: Gaussian sigma (px) of the local-background estimate for the partial-volume area.
PV_BACKGROUND_SIGMA_PX = 4.0
# targets of issue #3 (tests assert these or say why not)
#: grain segmentation: mineral area fractions (absolute), median diameter, count (relative).
GRAIN_FRACTION_TOL_ABS = 0.02
GRAIN_MEDIAN_D_TOL = 0.05
GRAIN_COUNT_TOL = 0.10
#: crack-type accuracy by crack area (pre-existing with a known grain map; post-test).
PRE_TYPE_ACCURACY_MIN = 0.90
POST_TYPE_ACCURACY_TARGET = 0.90
#: floor the tests assert for the built-in post-test model on semkit.synth seeds 200-205
#: (held out): it is fitted on the wider domain-randomised family of benchmarks/typing, of
#: which semkit.synth is one part, and does not reach the 0.90 target there
#: (docs/semkit_science.md quotes the measured value).
POST_TYPE_ACCURACY_SYNTH_MIN = 0.75
#: calibration: |mean confidence - observed accuracy| of crack groups (area-weighted).
POST_CALIBRATION_GAP_MAX = 0.10
#: per-image P against truth, median relative error.
P_TOL_MEDIAN = 0.15
# --- end issue #3 ---------------------------------------------------------------------------

# --- sample region and SEM data bar (semkit.roi, semkit.databar) ---
#: a data-bar row: at least this share of every third of the row holds the bar's background
DATABAR_MIN_FLAT = 0.3
#: grey tolerance (8-bit) around the row's modal grey
DATABAR_TOL_GREY = 6
#: the three rows next to a bar are sample: at most this share of each at the bar's grey (a round
#: core's corners fade into the surround; a sample clipped at the other end of the grey scale is
#: flat, but not at the bar's grey) ...
DATABAR_SAMPLE_FLAT = 0.5
#: ... unless the sample is clipped at the bar's grey (saturated grains over a white bar) and the
#: run of flat rows goes on into it: then the bar is the rows within this much of the edge rows'
#: flatness, ending in one step of this much, and the rows past it hold at least this much less
#: than the bar's median row at its grey (a bar's rows are nearly all background)
DATABAR_SAMPLE_STEP = 0.35
#: ... and the median bar row is at least this flat (text covers a minority of a bar; a noisy
#: image of large uniform grains is 40-50 % flat in every row)
DATABAR_MEDIAN_FLAT = 0.7
#: rows of text or a thick scale bar may break the run of bar rows by at most this many
DATABAR_MAX_GAP_ROWS = 12
#: a data bar holds at least this many rows and this share of the height, at most the last
DATABAR_MIN_ROWS = 8
DATABAR_MIN_FRACTION = 0.02
DATABAR_MAX_FRACTION = 0.35
#: text and scale-bar pixels ("ink") lie within this of the other end of the 8-bit scale
#: from the bar's background (white on a dark bar, black on a light one)
DATABAR_INK_GREY = 80
#: a bar holds at least this share of such pixels (rows without any are a surround)
DATABAR_MIN_INK = 0.005
#: a scale bar is a solid line at least this share of the image width long
SCALEBAR_MIN_FRACTION = 0.03
#: glyphs further apart than this many glyph heights belong to different words
SCALEBAR_WORD_GAP = 1.2
#: an ink component of a label wider than this many text heights may be touching glyphs (bold
#: text at a small size): it is cut where both parts read better than the whole
SCALEBAR_SPLIT_ASPECT = 0.85
#: a scale-bar label is used only when every glyph correlates at least this well (Liberation
#: Sans, an Arial twin without templates, draws an 11-px "0" that correlates 0.61)
SCALEBAR_MIN_CONFIDENCE = 0.6
#: ... and only when every glyph's best score leads the best score of any other character by at
#: least this much (set, when the templates were DejaVu only, on the second held-out generator's
#: misread Hershey "5"s, which led "6" by 0.002-0.056; with the Hershey templates those read
#: right; over the fonts without templates the rule gives up 24 right readings and no reading
#: is wrong either way: benchmarks/scale_bar_fonts.py)
SCALEBAR_MIN_MARGIN = 0.08
#: a given pixel size and the scale bar's disagreeing by more than this is noted
SCALEBAR_AGREE_FRACTION = 0.05
#: a surround (black or white outside the sample): share of the border pixels it must hold
SURROUND_MIN_BORDER_FRACTION = 0.10
#: a surround's grey is at least this many grey tolerances away from the image's median
SURROUND_MIN_SEPARATION = 4.0
#: surround grey tolerance: this many noise sigmas, at least SURROUND_TOL_FRACTION of the range
SURROUND_TOL_SIGMAS = 4.0
SURROUND_TOL_FRACTION = 0.04
#: the sample region is shrunk by this many px (the partial-volume rim of the sample's edge)
ROI_MARGIN_PX = 3
#: below this share of the image the sample region is flagged (roi_ok False)
ROI_MIN_FRACTION = 0.2
#: a burned-in annotation (scale bar, its box): a component of one extreme grey (0 or the pixel
#: type's maximum) whose bounding box's outline lies at least ANNOT_OUTLINE_FILL in it, at least
#: ANNOT_MIN_THICK_PX thick and ANNOT_MIN_LENGTH_PX long, and at most ANNOT_MAX_SHARE of the
#: image's width and height (a surround or an undetected data bar is larger)
ANNOT_OUTLINE_FILL = 0.95
ANNOT_MIN_THICK_PX = 3
ANNOT_MIN_LENGTH_PX = 12
ANNOT_MAX_SHARE = 0.5

# --- ridge detector (semkit.ridge) ---
#: scales of the dark-ridge response, px
RIDGE_SIGMAS_PX = (1.0, 2.0, 4.0)
#: scales from this up are computed on the image shrunk by 2, px
RIDGE_COARSE_SIGMA_PX = 2.0
#: weight of the edge (gradient) term: the dark side of a step edge is not a line
RIDGE_EDGE_KAPPA = 1.0
#: hysteresis levels of the ridge response, in units of its noise response
RIDGE_HIGH_SNR = 8.0
RIDGE_LOW_SNR = 4.0
#: a ridge line holds seed pixels at least this deep (share of background - crack core);
#: grain boundaries in semkit.synth are ~0.14, a faint crack more
RIDGE_MIN_DEPTH_FRACTION = 0.2
#: side of the grey closing giving the local background of a ridge, px
RIDGE_CLOSING_PX = 9
#: a ridge line touching a threshold object adds its pieces beyond the object of at least
#: this many px whose median depth is at least RIDGE_MIN_DEPTH_FRACTION (faint continuations)
RIDGE_CONTINUATION_MIN_PX = 10

# --- linking of faint, beaded cracks (semkit.link) ---
#: oriented line response: Gaussian scale across and along the line, px, and the number of
#: directions over 180 degrees
LINK_SIGMA_PX = 1.0
LINK_LENGTH_PX = 8.0
LINK_ORIENTATIONS = 12
#: weight of the edge term of the line response (RIDGE_EDGE_KAPPA's counterpart)
LINK_EDGE_KAPPA = 1.0
#: a line continuing an accepted crack object passes this many noise units of that response
#: (LINK_LENGTH_PX, LINK_SNR, LINK_MAX_DENSITY and LINK_MIN_CHAIN_PX chosen on the granite's
#: marked cracks, micro-CT slices 1-10 and semkit.synth seeds 11-16; docs/semkit.md)
LINK_SNR = 4.0
#: objects rejected by these rules of the first pass (their surroundings say they are no
#: crack, or they are a dark phase's band) are kept out of linking; objects rejected for
#: their own shape (phase_rim, compact_dark: a bead too round or short on its own) and pores
#: may be passed through
LINK_EXCLUDE_RULES = ("dark_phase", "mottled", "grain_rim", "dark_band")
#: lines keep this far (px) from an excluded object (more than the 1-px gap that
#: cleanup.bridge_gaps closes), so they never join one
LINK_EXCLUDE_PX = 2
#: line pixels lie at least this many pixel-noise sigmas below their local background (the
#: elongated filter's response runs on past a crack's tip, over background)
LINK_DEPTH_SIGMAS = 3.0
#: a piece of line (between objects or beyond one) lies at least this share of the contrast
#: below the darker side around it (median along the piece): the ridge's own low level
#: (0.5 RIDGE_MIN_DEPTH_FRACTION), read along the piece instead of per pixel; a faint grain
#: boundary of semkit.synth, or the dark side of a step between grains, is shallower
LINK_MIN_DEPTH_FRACTION = 0.1
#: a linked object must be at least this long (px; its principal length): two specks joined
#: into a short squiggle are no crack
LINK_MIN_CHAIN_PX = 30.0
#: lines are drawn only where their brighter side is less than this share of the contrast
#: brighter than the rock (a dark halo beside a bright grain or particle is its rim)
LINK_MAX_LIFT = 0.3
#: lines are drawn only where less than this share of a ZONE_WINDOW_PX window is detected
LINK_MAX_DENSITY = 0.12

# --- rejection of dark non-crack objects (semkit.reject) ---
#: a crack lies at least this far (share of the contrast) below the darker side around it
REJECT_SIDE_DEPTH = 0.3
#: ... unless it is a long line (a blurred 1-px crack is shallow but slender): skeleton length
#: over mean width at least this
REJECT_RIM_MAX_SLENDERNESS = 12.0
#: a rim around a brighter grain: closes a loop around at least this many px, brighter than
#: the darker side outside by this share of the contrast (and not reaching the crack core)
REJECT_RIM_LOOP_PX = 20
REJECT_RIM_HOLE_LIFT = 0.3
#: ... and its holes hold at least this share of its own area (a ring around an inclusion of
#: radius >= half the ring's width holds >= 1/8; a network with one small loop far less)
REJECT_RIM_HOLE_SHARE = 0.1
#: ... and at least this share of its pixels hugs its holes (within its width + 1.5 px): a
#: crack network of 4300 px that closed a loop around a bright grain through one pixel (1000
#: of its pixels around the grain: 0.27) was rejected whole as the grain's rim
REJECT_RIM_MIN_SHARE = 0.6
#: ... and at least this wide (a blurred thin crack is shallow; its depth says little)
REJECT_RIM_MIN_WIDTH_PX = 2.5
#: ... unless it lies inside one grain (ring quartiles under REJECT_TEXTURE_STEP apart), this far
#: out of the noise (depth_snr) and this elongated: a crack piece. Development renderings 0-23:
#: such objects the rule rejected were 26 on true cracks and 2 elsewhere; micro-CT slices 1-10: 1
#: on the fracture, none elsewhere (without the elongation limit 5 pores and specks, elongation
#: 1.4-2.2, were kept there)
REJECT_RIM_CLEAR_SNR = 20.0
REJECT_RIM_CLEAR_ELONGATION = 2.5
#: objects smaller than this (px) are not judged: too few pixels for their statistics
REJECT_MIN_AREA_PX = 30
#: the dark edge of a step between two phases (a grain boundary's rim, however thin): core
#: less than this share of the contrast below the darker side, the two sides of its ring
#: (25th and 75th percentiles) at least this share apart, shorter than this many widths, and
#: judged from this size on. A 22-px, 1-px-wide crack along a phase boundary (``semkit.synth``,
#: slenderness 11.8, side_depth 0.08) is as shallow and on as high a step: only its length
#: tells it apart (the boundary segments of the drawn-crack family: slenderness 3.3 median,
#: 90 % under 6.5)
REJECT_EDGE_DEPTH = 0.2
REJECT_EDGE_STEP = 0.6
REJECT_EDGE_MAX_SLENDERNESS = 8.0
REJECT_EDGE_MIN_AREA_PX = 15
#: a shallow, short object (``phase_rim``'s REJECT_SIDE_DEPTH and REJECT_RIM_MAX_SLENDERNESS,
#: at any size and width) whose ring's quartiles lie at least this far apart, but less than
#: REJECT_EDGE_STEP (a step between phases, judged by ``phase_edge``), is ``faint_texture``:
#: no deeper than its surroundings vary
REJECT_TEXTURE_STEP = 0.3
#: an object whose core lies less than this many pixel-noise sigmas below the darker side
#: around it, times the square root of its centreline length (px), cannot be told from noise
#: (``noise``), unless it is a long line on a step between phases (side_step >=
#: REJECT_EDGE_STEP, slenderness >= REJECT_RIM_MAX_SLENDERNESS: a thin crack along a phase
#: boundary is shallow against the darker phase). Chosen on the drawn family (TRAIN and HELDOUT
#: settings), the development family and the stress set (docs/semkit.md, step 5b)
REJECT_NOISE_SNR = 12.0
#: compact dark phase (biotite, opaque mineral): skeleton length under this many mean widths,
#: at least this wide, and not reaching the crack core grey (an open void does: a pore)
REJECT_COMPACT_SLENDERNESS = 3.0
REJECT_COMPACT_WIDTH_PX = 6.0
#: dark phase: the object's local background is below this share of the rock's (both from
#: the crack core grey)
REJECT_DARK_BACKGROUND = 0.4
#: ... except a lone line: at most this many other objects in its window (``neighbours``), at
#: least this elongated, and its core at least this share of the contrast below its darker
#: side (development images 10 and 12: 20 of 26 rejected objects were cracks in darker
#: minerals, each alone in its window; the granite's dark-grain objects have 2-17 around them,
#: the one with one around it 0.19 deep). Depth from 0.25: cracks thinner than the blur read
#: 0.25-0.4 (development, polyline and drawn families: 11 of the 13 lone lines at that depth
#: were cracks, one a dark lath; no real image's object at that depth is a lone line)
LONE_LINE_MAX_NEIGHBOURS = 1
LONE_LINE_ELONGATION = 5.0
LONE_LINE_DEPTH = 0.25
#: ... or, curved, at least this slender (skeleton length over mean width) and winding at
#: most this much (skeleton length over its bounding box's diagonal): a bent or wavy crack's
#: moments are not elongated, and it is one path (development images 2, 6 and 12 and the
#: polyline family's seed 23: cracks in darker minerals of slenderness 37-84, elongation 1.2-4.3,
#: winding 0.97-1.68, were rejected). A dark grain's cleavage traces joined into one object
#: wind to and fro (a test grain: 2.7); no object of the micro-CT tuning slices, granite or
#: dolomite micrographs that the rule rejects alone in its window is slenderer than 10
LONE_LINE_SLENDERNESS = 30.0
LONE_LINE_MAX_WINDING = 2.0
#: mottled, altered area: local background below this share, and at least this share of the
#: window around the object detected
REJECT_MOTTLED_BACKGROUND = 0.8
REJECT_MOTTLED_DENSITY = 0.15
#: ... and with at least this many other objects centred in the window around it
REJECT_MOTTLED_NEIGHBOURS = 4
#: an object whose dark core reaches this share of the crack contrast is an open crack or
#: void: the dark-phase, mottled, compact and grain-rim rules never reject it
REJECT_ZONE_MAX_DEPTH = 0.85
#: a dark band (a lath or vein of a darker mineral): at least this share of its pixels lie
#: REJECT_BAND_INTERIOR_PX or more inside it (wide enough to show its core grey through any
#: blur); that interior's dark core lies less than REJECT_BAND_DEPTH of the way from the darker
#: side around it to the void grey; it is smooth (median 5 x 5 grey standard deviation under
#: REJECT_BAND_MAX_ROUGH noise sigmas: flat mineral ~1.0-1.2; the drawn family's laths 0.4-3.8; its
#: cracks as shallow, with debris or merged layers inside, 6.8-26); and it is darkest inside
#: (its whole dark core less than REJECT_BAND_MAX_WALL below the interior's: laths -0.09-0.00;
#: a development crack with dark walls and a grey middle 0.11, most shallow drawn cracks more)
REJECT_BAND_INTERIOR_PX = 3.0
REJECT_BAND_INTERIOR_SHARE = 0.15
REJECT_BAND_DEPTH = 0.7
#: (phase_rim spares a band as rough as REJECT_BAND_MAX_ROUGH over REJECT_BAND_INTERIOR_SHARE of it:
#: merged layered traces or debris, where a grain's rim is smooth across)
REJECT_BAND_MAX_ROUGH = 5.0
REJECT_BAND_MAX_WALL = 0.05
#: an image whose zone and shape rules (all but phase_rim, phase_edge and faint_texture)
#: rejected at least this share of the dark objects' area is flagged (valid = False): its
#: figures rest on them
REJECT_MAX_ZONE_SHARE = 0.2
#: an image with at least FAINT_MAX_LENGTH_SHARE of its crack centreline length (each object
#: once, its parallel traces not counted) in objects whose core lies less than
#: FAINT_LINE_DEPTH of the contrast below their darker side is flagged: faint lines are grain
#: boundaries as often as cracks (development family: a valid image with boundaries darkened
#: by a third read length +38 % at 26 %; every other valid image <= 11 %,
#: semkit.synth 1-px cracks 7-8 %, micro-CT tuning slices 3-24 %: slices 0 and 5 flagged at
#: 24 and 20 % for the dark rims of bright inclusions)
FAINT_LINE_DEPTH = 0.2
FAINT_MAX_LENGTH_SHARE = 0.2
#: an image with at least THIN_MAX_LENGTH_SHARE of its crack centreline length (each object
#: once) in cracks narrower than THIN_POPULATION_WIDTH_PX (area / centreline) is flagged: its
#: crack population reaches the detection limit (a thin crack under blur is faint), so thinner
#: ones are missed (length is then a lower bound) and the areas rest on partial volumes. It
#: flags thin cracks measured right too (sample image S1_pre_03, hairline and polyline images);
#: counting only thin cracks with shallow cores (side_depth < 0.5) clears most of those but
#: loses half-size stress images (area +26 to +32 %) and micro-CT slices 163 and 176 (length
#: 0.62 and 0.68 of the truth): not adopted. Median signed length error by that
#: share, under 0.3 / at least 0.3: first held-out generator (seeds 9000-9047) -6 / -11 %,
#: second (0-39) 0 / -7 %, third (0-39) -10 / -50 %; set there, then read on the third's seeds
#: 1000-1039: its three valid rows off by more than 25 % read 0.42-0.73, every other valid row
#: at most 0.24. Development family: no valid image at 0.3 or more; Obara's dolomite 0.14.
THIN_POPULATION_WIDTH_PX = 2.0
THIN_MAX_LENGTH_SHARE = 0.3
#: an image with at least SPECKLE_MAX_LENGTH_SHARE of its crack centreline length in short
#: objects (skeleton under SPECKLE_MAX_LENGTH_PX) with SPECKLE_MIN_NEIGHBOURS or more other objects
#: in the ZONE_NEIGHBOUR_WINDOW_PX window around them is flagged: a speckled texture (dusty or
#: altered grains, fluid inclusions, pitted surfaces), not a crack pattern (development and
#: drawn families, micro-CT tuning slices, sample images: 0; the cracked dolomite
#: micrographs <= 0.041; plane-light sandstone thin sections 0.15-0.36)
SPECKLE_MAX_LENGTH_PX = 25.0
SPECKLE_MIN_NEIGHBOURS = 8
SPECKLE_MAX_LENGTH_SHARE = 0.1
#: an image whose ridge lines continue its detected cracks (pixels of a ridge line touching a
#: crack, more than 2 px from every detected pixel) for at least this many px per px of crack
#: centreline is flagged: the cracks were found only in part (development family: the under-read
#: images 0.15-0.19, every other image <= 0.045; 1-px hairlines blurred by 1.4 px: 14.5)
CONTINUATION_MAX_SHARE = 0.1
#: an image whose dark class's median grey (the crack grey detection works from) lies at least
#: DARK_PHASE_MAX_GAP of the contrast above the void grey (the darkest plateau of the open
#: cracks), with at least DARK_PHASE_MIN_SHARE of the dark class's flat cores on plateaus
#: brighter than the void, is flagged: a brighter dark phase (laths or grains of a dark
#: mineral) fills the dark class and may be counted as crack. Drawn family with 4 or 12 dark
#: laths: gap 0.22-0.35 with plateau share 0.62-0.84 where the laths shift it. Without the
#: plateau share, the partly resolved cores of many thin cracks raise the gap as well (1.5-8
#: px lines under a 1.4 px blur: 0.32, plateau share 0.20, areas right within 3 %).
#: Development, drawn and drawn-held-out families, semkit.synth speed set, micro-CT tuning
#: slices, granite, 8 shale tiles: gap <= 0.11.
DARK_PHASE_MAX_GAP = 0.2
DARK_PHASE_MIN_SHARE = 0.4
#: side of the grey closing giving an object's local background (fills cracks narrower), px
ZONE_CLOSING_PX = 21
#: side of the window of the detection density, px
ZONE_WINDOW_PX = 41
#: side of the window in which neighbouring objects are counted, px
ZONE_NEIGHBOUR_WINDOW_PX = 81

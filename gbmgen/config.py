"""Constants, defaults and tolerances of :mod:`gbmgen` (tests read the same values).

Sizes are SI (m) unless the name carries a unit suffix.
"""

#: Grain-size classes, in the order used by every (M, 3) array and by ``grain_class``.
CLASSES = ("fine", "medium", "coarse")

# ---------------------------------------------------------------- table validation
#: Columns of ``grains.csv`` (DESIGN.md §4).
TABLE_COLUMNS = ("mineral", "class", "d_min_um", "d_max_um", "frequency_pct",
                 "volume_fraction_pct")
#: Frequencies of a mineral must sum to 100 % within this (Table 4-1 pyroxene sums to 101).
FREQ_SUM_TOL_PCT = 2.0
#: Volume fractions of all minerals must sum to 100 % within this.
VOLUME_SUM_TOL_PCT = 0.5
#: Two classes overlap when d_max of the finer exceeds d_min of the coarser by more than this.
CLASS_OVERLAP_TOL_UM = 1e-6

# ---------------------------------------------------------------- scenarios
#: Scenario 2 keeps the 10-90 % passing range (by grain count).
S2_PASSING = (0.10, 0.90)
#: Scenario 3 and 4 keep mean +- this fraction of the mean.
S3_HALF_WIDTH = 0.5
S4_HALF_WIDTH = 0.25
#: Thesis: model scale = 10 x SEM scale (REFERENCE.md Ch. 4).
MODEL_SCALE = 10.0
#: Random seed of ``gbmgen build`` and ``gbmgen run`` when none is given (``--seed random``
#: draws one): two runs of the same command build the same specimen.
DEFAULT_SEED = 1

# ---------------------------------------------------------------- grain seeds
#: Solid fraction of the seed-disk packing; seed radius = d/2 * sqrt(SEED_PACKING_FRACTION),
#: so that a Laguerre cell of area ~ disk area / fraction has the target diameter d.
SEED_PACKING_FRACTION = 0.80
#: Largest seed overlap after relaxation (fraction of the smaller radius).
SEED_OVERLAP_TOL = 0.05
SEED_MAX_ITER = 4000

#: Fitted Laguerre: after the weight fit, move each seed to its cell's centroid and fit again,
#: this many times (one step puts ~98 % of the seeds inside their own cells, against ~31 %
#: straight after the fit, whose weights may shift cells away from their seeds).
CENTROID_STEPS = 1

# ---------------------------------------------------------------- particles
#: ``--particle-radius-mm`` is the mean radius; radii are uniform in [rmin, ratio*rmin].
PARTICLE_RADIUS_MM = 0.1
RADIUS_RATIO = 1.66
#: Target porosity of the particle packing (2D: 1 - disk area / box area). The thesis' PFC
#: value 0.01 is not reachable in 2D without large overlaps; random disk packings jam near
#: 0.16, and relaxing to a small overlap is fast at 0.20.
POROSITY = 0.20
#: Largest particle overlap after relaxation, fraction of the smaller radius.
PARTICLE_OVERLAP_TOL = 0.02
PARTICLE_MAX_ITER = 6000
#: Radius growth before the final relaxation: start at this fraction of the radii.
GROW_FROM = 0.85
GROW_STEPS = 4
GROW_ITER = 40
#: Seat the particle packing on the box faces (flat specimen ends; gbmgen.faces).
SEAT_FACES = True
#: Face seating: a particle within this many of its radii of a face moves onto it,
SEAT_CAPTURE_RADII = 1.0
#: an open stretch of a face longer than this many mean diameters receives a particle,
SEAT_MAX_OPEN_DIAMETERS = 2.5
#: in at most this many snap-fill-relax rounds.
SEAT_ROUNDS = 6

# ---------------------------------------------------------------- bonds
#: Thesis App. E: bond gap 0.5e-4 m with 0.1 mm particles -> 0.5 x the mean particle radius.
BOND_GAP_PER_RADIUS = 0.5

# ---------------------------------------------------------------- controlled shapes
#: Shape ranges of slenderness H/W (REFERENCE.md Ch. 5).
SLENDERNESS_RANGE = {"hexagon": (0.47, 2.13), "rectangle": (0.5, 3.0), "shield": (0.67, 1.43)}
#: Thesis grain area, mm^2.
GRAIN_AREA_MM2 = 1.78
#: Shield profile, fractions of the height H: straight sides, bottom cap, top cap.
SHIELD_SIDE = 0.40
SHIELD_BOTTOM = 0.48
SHIELD_TOP = 0.12

# ---------------------------------------------------------------- geometry tolerances
#: Relative tolerance (of the box size) for geometric predicates and vertex merging.
GEOM_EPS = 1e-9
#: Polygon area below which a clipped cell is dropped, fraction of the mean cell area.
MIN_CELL_AREA_FRACTION = 1e-9

# ---------------------------------------------------------------- fidelity targets (issue #4)
KS_MAX = 0.05
AREA_FRACTION_TOL = 0.02
SHAPE_TOL = 0.03
MHI_SCALE_TOL = 0.03

DEFAULT_PARAMS = "thesis-ch4"

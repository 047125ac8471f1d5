"""Tolerances, defaults and numeric constants of the DEM engine, in one place.

Tests read the same values (STYLE.md §5, rule 12). SI units throughout.
"""

#: Out-of-plane thickness of every disk, m (PFC2D convention, DESIGN.md §3).
THICKNESS = 1.0

#: Local damping coefficient alpha (Potyondy & Cundall 2004; thesis ``damp 0.7``).
DAMPING = 0.7

#: Default safety factor on the critical time step (REFERENCE.md §5).
#: 0.5 leaves room for the rotational coupling of parallel bonds and for contacts that form
#: between neighbour-list rebuilds; the 60:1 stiffness-contrast stress test and the energy-drift
#: test both run at this value.
TIMESTEP_FACTOR = 0.5

#: Verlet skin as a fraction of the mean particle radius. Pairs closer than r_i + r_j + skin are
#: kept in the contact list; the list is rebuilt when the largest displacement since the last
#: build exceeds skin / 2.
SKIN_FACTOR = 0.5

#: Scenes with fewer particles run the step loop on one thread (a parallel region costs a few
#: microseconds to start, more when other processes load the cores).
PARALLEL_MIN_PARTICLES = 4000

#: Chunks of the step loop (force buffers summed in a fixed order) for larger scenes; smaller
#: ones use one. The chunk count, not the thread count, fixes the summation order of the forces
#: on a particle, so results are bit-identical on 1 or 2 threads (or any number) at a given
#: chunk count. Fracture turns a change in summation order into a different failure path
#: (docs/sim.md), hence a fixed value. 2 fits the 2-core target machine and keeps every
#: recorded 2-thread result; at most this many threads work in the step loop. Override with
#: the environment variable ``SIM_FORCE_CHUNKS`` (:func:`sim.state.force_chunks`), e.g. to the
#: core count of a bigger machine; lab-test summaries record the value.
FORCE_CHUNKS = 2

#: OpenMP wait policy set (unless the user set one) before the first parallel step. Measured on
#: the shared 2-core machine at load ~4.7, 20k particles, 2 threads: 0.83 M particle-steps/s with
#: the default (spinning) policy, 5.07 M with "passive": a spinning thread steals the core its
#: partner needs when other processes compete for the CPU.
OMP_WAIT_POLICY = "passive"

#: Spare capacity when (re)allocating the contact arrays (fixed capacity + overflow flag).
CAPACITY_GROWTH = 1.3

#: Instability bounds.
#: A particle moving more than this fraction of its radius in one step is an energy blow-up.
MAX_STEP_DISPLACEMENT = 0.25
#: An overlap larger than this fraction of the smaller radius is an instability.
MAX_OVERLAP = 1.0

#: Reach of an unbonded smooth joint, as a fraction of the smaller radius: once the ball gap
#: (d - R_i - R_j) exceeds it, the joint faces are apart and the joint carries nothing (its
#: normal state follows the gap, un = -g, so it closes again when the balls touch). Joints are
#: installed at gaps up to ~0.6 min(R) (gbmgen bond gap 0.5 r_mean). Without a reach, a grain
#: ejected from a specimen kept acting on its old neighbours from tens of radii away: spin
#: increments w·a at the mid-gap contact point (a ~ d/2) closed the open joint and it fired
#: with a lever arm of d/2 (UCS blow-up "particle moved > 0.25 R", docs/sim.md).
SJ_REACH = 1.0

#: Servo: fraction of the stress error corrected per step (PFC's alpha = 0.5) and the
#: largest servo speed, m/s.
SERVO_ALPHA = 0.5
SERVO_VMAX = 1.0

#: Sleeping particles (Simulation(sleep=True); off by default): a free particle that moved
#: less than SLEEP_DISP x mean radius per step, with an unbalanced force below
#: SLEEP_FORCE_RATIO x the sum of its pair-force magnitudes, for SLEEP_STEPS steps in a row,
#: sleeps; it wakes when a pair or wall contact around it moves more than that per step.
SLEEP_DISP = 1e-9
SLEEP_FORCE_RATIO = 1e-3
SLEEP_STEPS = 200

#: Equilibrium: default target of the mean unbalanced-force ratio and the check interval, steps.
SOLVE_RATIO = 1e-5
SOLVE_CHECK_INTERVAL = 50

#: Bond states (per bond, int8).
BOND_INTACT = 0
BOND_BROKEN_TENSION = 1
BOND_BROKEN_SHEAR = 2

#: Bond kinds as in specimen.npz.
KIND_PB = 0
KIND_SJ = 1

#: Step-loop status codes returned by the kernel.
STATUS_DONE = 0
STATUS_REBUILD = 1
STATUS_UNSTABLE = 2

#: Instability cause codes (kernel) and names (InstabilityError.cause).
CAUSE_NAMES = {1: "nan", 2: "energy", 3: "overlap"}

#: Validation tolerances used by the analytic tests (tests/sim) and ``gbmsim verify``.
TOL_COLLISION_DURATION = 0.01
TOL_RESTITUTION = 0.02
TOL_PEAK_OVERLAP = 0.01
TOL_LATTICE_MODULUS = 0.02
TOL_BOND_STRENGTH = 1e-3
TOL_DAMPING_DECAY = 0.01
TOL_ENERGY_DRIFT = 1e-4

#: Broad phase: above this radius spread (r_max / r_min) the contact search uses one cell grid
#: per radius level (factor 2 apart) instead of one grid sized for the largest particle, whose
#: cells would hold hundreds of the smallest (sim.neighbors.build_contacts; field models).
MULTILEVEL_SPREAD = 4.0

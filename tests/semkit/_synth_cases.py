"""Shared synthetic cases for the semkit tests (cached once per test run: generation is the
slow part)."""
import functools

from semkit.synth import make_sem_image

SHAPE = (576, 768)
N_CRACKS = 22
SEEDS = (11, 12, 13, 14, 15, 16)


@functools.lru_cache(maxsize=None)
def case(seed, gradient=1.0, widths=(2.0, 8.0), stage="pre", shape=SHAPE, n_cracks=N_CRACKS):
    return make_sem_image(shape, stage=stage, gradient=gradient, widths=widths,
                          n_cracks=n_cracks, seed=seed)


@functools.lru_cache(maxsize=None)
def dev_scene(seed, **changes):
    """Development-family image ``seed`` (``benchmarks/semkit_dev_family.py``: its randomised
    appearance), with some keywords changed."""
    import pathlib
    import sys
    bench = pathlib.Path(__file__).resolve().parents[2] / "benchmarks"
    if str(bench) not in sys.path:
        sys.path.insert(0, str(bench))
    from semkit_dev_family import appearance
    return make_sem_image((768, 1024), stage="post", seed=seed,
                          **{**appearance(seed), **changes})

"""Crack classification: pre-existing (inter / intra / trans-granular) and post-test
(tensile / shear / mixed) types, the post-test model, user labels.

Modules, lowest first (each imports only those above it):

* :mod:`~semkit.classify.morphology` — per-crack-group morphology, the thesis's criteria
  (:func:`crack_morphology`);
* :mod:`~semkit.classify.pre` — He et al.'s rule against a grain map (:func:`classify_pre`);
* :mod:`~semkit.classify.model` — the calibrated logistic model, its trained feature ranges,
  JSON in and out, training (:func:`train_post`);
* :mod:`~semkit.classify.post` — :func:`classify_post` (types, probabilities, out-of-range
  flags);
* :mod:`~semkit.classify.labels` — :func:`read_labels`, :func:`apply_labels`;
* :mod:`~semkit.classify.stage` — :func:`classify_stage`, the step of the analysis that adds
  types and confidences to one image's ``cracks.csv`` rows.

The model is a small JSON dict; :func:`train_post` fits it from labelled cracks (``semkit
classify --train``, folder loop in :func:`semkit.workflow.train_from_folder`).
"""
from .labels import apply_labels, read_labels
from .model import DEFAULT_POST_MODEL, load_model, save_model, train_post
from .morphology import FEATURE_NAMES, LINK_PX, WINDOW_PX, crack_groups, crack_morphology
from .post import classify_post
from .pre import INTER_MIN_FRACTION, INTRA_MIN_FRACTION, classify_pre
from .stage import classify_stage

__all__ = ["classify_pre", "crack_morphology", "crack_groups", "classify_post", "train_post",
           "save_model", "load_model", "apply_labels", "read_labels", "classify_stage",
           "DEFAULT_POST_MODEL", "FEATURE_NAMES", "INTER_MIN_FRACTION", "INTRA_MIN_FRACTION",
           "LINK_PX", "WINDOW_PX"]

"""Crack classification: pre-existing (inter / intra / trans-granular) and post-test
(tensile / shear / mixed) types, the post-test model, user labels.

Modules, lowest first (each imports only those above it):

* :mod:`~semkit.classify.features` — per-skeleton-pixel morphology (:func:`post_features`);
* :mod:`~semkit.classify.traces` — skeleton branches joined into traces, along-trace features;
* :mod:`~semkit.classify.pre` — He et al.'s rule against a grain map (:func:`classify_pre`);
* :mod:`~semkit.classify.model` — the logistic / softmax model, JSON in and out, training;
* :mod:`~semkit.classify.post` — :func:`classify_post`;
* :mod:`~semkit.classify.labels` — :func:`read_labels`, :func:`apply_labels`;
* :mod:`~semkit.classify.stage` — :func:`classify_stage`, the step of the analysis that adds
  types and confidences to one image's ``cracks.csv`` rows.

The model is a small JSON dict; :func:`train_post` fits it from labelled cracks (``semkit
classify --train``, folder loop in :func:`semkit.workflow.train_from_folder`).
"""
from .features import FEATURE_NAMES, LINK_PX, WINDOW_PX, crack_clusters, post_features
from .labels import apply_labels, read_labels
from .model import DEFAULT_POST_MODEL, load_model, save_model, train_post
from .post import classify_post
from .pre import INTER_MIN_FRACTION, INTRA_MIN_FRACTION, classify_pre
from .stage import classify_stage

__all__ = ["classify_pre", "post_features", "classify_post", "train_post", "save_model",
           "load_model", "apply_labels", "read_labels", "crack_clusters", "classify_stage",
           "DEFAULT_POST_MODEL", "FEATURE_NAMES", "INTER_MIN_FRACTION", "INTRA_MIN_FRACTION",
           "LINK_PX", "WINDOW_PX"]

"""A model the Gestures panel trained to the profile's ``[gestures] model`` handed to
the console's running classifier."""

from __future__ import annotations

from typing import Any


def use_model(session: Any, model: Any) -> str:
    """Hand ``model`` to ``session``'s running classifier (this plugin's own ``svm``);
    says what happened."""
    svc = session.camera_started
    clf = getattr(svc, "classifier", None)
    if clf is None or not hasattr(clf, "model"):
        return "the console's classifier loads it when the camera starts"
    clf.model = model
    clf.problem = None  # a model that did not fit is replaced
    svc.classifier_problem = ""
    return "the Camera screen's classifier uses it now"

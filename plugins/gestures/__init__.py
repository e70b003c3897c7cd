"""Gestures plugin: rear-DI vision pipeline, static/dynamic classifiers, touch calibration."""

"""Fixtures: the analytic simply supported plate (an independent exact reference) and
its vibration map; a command context with the default profile values."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import pytest

from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map


@pytest.fixture(scope="session")
def ss_plate() -> SSPlate:
    return SSPlate()


@pytest.fixture(scope="session")
def ss_map(ss_plate):
    return analytic_map(ss_plate)


@pytest.fixture(scope="session")
def ss_tables(ss_map):
    from plugins.vibrotactile.tables import build_tables

    return build_tables(ss_map)


@pytest.fixture
def ctx(plugins, tmp_path):
    """A command context whose profile is every section's defaults (no device drivers)."""
    from console.config.profile import Profile, validate

    path = tmp_path / "defaults.toml"
    path.write_text("")
    prof = Profile(name="defaults", path=Path(path), data=validate({}, path, plugins))
    return SimpleNamespace(profile=prof, pm=plugins)

"""Studies fixtures: the analytic plate's map as a file, plugins with the observer double."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from ..pilot_harness import quicken_pilot

HERE = Path(__file__).resolve().parent


@pytest.fixture(autouse=True)
def _abort_confirmed_in_time(monkeypatch):
    """The Studies screen aborts on a second ``a`` within ``CONFIRM_S`` seconds; on a
    loaded machine two pilot key presses can be further apart than the 3 s an
    experimenter gets, so the tests get longer (a test of the window sets its own)."""
    from plugins.studies import panel

    monkeypatch.setattr(panel, "CONFIRM_S", 30.0)


@pytest.fixture(autouse=True)
def _long_runs_start_at_once(monkeypatch):
    """A run estimated over ``saved_run.LONG_S`` asks before it starts; a fixed plan's
    estimate comes from the folder's earlier runs, whose pace is this machine's (a
    loaded one makes a resumed exp2 "long"): the tests start at once unless they test
    the question (``long_runs_ask``)."""
    from plugins.studies import saved_run

    monkeypatch.setattr(saved_run, "LONG_S", float("inf"))


@pytest.fixture
def long_runs_ask(monkeypatch):
    """The question before a long run as the console asks it (over 5 minutes)."""
    from plugins.studies import saved_run

    monkeypatch.setattr(saved_run, "LONG_S", 300.0)


@pytest.fixture(autouse=True)
def _quick_key_presses(monkeypatch):
    """The pilot's waits made cheap and its keys reliable (``tests/pilot_harness.py``)."""
    quicken_pilot(monkeypatch)


@pytest.fixture(scope="session")
def map_file(tmp_path_factory):
    from console.files.vibration_map import save_map
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map

    return save_map(tmp_path_factory.mktemp("map") / "plate.npz", analytic_map(SSPlate()))


@pytest.fixture
def double_plugins(monkeypatch):
    """Plugins with the observer test double registered as ``double``."""
    monkeypatch.syspath_prepend(str(HERE))
    from console.config import plugins as cp

    monkeypatch.setitem(cp.BUILTIN_PLUGINS, "double", "observer_double")
    sys.modules.pop("observer_double", None)
    return cp.load_plugins()


SMALL_EXP2 = """
[study]
name = "exp2"
stimulus = "hand_flow"
responses = ["up", "down", "left", "right"]
seed = 3
[[regions]]
name = "Rprelim"
center_mm = [371.73, 223.65]
hand = "right"
[[regions]]
name = "R4"
center_mm = [580.0, 320.0]
hand = "right"
[[phases]]
name = "preliminary"
factors = { region = ["Rprelim"], direction = ["up", "right"] }
repetitions = 1
replays = "unlimited"
[[phases]]
name = "main"
factors = { region = ["R4"], direction = ["up", "down", "left", "right"] }
repetitions = 1
block_by = "region"
order = "same_for_all"
replays = 1
"""


@pytest.fixture
def small_exp2(tmp_path):
    p = tmp_path / "exp2-small.toml"
    p.write_text(SMALL_EXP2)
    return p

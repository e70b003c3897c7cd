"""A message names the fix where the user is (issue 27): one mechanism, ``console.core.words``,
for the console's screens and the command line, and the Studies plugin's words use it."""

from __future__ import annotations

import pytest

from console.core.errors import UserError
from console.core.words import AT_CLI, AT_CONSOLE, Placed, listing, worded


def test_a_placed_error_is_worded_for_each_place():
    exc = Placed(
        "point x=900.0 mm is outside the grid",
        {AT_CLI: "add --extrapolate", AT_CONSOLE: "pick a point marked ·"},
    )
    assert isinstance(exc, UserError)
    assert str(exc) == "point x=900.0 mm is outside the grid; add --extrapolate"  # a command
    assert worded(exc, AT_CONSOLE) == "point x=900.0 mm is outside the grid; pick a point marked ·"
    # a place without a fix of its own never gets another place's
    only_cli = Placed("no map", {AT_CLI: "give --map"})
    assert worded(only_cli, AT_CONSOLE) == "no map"
    assert worded(UserError("plain"), AT_CONSOLE) == "plain"
    with pytest.raises(ValueError, match="no place"):
        Placed("x", {"web": "click"})
    assert listing(["a"]) == "a" and listing(["a", "b", "c"]) == "a, b and c"


def test_the_studies_words_are_for_a_place_each():
    from plugins.studies.words import CLI, SCREEN

    exc = Placed(
        "the folder is not writable",
        {AT_CLI: "give a writable --out", AT_CONSOLE: "give a writable folder"},
    )
    assert CLI.worded(exc).endswith("--out") and SCREEN.worded(exc).endswith("folder")


def test_the_consoles_hand_flow_refusal_names_no_command_line_switch(plugins):
    import numpy as np

    from console.config.profile import load_profile
    from console.session.vibration import VibrationSession
    from plugins.vibrotactile.analytic_plate import analytic_map

    vmap = analytic_map(freq_hz=np.arange(0.0, 625.01, 5.0))
    s = VibrationSession(load_profile("sim", plugins), plugins, vmap)
    corner = tuple(vmap.points_mm[vmap.point_index(84)])
    with pytest.raises(Placed) as info:
        s.hand_plan(corner, "left")
    assert "--extrapolate" in str(info.value)  # at a shell
    console = worded(info.value, AT_CONSOLE)
    assert "--" not in console and "·" in console
    # the area is the effect's own: a hand one grid step in from the edge fits
    assert s.hand_fits(tuple(vmap.points_mm[vmap.point_index(14)]))
    assert not s.hand_fits(tuple(vmap.points_mm[vmap.point_index(13)]))

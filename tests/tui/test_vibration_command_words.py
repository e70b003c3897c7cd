"""The Vibration screen's command line (``:``) suggests the command a mistyped word
meant, as the CLI does (``:mesure`` answered 'give a point id ... e.g. 51'); numbers are
still points and a word like no command still asks for a point id."""

from __future__ import annotations

import pytest

from console.core.errors import UserError
from console.tui.panes.vibration_commands import run_command


class _Pane:
    def __init__(self) -> None:
        self.heard: list = []

    def audition(self, point: int) -> None:
        self.heard.append(("audition", point))

    def flow(self, a: int, b: int) -> None:
        self.heard.append(("flow", a, b))


@pytest.mark.parametrize(
    ("typed", "meant"), [("mesure", "measure"), ("tabels", "tables"), ("hnd 51 up", "hand")]
)
def test_a_mistyped_command_names_the_one_meant(typed, meant):
    with pytest.raises(UserError, match=f"did you mean '{meant}'"):
        run_command(_Pane(), typed)


def test_points_are_still_points_and_other_words_ask_for_one():
    pane = _Pane()
    run_command(pane, "51")
    run_command(pane, "51 52")
    assert pane.heard == [("audition", 51), ("flow", 51, 52)]
    with pytest.raises(UserError, match="give a point id"):
        run_command(pane, "xyz")

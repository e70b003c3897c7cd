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
        self.cell_of = {n: (n // 12, n % 12) for n in range(84)}  # the 7 x 12 grid

    def refuse_replacing(self, _what: str) -> bool:
        return False  # no run plays on the map

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
    with pytest.raises(UserError, match="'xyz' is no point id"):
        run_command(pane, "xyz")


def test_every_word_that_is_no_point_is_named():
    """A second new operator's try: `:999 abc` named only 'abc'."""
    with pytest.raises(UserError) as refused:
        run_command(_Pane(), "999 abc")
    said = str(refused.value)
    assert "point 999 is off the grid" in said and "'abc' is no point id" in said, said
    assert "the grid has points 0-83" in said, said


def test_load_of_an_unquoted_path_with_a_space_says_to_quote_it():
    """`:load /tmp/no such/x.npz` said only 'give one vibration map file (.npz)'."""
    with pytest.raises(UserError) as refused:
        run_command(_Pane(), "load /tmp/no such/x.npz")
    said = str(refused.value)
    assert "not 2 words" in said and "quote a path with spaces" in said, said

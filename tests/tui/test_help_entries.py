"""A help entry whose key is several words (``page down / page up: ...``) is an entry of
its own, not joined to the line above (Vibration's help read ``x: cancel what runs page
down / page up: ...``); entries written side by side (``b: ...   x: ...``) each start
a line of the help screen, at 80 x 24 and 120 x 40."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui import app as console_app
from console.tui.app import HapTableApp
from console.tui.help import entries, paragraphs
from console.tui.narrow import TypesEveryKey
from console.tui.panes.camera import TargetField
from console.tui.panes.vibration_words import HELP_KEYS
from console.tui.path_field import PathField

from .conftest import wait_for
from .test_camera_layout import SIZES, screen_lines


def test_a_key_of_several_words_starts_its_own_entry():
    got = paragraphs(HELP_KEYS)
    assert any(p.startswith("page down / page up: scroll") for p in got), got
    assert "b: build the lookup tables" in got and "x: cancel what runs" in got, got
    # a hard-wrapped sentence still joins back
    assert paragraphs("m: measure the map\nwith the vibrometer") == [
        "m: measure the map with the vibrometer"
    ]


def test_entries_side_by_side_are_cut_apart():
    assert entries("b: build the lookup tables   x: cancel what runs") == [
        "b: build the lookup tables",
        "x: cancel what runs",
    ]
    # a key's own spaces stay; the next entry after them is cut
    assert entries("t / T    body threshold down / up      c / C  contact up") == [
        "t / T    body threshold down / up",
        "c / C  contact up",
    ]
    # prose, a continued line's indent, a single entry: as written
    for line in ("         the profile): type its path", "m: measure it  now", "a b c"):
        assert entries(line) == [line]


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_vibration_help_shows_each_entry_on_its_own_line(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await pilot.press("question_mark")
            # the help box's rows, inside its borders (the screen shows beside it)
            rows = lambda: [  # noqa: E731
                (r.split("█")[1] if r.count("█") >= 2 else r).strip(" █▎▊▂")
                for r in screen_lines(app)
            ]
            await wait_for(pilot, lambda: any("build the lookup" in r for r in rows()), 10, "help")
            shown = [" ".join(r.split()) for r in rows()]  # (the columns' own spaces)
            assert any(r.startswith("x: cancel what runs") for r in shown), shown
            assert any(r.startswith("enter: audition the point") for r in shown), shown
            # the descriptions of a run of entries start in one column
            raw = rows()
            starts = {
                r.index(w)
                for r in raw
                for w in ("cancel what runs", "audition the point", "build the lookup")
                if w in r
            }
            assert len(starts) == 1, [r for r in raw if ":" in r[:12]]
            built = next(r for r in shown if "build the lookup tables" in r)
            assert "x:" not in built, built

    asyncio.run(scenario())


def test_an_entry_s_key_is_the_fewest_words_before_its_separator():
    """``b: build the lookup tables  ...`` is the key ``b`` (bold), and a description too
    long for a line wraps under itself, not back at the screen's left edge."""
    from console.tui.help import ENTRY, wrap

    line = "b: build the lookup tables  from the measured maps, every point and patch"
    assert ENTRY.match(line).group("key") == "b"
    (key, first), *more = wrap(line, 40)
    assert key == "b: " and first.startswith("build the lookup"), (key, first)
    assert more and all(r.startswith("   ") and r[3] != " " for _, r in more), more


def test_a_run_of_entries_is_one_table_whatever_its_spacing():
    """Camera's ``c / C  contact`` under ``t / T    body``, Scenes' ``x  cancel`` under
    ``enter    start``: the descriptions start in one column; the words stay as written."""
    from console.tui.help import columns

    got = columns(["t / T    body threshold", "c / C  contact threshold", "v  view", "", "x  y"])
    assert got[:3] == ["t / T  body threshold", "c / C  contact threshold", "v      view"]
    assert got[3:] == ["", "x  y"]  # a lone entry stays as written
    mixed = columns(["enter: audition", "arrows: move"])
    assert mixed == ["enter:   audition", "arrows:  move"]


def test_the_help_names_every_field_that_types_a_question_mark():
    """The help's ``?`` line says where ``?`` types instead (a new operator read 'no field
    takes a ?' and then saw the TUIO target type it)."""
    line = next(x for x in console_app.HELP.splitlines() if x.startswith("? "))
    assert set(TypesEveryKey.__subclasses__()) == {TargetField, PathField}
    assert {sub.__name__ for sub in PathField.__subclasses__()} == {"PathInput", "CommandLine"}
    fields = ("recording", "TUIO target", "Studies folder", "Gestures dataset and model")
    for field in (*fields, "Vibration's : command line"):
        assert field in line, (field, line)
    assert "a path or an address" in line and "no field" not in line, line

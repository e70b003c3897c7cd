"""Issue 27, fourth new-user try: a signal that does not read names the column in what
the operator typed (1-based), not in the text the parser saw with its units marked."""

from __future__ import annotations

import re

import pytest

from console.core.errors import UserError
from console.signals.expr import parse


def _column(text: str) -> int:
    with pytest.raises(UserError) as err:
        parse(text)
    got = re.search(r"does not read at column (\d+)", str(err.value))
    assert got, str(err.value)
    return int(got.group(1))


@pytest.mark.parametrize(
    "text",
    [
        "sine(250 Hz, 20 V, 1 s))",
        "sine(250 Hz, 20 V, 1 s) * ramp(10 ms) + sine(100 Hz, 5 V, 1 s) * ramp(10 ms))",
        "  sine(250 Hz, 20 V, 1 s))",
    ],
)
def test_an_unmatched_paren_is_at_its_column(text):
    assert _column(text) == len(text)  # the last ')' typed


def test_a_missing_comma_is_at_the_value_after_it():
    text = "sine(250 Hz 20 V, 1 s)"
    assert _column(text) in (text.index("250") + 1, text.index("20 V") + 1)


def test_a_signal_that_does_not_read_is_told_in_the_signal_s_words():
    """Python's own words ('invalid syntax. Perhaps you forgot a comma?') never reach the
    operator: each usual slip is named as a signal's (a comma, a bracket, a unit)."""
    for typed, words in (
        ("seq(sine(250 Hz, 4 V, 1 s) sine(1 Hz, 1 V, 1 s))", "a comma is missing"),
        ("sine(250 Hz, 4 V, 1 s", "never closed"),
        ("sine(250 Hz, 4 V, 1 s))", "closes nothing"),
        ("sine(250 Hz,, 4 V)", "not where a value"),
    ):
        with pytest.raises(UserError) as err:
            parse(typed)
        said = str(err.value)
        assert words in said and "Perhaps" not in said and "invalid syntax" not in said, said

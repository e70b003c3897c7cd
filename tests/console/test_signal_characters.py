"""A character the signal language does not use is named as such, at its column, with
the fix (issue 27, fifth new-user try: `sine([250] Hz, 40 V, 0.5 s)` said `a comma is
missing between two parts (seq(a, b))`). One rule for every such character: brackets and
braces, `;` and `:`, quotes, `/`, `#`, and typographic signs (`×`, `−`, `–`, `“`)."""

from __future__ import annotations

import pytest

from console.core.errors import UserError
from console.signals.expr import parse

OK = "sine(250 Hz, 40 V, 0.5 s)"


@pytest.mark.parametrize(
    ("expr", "char", "column", "fix"),
    [
        ("sine([250] Hz, 40 V, 0.5 s)", "[", 6, "250 Hz, not [250] Hz"),
        ("sine(250 Hz, 40 V, 0.5 s)[0]", "[", 26, "( )"),
        ("sine({250} Hz, 40 V, 0.5 s)", "{", 6, "( )"),
        ("sine(250 Hz; 40 V, 0.5 s)", ";", 12, "comma"),
        ("seq(silence(1 s): silence(1 s))", ":", 17, "comma"),
        ("sine('250' Hz, 40 V, 0.5 s)", "'", 6, "without quotes"),
        ('sine(250 Hz, 40 V, 0.5 s) * "a"', '"', 29, "without quotes"),
        (f"{OK} \u00d7 3", "\u00d7", 27, "*"),
        (f"{OK} \u2212 {OK}", "\u2212", 27, "-"),
        (f"{OK} \u2013 {OK}", "\u2013", 27, "-"),
        ("sine(250 Hz, 40 V, 0.5 s) * \u201cx\u201d", "\u201c", 29, "without quotes"),
        (f"{OK} / 2", "/", 27, "only +, - and * combine signals; for a gain write x * 50 %"),
        (f"{OK} | {OK}", "|", 27, "only +, - and * combine signals"),
        (f"{OK} ! ", "!", 27, "sine(250 Hz, 20 V, 1 s)"),
        (f"{OK} ?", "?", 27, "sine(250 Hz, 20 V, 1 s)"),
        (f"{OK} $", "$", 27, "sine(250 Hz, 20 V, 1 s)"),
        (f"{OK} ~", "~", 27, "sine(250 Hz, 20 V, 1 s)"),
        (f"{OK}\\", "\\", 26, "sine(250 Hz, 20 V, 1 s)"),
        (f"{OK} `", "`", 27, "without quotes"),
        (f"{OK} # three pulses", "#", 27, "description"),
        (f"  {OK} [", "[", 29, "( )"),  # columns count what was typed, blanks too
    ],
)
def test_a_character_outside_the_language_is_named_with_its_fix(expr, char, column, fix):
    with pytest.raises(UserError) as err:
        parse(expr)
    msg = str(err.value)
    assert f"{char!r} at column {column} is not part of the signal syntax" in msg, msg
    assert fix in msg, msg
    assert "comma is missing" not in msg and "\n" not in msg and len(msg) < 300, msg


@pytest.mark.parametrize(
    "expr",
    [
        "sine(250Hz,40V,.5s)*50 %",
        "noise(1 V, 1 s, seed=3) * -6 dB",
        "\tsine(250 Hz, 40 V, 0.5 s) - sine(300 Hz, 1 V, 0.5 s)",
        "seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), silence(0.2 s)) * 3",
    ],
)
def test_the_language_s_own_characters_still_read(expr):
    parse(expr)


@pytest.mark.parametrize(
    ("expr", "says"),
    [
        ("s\u00efne(250 Hz, 40 V, 0.5 s)", "did you mean 'sine'"),  # a letter: a word
        ("sine(250 Hz, 40 V, 0.5 \u00b5s)", "write us"),  # the micro sign: a unit's
        (f"{OK} @ 2", "only +, - and * combine signals"),  # @ is the language's (@NAME)
    ],
)
def test_letters_and_the_language_s_signs_keep_their_own_words(expr, says):
    with pytest.raises(UserError) as err:
        parse(expr)
    assert says in str(err.value), str(err.value)

"""A duration in a message reads as it was typed: ``99999 s`` was echoed ``1e+05 s``
(Signals, a new operator's try), ``0.00001 s`` as ``1e-05 s``
(``console.core.plain_numbers``)."""

from __future__ import annotations

import pytest

from console.cli.main import main
from console.core.plain_numbers import plain_number, plain_s


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (99999, "99999"),
        (99999.0, "99999"),
        (100.001, "100.001"),
        (1e-05, "0.00001"),
        (0.5, "0.5"),
        (1.0, "1"),
        (-2.5, "-2.5"),
        (0.0, "0"),
        (123456789.0, "123456789"),
        (1 / 3, "0.333333"),
    ],
)
def test_plain_number(value, text):
    assert plain_number(value) == text
    assert plain_s(value) == f"{text} s"


def test_an_absurd_number_still_reads():
    assert plain_number(1e300) == "1e+300" and plain_number(float("inf")) == "inf"


@pytest.mark.parametrize(
    ("expr", "said"),
    [
        ("sine(250 Hz, 20 V, 99999 s)", "99999 s is longer than"),
        ("silence(99999 s)", "99999 s is longer than"),
        ("sine(250 Hz, 20 V, 0.00001 s)", "0.00001 s is shorter than"),
    ],
)
def test_signals_show_says_durations_plainly(expr, said, capsys):
    capsys.readouterr()
    assert main(["signals", "show", expr]) == 2
    err = capsys.readouterr().err
    assert said in err and "e+" not in err and "e-0" not in err, err

"""The signal syntax's bounds (issue 25): nothing typed overflows, recurses without end or
reaches the terminal raw; each is one line naming the part and the fix. And whether a
signal can ever play (what ``signals add`` asks before saving)."""

from __future__ import annotations

import pytest

from console.config.plugins import load_plugins
from console.config.profile import load_profile
from console.core.errors import UserError
from console.safety import Limits
from console.signals.check import never_plays
from console.signals.expr import parse

BIG = "1" * 400
OK = "sine(250 Hz, 20 V, 1 s) * ramp(10 ms)"


@pytest.mark.parametrize(
    ("expr", "says"),
    [
        # from the issue: OverflowError and RecursionError before
        (f"sine({BIG} Hz, 1 V, 1 s)", "400 characters long (at most 30)"),
        (f"{OK} * {BIG}", "400 characters long"),
        (f"repeat({OK}, {BIG})", "400 characters long"),
        (f"sine(250 Hz, 1 V, 1 s) * adsr(1 ms, 1 ms, {BIG}, 1 ms)", "400 characters long"),
        (f"noise(1 V, 1 s, seed={BIG})", "400 characters long"),
        (f"{OK} * 7000 dB", "gain 7000 dB is outside -200..200 dB"),
        ("-" * 900 + OK, "900 signs in a row"),
        # beyond the issue
        (f"sine(250 Hz, 1 V, {BIG} s)", "400 characters long"),
        (f"sine(250 Hz, 1 V, 1 s) * {BIG} %", "400 characters long"),
        (f"sine({'9' * 1900} Hz, 1 V, 1 s)", "1900 characters long"),
        (f"{OK} * 0x{'f' * 400}", "402 characters long"),
        (f"{OK} * 1e308 dB", "larger than any value a signal uses"),
        (f"{OK} * -7000 dB", "outside -200..200 dB"),
        ("sine(1e300 Hz, 1 V, 1 s)", "larger than any value"),
        (f"{OK} * 1e19", "larger than any value"),
        (f"{OK} * 1e300 % * 1e300 %", "larger than any value"),
        ("+" * 900 + OK, "900 signs in a row"),
        ("-+" * 450 + OK, "900 signs in a row"),
        (f"sine({'-' * 900}250 Hz, 1 V, 1 s)", "900 signs in a row before 250 Hz"),
        ("silence(1 s)+" * 150 + "silence(1 s)", "nested too deeply"),
        ("lowpass(" * 120 + "silence(1 s)" + ", 1 kHz)" * 120, "nested too deeply"),
        (f"{OK} #\udcff", "'\\udcff' at column 40, not a printable character"),
        (f"{OK} #\x1b[2J", "'\\x1b' at column 40"),
        (f"{OK}\x00", "'\\x00'"),
        (f"{OK}  # three pulses", "'#' at column 40 is not part of the signal syntax"),
        ("sine(250 Hz, 1 V, 1 s)\u202e", "not a printable character"),
    ],
)
def test_bounded_parse_is_one_line(expr, says):
    with pytest.raises(UserError) as err:
        parse(expr)
    msg = str(err.value)
    assert says in msg and "\n" not in msg and len(msg) < 400


def test_what_stays_allowed():
    parse(f"{OK} * -6 dB")
    parse(f"-{OK}")
    parse(f"--{OK}")  # two signs: still read
    parse("sine(250 Hz,\t20 V, 1 s)")  # a tab is white space
    parse("noise(1 V, 1 s, seed=999999999999999999)")  # 18 digits
    parse(f"{OK} * 200 dB")


@pytest.fixture(scope="module")
def limits() -> Limits:
    return Limits.from_profile(load_profile("sim", load_plugins()))


@pytest.mark.parametrize(
    ("expr", "says"),
    [
        ("sine(1e12 Hz, 20 V, 1 s) * ramp(10 ms)", "at or above 24000 Hz, half the outputs'"),
        ("sine(250 Hz, 300 V, 1 s) * ramp(10 ms)", "beyond every output"),
        ("sine(250 Hz, 150 V, 1 s) * ramp(10 ms)", "[limits] piezo_min_v"),  # -150 V < -100 V
        (f"{OK} * 100000", "longer than [limits] max_plan_s"),
        ("silence(0 s)", "shorter than two samples"),
        ("adsr(1 ms, 1 ms, 0.5, 1 ms)", "an envelope alone has no length"),
        ("sine(5 Hz, 50 %, 1 s)", "a ratio, not volts"),
        ("sine(250 Hz, 20 V, 0.1 s) * adsr(1 s, 1 s, 0.5, 1 s)", "longer than the 0.1 s"),
        (f"lowpass({OK}, 30 kHz)", "30000 Hz is at or above 24000 Hz"),
        ("chirp(10 Hz, 30 kHz, 10 V, 1 s) * ramp(10 ms)", "30000 Hz"),
        ("seq(sine(250 Hz, 20 V, 1 s), sine(250 Hz, 20 V, 1 s) * 60 dB) * 3", "beyond every"),
        (f"({OK} + {OK}) * 20 dB", "beyond every output"),  # 400 V in a sum
    ],
)
def test_signals_that_can_never_play_say_why(limits, expr, says):
    why = never_plays(parse(expr), limits)
    assert why is not None and says in why and "\n" not in why


@pytest.mark.parametrize(
    "expr",
    [
        OK,
        "sine(250 Hz, 100 V, 1 s) * ramp(10 ms)",  # the screen takes +-100 V
        "sine(250 Hz, 250 V, 1 s) * 40 % * ramp(10 ms)",  # a gain brings it in range
        "(sine(250 Hz, 200 V, 1 s) - sine(250 Hz, 200 V, 1 s)) * ramp(10 ms)",  # cancels
        "seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), silence(0.2 s)) * 3",
        "silence(1 s)",
        "noise(5 V, 1 s, seed=2) * ramp(5 ms)",
        "sine(250 Hz, 20 V, 1 s)",  # no ramp: the gate says so at play time (ctrl+t adds it)
    ],
)
def test_signals_that_may_play_are_saved(limits, expr):
    assert never_plays(parse(expr), limits) is None

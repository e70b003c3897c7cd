"""Issue 27, finding 15: a gesture command's progress line at a terminal says the share
done, which only moves forward, and the time left on every line once the pace tells it
(``gestures synth`` and ``gestures train`` printed the step alone)."""

from __future__ import annotations

import re
import time

from plugins.gestures.progress import ProgressLine

from ..kernel.test_kernel import at_terminal

SHARE = re.compile(r"^\s*(\d+)% ")


def test_the_line_only_moves_forward_and_says_the_time_left():
    now = [0.0]
    said: list[tuple[str, bool]] = []
    line = ProgressLine(lambda text, done: said.append((text, done)), clock=lambda: now[0])
    line(0.01, "features 1/100 samples")  # too little done, too soon: no estimate
    now[0] = 2.0
    line(0.2, "features 20/100 samples")
    now[0] = 4.0
    line(0.1, "a later step reporting less")
    now[0] = 5.0
    line(1.0, "saved")
    texts = [t for t, _ in said]
    assert texts[0] == "  1% features 1/100 samples"
    assert texts[1] == " 20% features 20/100 samples (about 8 s left)"
    assert texts[2] == " 20% a later step reporting less (about 16 s left)"  # not back to 10 %
    assert said[3] == ("100% saved", True)


def test_synth_and_train_at_a_terminal_say_the_time_left_on_every_line(tmp_path):
    ds, model = tmp_path / "ds", tmp_path / "m.skops"
    code, out = at_terminal(
        "gestures", "synth", "--out", str(ds), "--subjects", "1", "--reps", "2", timeout=120
    )
    assert code == 0, out
    t0 = time.monotonic()
    code2, out2 = at_terminal("gestures", "train", str(ds), "--out", str(model), timeout=120)
    took_s = time.monotonic() - t0
    assert code2 == 0, out2
    for text in (out, out2):
        lines = [ln.strip() for ln in re.split(r"[\r\n]+", text) if SHARE.match(ln)]
        shares = [int(SHARE.match(ln).group(1)) for ln in lines]
        assert shares == sorted(shares) and shares[-1] == 100, lines  # only forward
        # the time left shows from the run's second second (a fast machine may finish
        # the features before it: train's last step says it, asserted below)
        timed = [i for i, ln in enumerate(lines) if ln.endswith(" left)")] or [len(lines)]
        # once the time left is known, every line until the end says it
        assert all(
            ln.endswith(" left)") for ln in lines[timed[0] :] if not ln.startswith("100%")
        ), lines
    if took_s > 6.0:  # long enough for the pace to tell (from the second second on)
        assert re.search(r"training on every sample \((about|less than) [^)]* left\)", out2), out2

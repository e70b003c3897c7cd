"""The kernel checks a plan once, however often a demo replays it; a new plan is checked.

How many plans the kernel's scheduler judged is its ``plans_checked`` counter, which a
client reads in ``status()["kernel"]``."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.errors import SafetyRefusal
from console.core.types import OutputPlan, Segment
from console.signals.waveforms import tone

FS = 48000


def checks(outputs) -> int:
    """Plans the table's kernel has checked (accepted or refused) so far."""
    return int(outputs.status()["kernel"]["plans_checked"])


def test_replayed_plan_is_checked_once_and_new_plans_still_refused(outputs):
    c0 = checks(outputs)
    sig = tone(250, 10, 0.05, FS, 0.01)
    plan = OutputPlan(FS, (Segment(sig, np.zeros_like(sig), frozenset({"PA"})),))
    for _ in range(3):
        outputs.play(plan)
    assert checks(outputs) - c0 == 1
    bad = OutputPlan(FS, (Segment(100 * sig, np.zeros_like(sig), frozenset({"PA"})),))
    with pytest.raises(SafetyRefusal):
        outputs.play(bad)
    with pytest.raises(SafetyRefusal):
        outputs.play(bad)  # a refused plan is never remembered as checked
    assert checks(outputs) - c0 == 3


def test_a_checked_plan_changed_afterwards_plays_as_checked(outputs):
    sig = tone(250, 10, 0.05, FS, 0.01)
    piezo = sig.copy()
    plan = OutputPlan(FS, (Segment(piezo, np.zeros_like(sig), frozenset({"PA"})),))
    outputs.play(plan).wait(10)
    piezo *= 100  # over the limits: a second check would refuse it
    outputs.play(plan).wait(10)
    rec = outputs.recording()[:, 0]
    assert np.max(np.abs(rec)) == pytest.approx(np.max(np.abs(sig)), rel=1e-6)


def test_a_prechecked_plan_plays_unchecked_and_a_refused_one_stays_refused(outputs):
    import time

    c0 = checks(outputs)
    sig = tone(250, 10, 0.05, FS, 0.01)
    plan = OutputPlan(FS, (Segment(sig, np.zeros_like(sig), frozenset({"PA"})),))
    outputs.precheck(plan)
    assert checks(outputs) - c0 == 1
    t0 = time.monotonic()
    rep = outputs.play(plan)
    assert checks(outputs) - c0 == 1  # checked ahead: not again on the way to the driver
    assert rep.t_first_sample_s is not None and rep.t_first_sample_s >= t0
    bad = OutputPlan(FS, (Segment(100 * sig, np.zeros_like(sig), frozenset({"PA"})),))
    with pytest.raises(SafetyRefusal):
        outputs.precheck(bad)
    with pytest.raises(SafetyRefusal):
        outputs.play(bad)  # a plan refused ahead is checked (and refused) again
    assert checks(outputs) - c0 == 3

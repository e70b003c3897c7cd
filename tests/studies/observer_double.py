"""A TEST DOUBLE of the simulated observer (``contracts.SimulatedObserver``), used only in
the studies tests until the twin's observer exists: it answers the trial's true direction
with probability ``P_CORRECT`` (seeded by participant and trial), else another answer.

``HAPTABLE_TEST_HANG_AT=k`` and ``HAPTABLE_TEST_HANG_FILE=path``: at trial index k it
writes the file and hangs (a run to kill mid-trial)."""

from __future__ import annotations

import os
import time

import numpy as np

from console.core.hookspecs import hookimpl
from console.core.types import OutputPlan

P_CORRECT = 0.8
ANSWERS = {
    "left_to_right": ("right_to_left",),
    "right_to_left": ("left_to_right",),
    "up": ("down", "left", "right"),
    "down": ("up", "left", "right"),
    "left": ("up", "down", "right"),
    "right": ("up", "down", "left"),
}


class ObserverDouble:
    def __init__(self, profile=None) -> None:
        self.played: list = []

    def parameters(self, participant_seed: int) -> dict:
        return {"model": "test double", "p_correct": P_CORRECT}

    def respond(self, trial, played: OutputPlan, *, participant_seed: int):
        assert isinstance(played, OutputPlan)
        self.played.append((trial["index"], played.name))
        hang = os.environ.get("HAPTABLE_TEST_HANG_AT")
        if hang is not None and int(hang) == trial["index"]:
            path = os.environ["HAPTABLE_TEST_HANG_FILE"]
            if not os.path.exists(path):
                with open(path, "w") as f:
                    f.write("hanging")
                time.sleep(600)
        rng = np.random.default_rng([participant_seed % (2**32), trial["index"]])
        truth = trial["direction"]
        if rng.random() < P_CORRECT:
            return truth, 0.5 + rng.random()
        wrong = ANSWERS[truth]
        return wrong[int(rng.integers(len(wrong)))], 0.5 + rng.random()


@hookimpl
def haptable_register_observers(register) -> None:
    register("double", ObserverDouble)

"""Where answers come from: the console's keys, a keypad or terminal, a simulated observer.

- ``QueueResponder``: answers put by another thread (the Studies screen's keys and
  buttons, the projected arrow buttons); ``put(Answer)``.
- ``TerminalResponder``: a terminal or USB keypad: arrows as 8/2/4/6 (keypad) or
  u/d/l/r, exp1's ``1`` (left to right) / ``2`` (right to left), ``0`` or ``p`` replays.
- ``ObserverResponder``: a ``contracts.SimulatedObserver`` (the first registered)
  answers the stimulus actually played; questionnaire scores come from
  ``simulated_score`` (below).

Simulated questionnaire (documented model, seeded): an item's score is
``round(4 + 1.5 * q + f + noise)`` clipped to 1..scale, where ``q`` in [-1, 1] is the
participant's performance in that condition (``1 - 2 * share of trials with an
overshoot or a time-out``), ``f`` is +1 when the knob gave felt feedback in those trials
(detents > 0) and 0 otherwise, and ``noise`` ~ N(0, 0.8) per participant, condition and
item. It follows from the simulated trials; it is no measurement of people.
"""

from __future__ import annotations

import queue
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from console.plugin_api import SimulatedObserver

from .runner import Answer, Control

KEYS = {
    "8": "up",
    "2": "down",
    "4": "left",
    "6": "right",
    "u": "up",
    "d": "down",
    "l": "left",
    "r": "right",
    "up": "up",
    "down": "down",
    "left": "left",
    "right": "right",
}
EXP1_KEYS = {"1": "left_to_right", "2": "right_to_left", "l": "left_to_right", "r": "right_to_left"}
REPLAY_KEYS = ("0", "p", "replay")
#: the abort reason when the terminal's input ends (stdin closed, a script ran out)
INPUT_ENDED = "input ended"


def parse_key(key: str, responses: list[str]) -> Answer | None:
    """A typed or pressed key as an ``Answer`` (None: not one)."""
    k = key.strip().lower()
    if k in REPLAY_KEYS:
        return Answer(replay=True)
    if k in responses:
        return Answer(response=k)
    table = EXP1_KEYS if "left_to_right" in responses else KEYS
    r = table.get(k)
    return Answer(response=r) if r in responses else None


class QueueResponder:
    """Answers and scores put by another thread (``put``); waits for them, checking the
    run's control for an abort."""

    def __init__(self) -> None:
        self._q: queue.Queue[Any] = queue.Queue()
        self.asked: dict[str, Any] | None = None  # what the participant is asked now

    def put(self, answer: Answer | int) -> None:
        self._q.put(answer)

    def clear(self) -> None:
        while not self._q.empty():
            self._q.get_nowait()

    def _get(self, control: Control, want: type) -> Any:
        while True:
            control.check()
            try:
                x = self._q.get(timeout=0.05)
            except queue.Empty:
                continue
            if isinstance(x, want):
                return x

    def answer(self, trial, played, replays_left, control: Control) -> Answer:
        self.clear()
        self.asked = {"trial": trial, "replays_left": replays_left}
        t0 = time.monotonic()
        a = self._get(control, Answer)
        self.asked = None
        if a.replay or a.response_time_s is not None:
            return a
        return Answer(response=a.response, response_time_s=time.monotonic() - t0)

    def rate(self, item, questionnaire, records, control: Control) -> int:
        self.clear()
        self.asked = {"item": item, "scale": questionnaire["scale"]}
        score = self._get(control, int)
        self.asked = None
        return score


class TerminalResponder:
    """Answers typed at a terminal (or a keypad that types)."""

    def __init__(
        self,
        responses: list[str],
        read: Callable[[str], str] | None = None,
        write: Callable[[str], Any] = lambda s: print(s, file=sys.stderr),
    ) -> None:
        self.responses = responses
        self.read = read or (lambda prompt: input(prompt))
        self.write = write

    def answer(self, trial, played, replays_left, control: Control) -> Answer:
        left = "unlimited" if replays_left is None else str(replays_left)
        keys = (
            "1 = left to right, 2 = right to left"
            if "left_to_right" in self.responses
            else "8/u up, 2/d down, 4/l left, 6/r right"
        )
        t0 = time.monotonic()
        while True:
            control.check()
            try:
                raw = self.read(f"trial {trial['index'] + 1}: {keys}; 0/p replay ({left} left): ")
            except EOFError:
                control.abort(INPUT_ENDED)
                control.check()
            a = parse_key(raw, self.responses)
            if a is None:
                self.write(f"{raw!r} is not an answer: {keys}, or 0/p to replay")
                continue
            if a.replay:
                return a
            return Answer(response=a.response, response_time_s=time.monotonic() - t0)

    def rate(self, item, questionnaire, records, control: Control) -> int:
        scale = questionnaire["scale"]
        while True:
            control.check()
            try:
                raw = self.read(
                    f"[{questionnaire['condition']}] {item['text']} (1 = disagree .. "
                    f"{scale} = agree): "
                )
            except EOFError:
                control.abort(INPUT_ENDED)
                control.check()
            if raw.strip().isdigit() and 1 <= int(raw) <= scale:
                return int(raw)
            self.write(f"{raw!r}: give a whole number from 1 to {scale}")


def simulated_score(records: list[dict[str, Any]], scale: int, rng: np.random.Generator) -> int:
    """A questionnaire score from the participant's simulated trials (module docstring)."""
    if records:
        bad = sum(1 for r in records if r.get("overshoots", 0) or r.get("timed_out"))
        q = 1.0 - 2.0 * bad / len(records)
        felt = 1.0 if any((r.get("detents") or 0) > 0 for r in records) else 0.0
    else:
        q, felt = 0.0, 0.0
    x = 4.0 + 1.5 * q + felt + rng.normal(0.0, 0.8)
    return int(np.clip(round(x), 1, scale))


class ObserverResponder:
    """A simulated participant: the observer answers what was played."""

    def __init__(self, observer: Any, participant_seed: int) -> None:
        self.observer = observer
        self.seed = int(participant_seed)

    def answer(self, trial, played, replays_left, control: Control) -> Answer:
        response, rt = self.observer.respond(trial, played, participant_seed=self.seed)
        return Answer(response=str(response), response_time_s=float(rt))

    def rate(self, item, questionnaire, records, control: Control) -> int:
        key = f"{self.seed}:{questionnaire['condition']}:{item['category']}:{item['item']}"
        rng = np.random.default_rng(list(key.encode()))
        return simulated_score(records, int(questionnaire["scale"]), rng)


def observer(plugins: Any, profile: Any) -> Any:
    """The first registered ``SimulatedObserver`` (a one-line error naming the plugin to
    enable when none is)."""
    return plugins.provider("observer", SimulatedObserver, profile, plugin_hint="twin")

"""A demo's start moves forward with the time left (issue 27, seventh try, finding 1): its
process sits in one step ("opening the camera") for seconds, the bar does not."""

from __future__ import annotations

import threading

from console.runtime import start_clock
from console.runtime.demo_process import DemoProcess
from console.runtime.start_clock import StartClock


class FakeTime:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def test_the_start_moves_forward_with_the_time_left_and_learns_the_last_start(tmp_path):
    path, now = tmp_path / "starts.json", FakeTime()
    clock = StartClock("flow", path=path, now=now)
    seen = []
    for t_s in (0.0, 2.0, 6.0, 11.0, 20.0, 40.0):
        now.t = 100.0 + t_s
        seen.append(clock.fraction_text("opening the camera"))
    fracs = [f for f, _ in seen]
    assert fracs == sorted(fracs) and len(set(fracs)) == len(fracs)  # forward, every time
    assert fracs[-1] < 1.0  # full only once it runs
    assert "about 12 s left (a guess)" in seen[0][1] and "about 6 s left" in seen[2][1]
    assert "longer than guessed (12 s)" in seen[4][1]
    now.t = 105.0  # this start took 5 s: the next one expects that
    clock.done()
    again = StartClock("flow", path=path, now=now)
    assert again.expected_s == 5.0 and again.left_text() == "about 5 s left"
    now.t += 2.5
    assert abs(again.fraction() - start_clock.AT_EXPECTED / 2) < 1e-9
    assert clock.fraction(floor=0.97) == 0.97  # the demo's own preparation counts


def test_waiting_for_a_demo_reports_progress_while_its_step_does_not_change(monkeypatch, tmp_path):
    monkeypatch.setattr(start_clock, "DEFAULT_START_S", 1.0)
    monkeypatch.setattr(start_clock, "starts_path", lambda: tmp_path / "starts.json")
    run = DemoProcess.__new__(DemoProcess)  # its messages, without a process
    run.name, run.stopped, run.scene_name = "flow", False, None
    run._started, run._ended = threading.Event(), threading.Event()
    run._progress = (0.0, "opening the camera")

    def comes_up() -> None:
        run.scene_name = "flow_hand"
        run._started.set()

    timer = threading.Timer(0.8, comes_up)
    timer.start()
    got: list[tuple[float, str]] = []
    run.wait_started(lambda f, text: got.append((f, text)))
    timer.join()
    fracs = [f for f, _ in got]
    assert len(got) >= 4, got  # before: one 5 % for the whole step
    assert fracs == sorted(fracs) and fracs[-1] > 0.4
    assert all("opening the camera" in text and "left" in text for _, text in got)

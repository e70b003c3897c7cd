"""The real ``haptable`` command in a terminal (tmux), driven by keys as a person would:
open Vibration, audition point 51, play the flow 51 -> 52, toggle relay 1, e-stop, quit.
Then the twin's audio and relay logs (written on exit, HAPTABLE_TWIN_LOG) must show
exactly those stimuli, relays switched only in silence and every relay open at the end."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from console.core.types import patches_of

from .conftest import segment_in

pytestmark = [
    pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed"),
    pytest.mark.slow,
]


def _haptable() -> str:
    cand = Path(sys.executable).parent / "haptable"
    return str(cand) if cand.is_file() else (shutil.which("haptable") or "haptable")


class Term:
    def __init__(self, tmp_path: Path, env: dict[str, str]) -> None:
        self.sock = str(tmp_path / "tmux.sock")
        self.name = "haptable"
        envs = " ".join(f"{k}={v}" for k, v in env.items())
        # COLUMNS/LINES (set by test runners) would override the terminal's real size
        cmd = f"env -u COLUMNS -u LINES {envs} {_haptable()}; echo HAPTABLE-EXITED $?; sleep 30"
        self.tmux("new-session", "-d", "-s", self.name, "-x", "100", "-y", "30", cmd)
        self.tmux("resize-window", "-t", self.name, "-x", "100", "-y", "30")

    def tmux(self, *args: str) -> str:
        out = subprocess.run(
            ["tmux", "-S", self.sock, *args], capture_output=True, text=True, timeout=20
        )
        return out.stdout

    def screen(self) -> str:
        return self.tmux("capture-pane", "-p", "-t", self.name)

    def keys(self, *keys: str, literal: bool = False) -> None:
        self.tmux("send-keys", "-t", self.name, *(["-l"] if literal else []), *keys)

    def wait(self, text: str | tuple[str, ...], timeout_s: float = 30.0) -> str:
        """The screen once it shows ``text`` (or one of several: a short state such as
        ``playing`` can be over between two looks on a loaded machine, its outcome not)."""
        texts = (text,) if isinstance(text, str) else text
        t_end = time.monotonic() + timeout_s
        while time.monotonic() < t_end:
            s = self.screen()
            if any(t in s for t in texts):
                return s
            time.sleep(0.1)
        raise AssertionError(f"{text!r} did not appear; the screen:\n{self.screen()}")

    def open_tab(self, key: str, shows: str, tries: int = 5) -> str:
        """Press a function key until its screen shows (an escape sequence can be split
        and lost on a loaded machine, as a person pressing it again would notice)."""
        for _ in range(tries):
            self.keys(key)
            try:
                return self.wait(shows, 4.0)
            except AssertionError:
                continue
        return self.wait(shows, 1.0)

    def close(self) -> None:
        self.tmux("kill-server")


def test_console_in_a_terminal(tmp_path, map_file):
    log = tmp_path / "twin.json"
    env = {
        "HAPTABLE_TWIN_LOG": str(log),
        "HOME": os.environ["HOME"],
        "XDG_RUNTIME_DIR": os.environ["XDG_RUNTIME_DIR"],
        "HAPTABLE_LOAD_ENTRYPOINTS": "0",
        "TERM": "xterm-256color",
    }
    term = Term(tmp_path, env)
    try:
        term.wait("outputs idle", 60)
        term.open_tab("F3", "no vibration map")
        # the footer lists the screen's own keys once the focus is in it (as a person
        # waits for the screen to answer before typing its ':' command)
        term.wait("m measure", 30)
        term.keys(":")
        time.sleep(0.3)
        term.keys(f"load {map_file}", literal=True)
        term.keys("Enter")
        term.wait("ready", 60)
        term.keys(":")
        time.sleep(0.3)
        term.keys("51", literal=True)
        term.keys("Enter")
        term.wait(("playing point 51", "played point 51"))
        term.wait("outputs idle")
        term.keys(":")
        time.sleep(0.3)
        term.keys("51 52", literal=True)
        term.keys("Enter")
        shown = term.wait(("playing flow 51->52", "played flow 51->52"))
        if "playing flow" in shown:  # the bar may still show the idle state from before:
            # see the flow play (unless it ended between two looks), then end
            term.wait(("outputs PLAYING", "played flow 51->52"), 20)
        term.wait("played flow 51->52", 20)
        term.wait("outputs idle", 20)
        term.open_tab("F4", "relay 1  PA")
        time.sleep(0.3)
        term.keys("1")
        term.wait("relays closed: 1")
        term.keys("C-e")
        term.wait("E-STOP: operator e-stop")
        term.keys("q")
        term.wait("HAPTABLE-EXITED 0", 20)
    finally:
        term.close()

    data = json.loads(log.read_text())
    arrays = np.load(log.with_suffix(".npz"))
    rec = arrays["recording_v"]
    played = data["played"]
    assert [p["name"] for p in played] == ["point 51", "flow 51->52"]

    # exactly the auditioned stimuli reached the amplifiers, sample for sample, in order
    # (parts on the same patches play back to back: no relay switch, no gap)
    waves = [
        (arrays[f"plan{i}_seg{j}_piezo_v"], seg)
        for i, p in enumerate(played)
        for j, seg in enumerate(p["segments"])
    ]
    pos, starts = 0, []
    for wave, meta in waves:
        first = pos + int(np.flatnonzero(rec[pos:, 0])[0])
        err = segment_in(rec[:, 0], wave, first, data["underruns"])
        assert err < 1e-3, f"{meta['label']}: differs by {err:.3g} V at sample {first}"
        start = first - int(np.flatnonzero(wave)[0])
        starts.append(start)
        pos = start + wave.size
    assert not np.any(rec[pos:]), "nothing else played"
    assert not np.any(rec[:, 1]), "the screen channel stayed silent"
    bursts = data["bursts"]
    point = played[0]["meta"]
    assert abs(bursts[0]["piezo_freq_hz"] - point["frequency_hz"]) < 1.0
    assert abs(bursts[0]["piezo_peak_v"] - played[0]["segments"][0]["piezo_peak_v"]) < 1e-3

    # relays: the point's patches closed before it and opened after it, all in silence
    relays = data["relay_log"]
    assert all(r["level_v"] == [0.0, 0.0] for r in relays)
    channels = {"PA": 1, "PB": 2, "PC": 3, "PD": 4}
    want = {channels[p] for p in patches_of(point["actuator"])}
    closed_before = {r["channel"] for r in relays if r["closed"] and r["clock"] <= starts[0]}
    assert want <= closed_before
    # the operator's relay 1 toggle after the flow, then the e-stop opened it
    after = [(r["channel"], r["closed"]) for r in relays if r["clock"] >= pos]
    assert after[-2:] == [(1, True), (1, False)]
    state: dict[int, bool] = {}
    for r in relays:
        state[r["channel"]] = r["closed"]
    assert not any(state.values())
    assert data["estop_reason"] == "operator e-stop (console)"

"""``haptable signals play`` of a library signal meant for a channel (the built-in
``screen-180`` for the screen): it plays there without a flag and is refused on another,
as the console's Signals screen loads it with its channel."""

import os
import subprocess
import sys


def _haptable(*args: str) -> subprocess.CompletedProcess:
    code = "from console.cli.entry import main; raise SystemExit(main())"
    return subprocess.run(
        [sys.executable, "-c", code, *args],
        capture_output=True, text=True, env=dict(os.environ), timeout=120,
    )  # fmt: skip


def test_a_signal_meant_for_the_screen_plays_there_and_not_on_a_patch():
    out = _haptable("signals", "play", "screen-180", "--patch", "PA", "--dry-run")
    assert out.returncode == 2, out.stdout
    assert "screen-180 is meant for screen, not PA: play it with --screen" in out.stderr
    out = _haptable("signals", "play", "screen-180", "--dry-run")
    assert out.returncode == 0, out.stderr
    assert "screen" in out.stdout
    out = _haptable("signals", "add", "pc-pulse", "sine(200 Hz, 10 V, 0.2 s) * ramp(10 ms)",
                    "--target", "PC")  # fmt: skip
    assert out.returncode == 0, out.stderr
    assert "pc-pulse" in _haptable("signals", "list").stdout
    assert "[on PC]" in _haptable("signals", "list").stdout
    out = _haptable("signals", "play", "tone-250", "--dry-run")  # meant for none: say where
    assert out.returncode == 2 and "--patch PA" in out.stderr

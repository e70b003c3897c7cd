"""The recorder without a demo: frames come back bit for bit, a killed run leaves a
readable file, bad files are one line naming the file and the fix, plans are told apart."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from console.core.errors import UserError
from console.core.types import Frame, OutputPlan, Segment

REPO = Path(__file__).resolve().parents[2]
PROFILE = SimpleNamespace(name="test", data={"camera": {"fps": 60}}, path=None)


def noisy(seq: int, shape=(48, 64)) -> np.ndarray:
    """A frame that depends on its number only (the reference the file is checked against)."""
    return np.random.default_rng(seq).integers(0, 256, shape, dtype=np.uint8)


@pytest.mark.parametrize("codec", ["lzf", "gzip1"])
def test_frames_read_back_bit_for_bit(tmp_path, codec):
    from plugins.recording.reader import open_recording
    from plugins.recording.writer import Recorder

    rec = Recorder(tmp_path / "r.h5", PROFILE, codec=codec, queue_frames=64)
    for k in range(40):
        rec(Frame(noisy(k), 100 + k, k / 60), {})
    rec.close()
    assert (rec.written, rec.dropped, rec.error) == (40, 0, "")
    with open_recording(tmp_path / "r.h5") as r:
        assert r.n_frames == 40 and r.attrs["codec"] == codec
        assert list(r.seq) == list(range(100, 140))
        assert np.array_equal(r.t_capture_s, np.arange(40) / 60)
        for k in range(40):
            assert np.array_equal(r.frame(k), noisy(k))
        assert r.versions["numpy"] == np.__version__


def test_a_full_queue_drops_and_counts_the_frame(tmp_path):
    from plugins.recording.reader import open_recording
    from plugins.recording.writer import Recorder

    class SlowDisk(Recorder):
        def _write(self, ds, item, packed=None):
            time.sleep(0.02)  # a writer far behind the camera
            super()._write(ds, item, packed)

    rec = SlowDisk(tmp_path / "r.h5", PROFILE, queue_frames=8)
    for k in range(40):
        rec(Frame(noisy(k), k, k / 60), {})  # never blocks
    rec.close()
    assert rec.dropped >= 20 and rec.written + rec.dropped == 40
    with open_recording(tmp_path / "r.h5") as r:  # the file says so too
        assert r.stats == {"written": rec.written, "dropped": rec.dropped}
        seq = list(r.seq)
        assert seq[:8] == list(range(8)) and seq == sorted(seq)  # the first ones, in order
        assert sorted(seq + list(r.dropped_seq)) == list(range(40))  # which were dropped


WRITER = textwrap.dedent(
    """
    import sys, time
    from types import SimpleNamespace
    import numpy as np
    from console.core.types import Frame
    from plugins.recording.writer import Recorder
    rec = Recorder(sys.argv[1], SimpleNamespace(name="t", data={}, path=None), flush_s=0.05)
    k = 0
    while True:
        image = np.random.default_rng(k).integers(0, 256, (48, 64), dtype=np.uint8)
        rec(Frame(image, k, k / 60), {})
        k += 1
        if k == 60:
            print("60", flush=True)
        time.sleep(1 / 240)
    """
)


def test_a_recording_killed_with_sigkill_still_opens(tmp_path):
    from plugins.recording.reader import open_recording

    path = tmp_path / "killed.h5"
    child = subprocess.Popen(
        [sys.executable, "-c", WRITER, str(path)], stdout=subprocess.PIPE, text=True, cwd=REPO
    )
    seen, t_end = 0, time.monotonic() + 30
    try:
        assert child.stdout.readline().strip() == "60"
        while seen < 30 and time.monotonic() < t_end:  # read while it writes (SWMR)
            time.sleep(0.05)
            try:
                with open_recording(path) as r:
                    seen = r.n_frames
            except UserError:
                pass  # not yet in SWMR mode
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait(10)
    assert seen >= 30
    with open_recording(path) as r:  # every frame flushed before the kill, whole
        assert r.n_frames >= seen
        for k in range(r.n_frames):
            assert r.seq[k] == k and np.array_equal(r.frame(k), noisy(k))
            assert r.decisions(k)["gesture"] is None


def test_bad_files_are_one_line_naming_the_file(tmp_path):
    import h5py

    from plugins.recording.reader import open_recording
    from plugins.recording.writer import Recorder

    text = tmp_path / "notes.txt"
    text.write_text("hello")
    other = tmp_path / "other.h5"
    with h5py.File(other, "w") as f:
        f["x"] = [1, 2]
    cases = {
        tmp_path / "missing.h5": "no such file",
        text: "not an HDF5 file",
        other: "not a HapTable recording",
        tmp_path: "is a folder",
    }
    for path, what in cases.items():
        with pytest.raises(UserError) as err:
            open_recording(path)
        msg = str(err.value)
        assert str(path) in msg and what in msg and "--record" in msg and "\n" not in msg
    with pytest.raises(UserError, match="folder .*nowhere does not exist; create it"):
        Recorder(tmp_path / "nowhere" / "r.h5", PROFILE)


def test_plans_differing_in_one_sample_hash_apart():
    from plugins.recording.decisions import plan_hash

    def plan(x: float) -> OutputPlan:
        v = np.sin(np.arange(480) / 10.0)
        v[100] = x
        return OutputPlan(48000, (Segment(v, np.zeros(480), frozenset({"PA"})),), "p")

    assert plan_hash(plan(0.5)) == plan_hash(plan(0.5))
    assert plan_hash(plan(0.5)) != plan_hash(plan(np.nextafter(0.5, 1.0)))


def test_plans_handed_to_the_outputs_are_kept_with_their_clocks(tmp_path):
    import threading

    from plugins.recording.decisions import plan_hash
    from plugins.recording.reader import open_recording
    from plugins.recording.writer import Recorder

    done = threading.Event()
    done.set()

    class Outputs:
        estopped = False

        def play(self, plan, wait=True):
            return SimpleNamespace(
                segment_start=[480], segment_end=[959], t_first_sample_s=2.5, error="", done=done
            )

        def estop(self):
            self.estopped = True

    plan = OutputPlan(48000, (Segment(np.ones(480), np.zeros(480), frozenset({"PB"})),), "p1")
    rec = Recorder(tmp_path / "r.h5", PROFILE)
    out = rec.watch_outputs(Outputs())
    out.play(plan, wait=False)
    out.estop()  # everything else is the outputs' own
    assert out._outputs.estopped
    rec(Frame(noisy(0), 0, 0.0), {"plan": plan})
    rec.close()
    with open_recording(tmp_path / "r.h5") as r:
        (line,) = r.plans()
        assert line["kind"] == "plan" and line["hash"] == plan_hash(plan)
        assert line["segment_start"] == [480] and line["t_first_sample_s"] == 2.5
        assert r.decisions(0)["plan"]["hash"] == plan_hash(plan)  # the frame that decided it

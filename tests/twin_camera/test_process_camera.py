"""The twin camera apart (``TwinCamera.apart()``): the same frames as the twin rendering
in this process, commands reaching the child, a rate for viewers that need few frames,
and no process left behind."""

from __future__ import annotations

import os
import pickle
import time

import numpy as np

from plugins.twin.camera.factory import make_camera
from plugins.twin.camera.process import CMD


def _twin(realtime: bool = True):
    cam = make_camera(None)
    cam.realtime = realtime
    return cam


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie is gone for good (its parent has not reaped it yet)
    with open(f"/proc/{pid}/stat") as f:
        return f.read().rsplit(")", 1)[1].split()[0] != "Z"


def test_apart_delivers_the_frames_the_twin_renders_in_process():
    """Same rig, script and seed: frame k from the child equals frame k rendered here
    (noise included), and its background is the empty table the twin renders here."""
    here = _twin(realtime=False)
    cam = _twin(realtime=False).apart()
    try:
        assert np.array_equal(cam.background(), here.background())
        here = _twin(realtime=False)  # background() drew from the rng: start over
        here.background()
        frames = [cam.read(5.0) for _ in range(40)]
        assert all(f is not None for f in frames)
        by_seq = {f.seq: f.image for f in frames}
        mine = {}
        for _ in range(max(by_seq) + 1):
            f = here.read()
            mine[f.seq] = f.image
        assert by_seq.keys() <= mine.keys()
        for seq, img in by_seq.items():
            assert np.array_equal(img, mine[seq]), f"frame {seq} differs"
        st = cam.status()
        assert st["process"] and st["alive"]
    finally:
        cam.close()


def test_close_ends_the_process_and_a_closed_camera_reads_nothing():
    cam = _twin().apart()
    pid = cam.pid
    assert cam.read(5.0) is not None
    cam.close()
    assert not _alive(pid), "the camera process ended"
    assert cam.read(0.1) is None
    assert not cam.status()["alive"]
    cam.set_target((100.0, 100.0))  # closed: nothing to tell, no error
    cam.set_rate(10)


def test_the_child_ends_when_its_parent_goes_away():
    """No orphan: the child stops at the end of its stdin (the parent's end, however it
    comes), not only on ``close()``."""
    cam = _twin().apart()
    pid = cam.pid
    cam._proc.stdin.close()  # what the parent's death does to the pipe
    t_end = time.monotonic() + 10
    while cam._proc.poll() is None and time.monotonic() < t_end:
        cam.read(0.1)  # keep draining its announcements
    assert cam._proc.poll() is not None
    assert not _alive(pid)
    cam.close()


def test_the_mapping_stays_in_the_parent():
    twin = _twin()
    cam = twin.apart()
    try:
        p = (300.0, 200.0)
        assert cam.mm_to_px(p) == twin.mm_to_px(p)
        assert cam.mapping is twin.mapping
    finally:
        cam.close()


def test_a_rate_renders_fewer_frames_on_the_script_s_time():
    """``set_rate(15)`` on a 60 fps twin: every fourth frame of the script's time is
    rendered (``seq`` four apart: the gestures last as long); ``None`` gives all."""
    cam = _twin(realtime=False)
    cam.set_rate(15)
    seqs = [cam.read().seq for _ in range(10)]
    assert set(np.diff(seqs)) == {4}
    assert cam.status()["rate_fps"] == 15
    cam.set_rate(None)
    seqs = [cam.read().seq for _ in range(10)]
    assert set(np.diff(seqs)) == {1}
    assert cam.status()["rate_fps"] is None


def test_apart_a_rate_reaches_the_child():
    """The child renders at the rate asked: frames four apart on the script's time, no
    more of them than the rate allows (fewer on a loaded machine: late ones are lost)."""
    cam = _twin().apart()
    try:
        cam.set_rate(15)
        time.sleep(0.3)
        while cam._next(0) is not None:  # what it rendered before the command arrived
            pass
        t0 = time.monotonic()
        frames = []
        while time.monotonic() - t0 < 1.0:
            f = cam.read(0.2)
            if f is not None:
                frames.append(f)
        steps = np.diff([f.seq for f in frames])
        assert len(frames) >= 3 and all(s % 4 == 0 for s in steps), steps
        assert len(frames) <= 17
        assert cam.status()["rate_fps"] == 15
    finally:
        cam.close()


def test_commands_reach_the_child():
    """``set_target`` crosses to the child: the hand shows where the operator put it."""
    cam = _twin().apart()
    try:
        bg = cam.background().astype(int)

        def centroid():
            time.sleep(0.4)
            frames = [f for f in (cam.read(2.0) for _ in range(12)) if f is not None]
            ys, xs = np.nonzero(np.abs(frames[-1].image.astype(int) - bg) > 30)
            assert xs.size > 200, "a hand is on the table"
            return np.array([xs.mean(), ys.mean()])

        cam.set_target((200.0, 150.0))
        a = centroid()
        cam.set_target((600.0, 300.0))
        b = centroid()
        assert np.hypot(*(b - a)) > 250
    finally:
        cam.close()


def test_commands_that_arrive_together_all_reach_the_child():
    """The calibration's "lift" and "touch the next target" leave in one breath: the
    child applies both (the hand ends at the second target), not only the first of what
    one read of the pipe brought."""
    cam = _twin().apart()
    try:
        bg = cam.background().astype(int)
        cam.set_target((200.0, 150.0))
        # three commands in one write: the pipe delivers them together
        blobs = [
            pickle.dumps(("set_target", (None,))),
            pickle.dumps(("set_target", ((600.0, 300.0),))),
            pickle.dumps(("set_rate", (20.0,))),
        ]
        cam._proc.stdin.write(b"".join(CMD.pack(len(b)) + b for b in blobs))
        cam._proc.stdin.flush()
        time.sleep(0.6)
        frames = [f for f in (cam.read(2.0) for _ in range(12)) if f is not None]
        ys, xs = np.nonzero(np.abs(frames[-1].image.astype(int) - bg) > 30)
        assert xs.size > 200, "the hand came back on the table at the second target"
        want = np.array(cam.mm_to_px((600.0, 300.0)))
        assert np.hypot(*(np.array([xs.mean(), ys.mean()]) - want)) < 150
    finally:
        cam.close()


def test_rate_zero_pauses_the_child_and_a_rate_resumes_it():
    """``set_rate(0)`` (nobody reads): the child renders nothing, costs no CPU; a rate
    again: frames come, the stale ones from before the pause are not counted as drops."""
    cam = _twin().apart()
    try:
        assert cam.read(5.0) is not None
        cam.set_rate(0)
        time.sleep(0.5)
        while cam._next(0) is not None:  # what it rendered before the command arrived
            pass
        cpu0 = _cpu_s(cam.pid)
        time.sleep(1.0)
        assert cam.read(0.3) is None, "no frame while paused"
        assert _cpu_s(cam.pid) - cpu0 < 0.05
        cam.set_rate(10)
        f = cam.read(5.0)
        # the first frame after the pause is a new one, not one rendered before it
        assert f is not None and time.monotonic() - f.t_capture_s < 0.6
    finally:
        cam.close()


def _cpu_s(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def test_frames_before_the_first_read_are_unread_not_dropped():
    """A demo prepares for seconds after opening the camera: what the child rendered
    before the loop's first read is not a frame the loop dropped, and the first frame read
    is a fresh one, not the oldest waiting."""
    cam = _twin().apart()
    try:
        time.sleep(0.6)  # ~36 frames at 60 fps announced, nobody reading
        first = cam.read(5.0)
        assert first is not None and time.monotonic() - first.t_capture_s < 0.25
        assert all(cam.read(5.0) is not None for _ in range(10))
        st = cam.status()
        # (the backlog alone was ~36; a loaded machine's renderer may burst a frame or two)
        assert st["dropped_reading"] < 5, st
        assert st["unread"] >= 20, st
    finally:
        cam.close()

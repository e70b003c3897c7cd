"""The full-screen window path (pyglet + moderngl.create_context) on a virtual X display.

Skips unless Xvfb is installed (Debian: xvfb); the lab machine uses a real screen.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess

import cv2
import pytest

from console.runtime.projector.service import ProjectorService
from plugins.projector.launch import projector_command
from plugins.projector.scenes import BUILTIN_SCENES

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(
        shutil.which("Xvfb") is None, reason="Xvfb not installed (apt install xvfb)"
    ),
]


@pytest.fixture
def display():
    r, w = os.pipe()
    xvfb = subprocess.Popen(
        ["Xvfb", "-displayfd", str(w), "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
        pass_fds=(w,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    os.close(w)
    with os.fdopen(r) as f:
        num = f.readline().strip()
    if not num.isdigit():
        xvfb.kill()
        pytest.skip("Xvfb did not start")
    yield f":{num}"
    with contextlib.suppress(ProcessLookupError):
        os.kill(xvfb.pid, signal.SIGKILL)
    xvfb.wait()


@pytest.mark.usefixtures("requires_egl")  # no Mesa GL at all: nothing to test
def test_window_projector_draws_the_knob_full_screen(display, tmp_path):
    sock = tmp_path / "p.sock"
    svc = ProjectorService(
        socket_path=sock,
        command=projector_command(
            sock, extra=["--screen", "0", "--heartbeat-s", "0.1", "--peer-timeout-s", "2"]
        ),
        scenes={n: c for n, (c, _) in BUILTIN_SCENES.items()},
        heartbeat_s=0.1,
        peer_timeout_s=2.0,
        log_path=tmp_path / "projector.log",
        env={**os.environ, "DISPLAY": display},
    )
    pid = None
    try:
        svc.start()
        pid = svc.supervisor.pid
        assert svc.link.wait_connected(30), (tmp_path / "projector.log").read_text()
        assert svc.link.peer["headless"] is False and svc.link.peer["size_px"] == [1280, 800]
        svc.start_scene("knob")
        assert svc.wait_drawn(20)
        out = tmp_path / "window.png"
        assert svc.snapshot(out, 20)
        img = cv2.imread(str(out))
        assert img.shape == (800, 1280, 3)
        red = (img[..., 2] > 180) & (img[..., 1] < 90) & (img[..., 0] < 90)
        blue = (img[..., 0] > 180) & (img[..., 2] < 110)
        assert red.sum() > 20 and blue.sum() > 100
        svc.stop_scene()
        assert svc.wait_drawn(20) and svc.snapshot(out, 20)
        assert cv2.imread(str(out)).max() == 0  # black
    finally:
        svc.close()
        if pid is not None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)

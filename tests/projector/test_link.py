"""The console <-> projector link: protocol, black on console loss, and SIGKILL on each side.

The subprocess tests start real projector processes (headless, EGL) through the
supervisor and kill them; generous timeouts only bound the wait (no timing asserts).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import pytest

from console.core.errors import UserError
from console.runtime.projector.protocol import LineBuffer, ProtocolError, encode, probe
from console.runtime.projector.service import ProjectorService
from plugins.projector.launch import projector_command
from plugins.projector.scenes import BUILTIN_SCENES
from plugins.projector.server import SOCKET_CHECK_S, LinkServer

SCENES = {n: cls for n, (cls, _) in BUILTIN_SCENES.items()}
FAST = ["--size", "320x200", "--fps", "30", "--heartbeat-s", "0.1", "--peer-timeout-s", "1.0"]


def wait_until(cond, timeout_s=20.0, what="condition"):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if cond():
            return
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:
        return f.read().rsplit(")", 1)[1].split()[0] != "Z"


def inet_sockets(pid: int) -> set[str]:
    """Socket inodes of ``pid`` that are TCP/UDP (IPv4 or IPv6) sockets."""
    inodes = set()
    for fd in os.listdir(f"/proc/{pid}/fd"):
        with contextlib.suppress(OSError):
            target = os.readlink(f"/proc/{pid}/fd/{fd}")
            if target.startswith("socket:["):
                inodes.add(target[8:-1])
    inet = set()
    for table in ("tcp", "tcp6", "udp", "udp6"):
        with contextlib.suppress(OSError), open(f"/proc/net/{table}") as f:
            inet |= {line.split()[9] for line in list(f)[1:]}
    return inodes & inet


@pytest.fixture
def sock_path(tmp_path):
    return tmp_path / "p.sock"


@pytest.fixture
def reaper():
    """Pids this test started; SIGKILLed at teardown if still there."""
    pids: list[int] = []
    yield pids
    for pid in pids:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)


def service(sock_path, tmp_path) -> ProjectorService:
    return ProjectorService(
        socket_path=sock_path,
        command=projector_command(sock_path, headless=True, extra=FAST),
        scenes=SCENES,
        heartbeat_s=0.1,
        peer_timeout_s=1.0,
        backoff_max_s=0.5,
        log_path=tmp_path / "projector.log",
    )


# --------------------------------------------------------------------------- protocol
def test_line_buffer_joins_split_lines_and_refuses_a_runaway_line():
    rx = LineBuffer(max_line_bytes=100)
    data = encode({"type": "state", "seq": 1}) + b"\n  \n" + encode({"type": "heartbeat"})
    lines = rx.feed(data[:7]) + rx.feed(data[7:])
    assert [json.loads(x)["type"] for x in lines] == ["state", "heartbeat"]
    with pytest.raises(ProtocolError, match="longer than 100"):
        rx.feed(b"x" * 200)  # a runaway line: the connection is dropped


def test_state_must_be_json_in_the_caller(sock_path):
    svc = ProjectorService(socket_path=sock_path, command=None, scenes=SCENES)
    with pytest.raises(ValueError):
        svc.link.send_state("x", {"v": float("nan")})
    svc.link.close()


def _fake_console(path):
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.connect(str(path))
    s.settimeout(5.0)
    return s, s.makefile("rb")


def test_projector_end_draws_newest_state_and_goes_black_when_the_console_leaves(sock_path):
    srv = LinkServer(sock_path, heartbeat_s=0.05, peer_timeout_s=3.0, initial={"kind": "alignment"})
    srv.start()
    try:
        assert srv.snapshot()[3] == {"kind": "alignment"}  # shown until a console comes
        s, f = _fake_console(sock_path)
        hello = json.loads(f.readline())
        assert hello["type"] == "hello" and hello["pid"] == os.getpid()
        s.sendall(
            encode({"type": "state", "seq": 1, "scene": "knob", "state": {"kind": "knob", "n": 1}})
        )
        s.sendall(
            encode({"type": "state", "seq": 2, "scene": "knob", "state": {"kind": "knob", "n": 2}})
        )
        wait_until(lambda: srv.snapshot()[1] == 2, 5, "state 2")
        assert srv.snapshot()[3] == {"kind": "knob", "n": 2}
        srv.frame_done(srv.snapshot()[0], time.monotonic())
        seen = []
        while not any(m["type"] == "drawn" for m in seen) and len(seen) < 50:
            seen.append(json.loads(f.readline()))
        acks = [m["seq"] for m in seen if m["type"] == "ack"]
        assert acks == [1, 2] and seen[-1]["seq"] == 2  # each state acked; the newest drawn
        # a malformed message: the connection is dropped and the projector shows black
        s.sendall(b'{"type": "state", "seq": "x", "state": {}}\n')
        wait_until(lambda: srv.snapshot()[3] is None, 5, "black after a bad message")
        assert srv.last_drop.startswith("protocol error") and f.read().endswith(b"\n")
        f.close()
        s.close()
        s, f = _fake_console(sock_path)  # the next console is served
        s.sendall(encode({"type": "state", "seq": 4, "scene": "grid", "state": {"kind": "grid"}}))
        wait_until(lambda: srv.snapshot()[1] == 4, 5, "state 4 from the next console")
        f.close()
        s.close()  # the console dies: EOF, noticed at once (well before the 3 s timeout)
        wait_until(lambda: srv.snapshot()[3] is None, 10, "black after EOF")
        # noticed from the socket (EOF or reset), not by waiting for the timeout
        assert not srv.last_drop.startswith("no word"), srv.last_drop
        # a console that goes silent (hung) is dropped after the timeout: black again
        s, f = _fake_console(sock_path)
        s.sendall(encode({"type": "state", "seq": 1, "scene": "grid", "state": {"kind": "grid"}}))
        wait_until(lambda: srv.snapshot()[3] == {"kind": "grid"}, 5, "grid state")
        wait_until(lambda: srv.snapshot()[3] is None, 10, "black after silence")
        assert srv.last_drop.startswith("no word from the console")
        s.close()
    finally:
        srv.close()
    assert not sock_path.exists()


def test_second_projector_on_a_live_socket_is_refused_and_a_stale_one_replaced(sock_path):
    srv = LinkServer(sock_path)
    try:
        with pytest.raises(UserError, match="already running"):
            LinkServer(sock_path)
    finally:
        srv.close()
    stale = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    stale.bind(str(sock_path))  # a socket file nobody listens on (a killed projector's)
    stale.close()
    assert sock_path.exists() and probe(sock_path) is None
    srv = LinkServer(sock_path)
    assert probe(sock_path) == os.getpid()
    srv.close()


# --------------------------------------------------------------------------- processes
@pytest.mark.usefixtures("requires_egl")
def test_projector_killed_with_sigkill_is_restarted_and_shows_the_scene_again(
    sock_path, tmp_path, reaper
):
    svc = service(sock_path, tmp_path)
    try:
        svc.start()
        reaper.append(svc.supervisor.pid)
        svc.start_scene("knob")
        assert svc.wait_drawn(20), (tmp_path / "projector.log").read_text()
        first = svc.supervisor.pid
        os.kill(first, signal.SIGKILL)
        wait_until(
            lambda: svc.supervisor.pid not in (None, first) and svc.link.connected,
            30,
            "a new projector",
        )
        reaper.append(svc.supervisor.pid)
        # the full state is re-sent after the reconnect: the new process draws the knob
        wait_until(lambda: svc.status()["shown_scene"] == "knob", 20, "knob shown again")
        st = svc.status()
        assert st["restarts"] == 1 and st["connected"] and st["last_exit"] == -signal.SIGKILL
        svc.update({"type": "rotate", "delta_deg": 45})
        assert svc.wait_drawn(20)
    finally:
        svc.close()
    assert not alive(reaper[-1])


@pytest.mark.usefixtures("requires_egl")
def test_hung_projector_is_detected_by_heartbeat_and_replaced(sock_path, tmp_path, reaper):
    svc = service(sock_path, tmp_path)
    try:
        svc.start()
        reaper.append(svc.supervisor.pid)
        svc.start_scene("grid", [{"type": "audition", "point": 51}])
        assert svc.wait_drawn(20)
        first = svc.supervisor.pid
        os.kill(first, signal.SIGSTOP)  # alive but silent
        wait_until(
            lambda: svc.supervisor.pid not in (None, first) and svc.link.connected,
            30,
            "replacement",
        )
        reaper.append(svc.supervisor.pid)
        wait_until(lambda: svc.status()["shown_scene"] == "grid", 20, "grid shown again")
        assert svc.status()["hangs"] >= 1 and "hung" in svc.status()["last_reason"]
        assert not alive(first)  # the hung one was killed, not left behind
    finally:
        svc.close()


CONSOLE = """
import sys, time
from console.runtime.projector.service import ProjectorService
from plugins.projector.launch import projector_command
from plugins.projector.scenes import BUILTIN_SCENES
sock, log = sys.argv[1], sys.argv[2]
svc = ProjectorService(socket_path=sock, command=projector_command(sock, headless=True, extra={fast!r}),
                       scenes={{n: c for n, (c, _) in BUILTIN_SCENES.items()}},
                       heartbeat_s=0.1, peer_timeout_s=1.0, log_path=log)
svc.start()
svc.start_scene("knob")
assert svc.wait_drawn(30)
print(svc.supervisor.pid, flush=True)
time.sleep(600)
"""


@pytest.mark.usefixtures("requires_egl")
def test_console_killed_with_sigkill_leaves_the_projector_black_and_a_new_console_adopts_it(
    sock_path, tmp_path, reaper
):
    console = subprocess.Popen(
        [
            sys.executable,
            "-c",
            CONSOLE.format(fast=FAST),
            str(sock_path),
            str(tmp_path / "projector.log"),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    reaper.append(console.pid)
    line = console.stdout.readline()
    assert line.strip().isdigit(), "the console did not get its projector drawing"
    projector = int(line)
    reaper.append(projector)
    console.kill()
    console.wait()
    # the projector lives on (own session) and turns black once its console is gone
    time.sleep(0.3)
    assert alive(projector)
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(5.0)
    wait_until(lambda: probe(sock_path) == projector, 10, "the projector answering")
    s.connect(str(sock_path))
    hello = json.loads(s.makefile("rb").readline())
    s.close()
    assert hello["pid"] == projector and hello["scene"] is None  # black
    # a new console adopts the running projector instead of starting a second one
    svc = service(sock_path, tmp_path)
    try:
        svc.start()
        assert svc.supervisor.adopted and svc.supervisor.pid == projector
        svc.start_scene("flow_hand")
        assert svc.wait_drawn(20)
        assert svc.status()["shown_scene"] == "flow_hand" and svc.status()["restarts"] == 0
    finally:
        svc.close()
    wait_until(lambda: not alive(projector), 10, "the projector to stop")
    assert not sock_path.exists()


@pytest.mark.usefixtures("requires_egl")
def test_stop_scene_shows_black_and_status_reports_the_link(sock_path, tmp_path, reaper):
    svc = service(sock_path, tmp_path)
    try:
        svc.start()
        reaper.append(svc.supervisor.pid)
        assert svc.wait_connected(20)
        svc.start_scene("contacts")
        assert svc.wait_drawn(20)
        svc.stop_scene()
        assert svc.wait_drawn(20)
        st = svc.status()
        assert st["shown_scene"] == "black" and st["scene"] is None
        assert st["connected"] and st["pid"] == st["projector_pid"]
        assert st["headless"] is True and st["size_px"] == [320, 200]
        assert st["unprepared_needs"] == []
        assert inet_sockets(st["pid"]) == set()  # the link is a Unix socket only
        with pytest.raises(UserError, match="available"):
            svc.start_scene("no-such-scene")
    finally:
        svc.close()


@pytest.mark.usefixtures("requires_egl")
def test_snapshot_saves_what_the_projector_shows(sock_path, tmp_path, reaper):
    import cv2

    svc = service(sock_path, tmp_path)
    try:
        svc.start()
        reaper.append(svc.supervisor.pid)
        svc.start_scene("knob")
        assert svc.wait_drawn(20)
        out = tmp_path / "shown.png"
        assert svc.snapshot(out, 20)
        img = cv2.imread(str(out))
        assert img.shape == (200, 320, 3)
        red = (img[..., 2] > 180) & (img[..., 1] < 90) & (img[..., 0] < 90)  # BGR
        assert red.sum() > 0  # the knob's target city
    finally:
        svc.close()


@pytest.mark.slow
def test_a_projector_that_cannot_start_is_retried_and_its_error_reported(sock_path, tmp_path):
    # a window on a display that does not exist: the process exits 2, again and again
    svc = ProjectorService(
        socket_path=sock_path,
        command=projector_command(sock_path, extra=["--screen", "0"]),
        scenes=SCENES,
        backoff_max_s=0.3,
        log_path=tmp_path / "projector.log",
        env={**os.environ, "DISPLAY": ":4242"},
    )
    try:
        svc.start()
        wait_until(lambda: svc.status()["restarts"] >= 2, 60, "two restarts")
        st = svc.status()
        assert not st["connected"] and st["last_exit"] == 2
        assert "cannot open a window" in st["last_error"]
    finally:
        svc.close()


@pytest.mark.usefixtures("requires_egl")
def test_show_command_starts_a_projector_shows_the_scene_and_stops_it(tmp_path, capsys):
    import cv2

    from plugins.projector.cli import main

    sock, png = tmp_path / "p.sock", tmp_path / "shown.png"
    argv = ["--show", "grid", "--event", '{"type": "audition", "point": 51}', "--headless"]
    argv += ["--size", "320x200", "--socket", str(sock), "--seconds", "0", "--snapshot", str(png)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "showing grid on projector pid" in out and "(started)" in out
    pid = int(out.split("pid ")[1].split()[0])
    img = cv2.imread(str(png))
    yellow = (img[..., 2] > 200) & (img[..., 1] > 190) & (img[..., 0] < 120)
    assert yellow.sum() > 20  # the auditioned point
    wait_until(lambda: not alive(pid), 10, "the projector to stop")
    assert not sock.exists()


def test_console_link_drops_a_malformed_projector_and_reconnects(sock_path):
    from console.runtime.projector.client import ProjectorLink

    lst = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    lst.bind(str(sock_path))
    lst.listen(1)
    lst.settimeout(10)
    link = ProjectorLink(sock_path, heartbeat_s=0.05, peer_timeout_s=5.0)
    link.start()
    try:
        seq = link.send_state("knob", {"kind": "knob"})
        for round_ in range(2):  # the second round: after the fake projector dropped us
            conn, _ = lst.accept()
            f = conn.makefile("rb")
            conn.sendall(encode({"type": "hello", "pid": os.getpid(), "scene": None}))
            msgs = [json.loads(f.readline())]
            while msgs[-1]["type"] != "state" and len(msgs) < 50:
                msgs.append(json.loads(f.readline()))
            state = msgs[-1]  # the full state is (re-)sent on every connect
            assert state["seq"] == seq and state["state"] == {"kind": "knob"}
            assert link.wait_connected(5)
            if round_ == 0:  # a malformed message: the console drops this projector
                conn.sendall(b'{"type": "ack", "seq": "x"}\n')
                wait_until(lambda: not link.connected, 5, "the drop")
                assert link.last_drop.startswith("protocol error")
                f.close()  # the file keeps the socket open too
                conn.close()
        conn.sendall(
            encode({"type": "drawn", "seq": seq, "t_drawn_s": time.monotonic(), "scene": "knob"})
        )
        assert link.wait_drawn(seq, 5)
        assert link.status()["shown_scene"] == "knob" and link.status()["connects"] == 2
        conn.close()
    finally:
        link.close()
        lst.close()


def test_a_probe_does_not_displace_the_console(sock_path):
    srv = LinkServer(sock_path, heartbeat_s=0.05, peer_timeout_s=5.0)
    srv.start()
    try:
        s, f = _fake_console(sock_path)
        s.sendall(encode({"type": "state", "seq": 1, "scene": "knob", "state": {"kind": "knob"}}))
        wait_until(lambda: srv.snapshot()[3] == {"kind": "knob"}, 5, "knob")
        assert probe(sock_path) == os.getpid()  # "is a projector running?" from elsewhere
        wait_until(lambda: srv.accepted == 2, 5, "the probe accepted")
        s.sendall(encode({"type": "heartbeat"}))
        assert srv.consoles == 1 and srv.snapshot()[3] == {"kind": "knob"}
        assert srv.connected and srv.last_drop == ""
        f.close()
        s.close()
    finally:
        srv.close()


def test_a_console_whose_loop_stops_ticking_turns_the_projector_black(sock_path):
    from console.runtime.projector.client import ProjectorLink

    srv = LinkServer(sock_path, heartbeat_s=0.05, peer_timeout_s=1.0)
    srv.start()
    stop = threading.Event()

    def render_loop():  # frames advance, so the projector end keeps its heartbeat
        while not stop.wait(0.02):
            srv.frame_done(srv.snapshot()[0], time.monotonic())

    threading.Thread(target=render_loop, daemon=True).start()
    link = ProjectorLink(sock_path, heartbeat_s=0.05, peer_timeout_s=1.0, require_tick=True)
    link.start()
    try:
        link.tick()
        link.send_state("knob", {"kind": "knob"})
        wait_until(lambda: srv.snapshot()[3] == {"kind": "knob"}, 10, "knob")
        for _ in range(30):  # the console loop runs: the projector keeps the scene
            link.tick()
            time.sleep(0.05)
        assert srv.snapshot()[3] == {"kind": "knob"}
        # the console's loop hangs (its I/O thread lives on): the projector goes black
        wait_until(lambda: srv.snapshot()[3] is None, 10, "black")
        assert srv.last_drop.startswith("no word from the console")
        time.sleep(1.5)  # and it stays black: the stuck console does not reconnect
        assert srv.snapshot()[3] is None and srv.consoles == 1
        # the loop recovers (ticks again): reconnect and show the scene again
        wait_until(lambda: link.tick() or srv.snapshot()[3] == {"kind": "knob"}, 10, "knob again")
        assert link.hangs == 0  # the projector never looked hung meanwhile
    finally:
        stop.set()
        link.close()
        srv.close()


def test_a_projector_whose_socket_is_gone_quits_instead_of_running_forever(sock_path):
    """Nobody can adopt a projector once its socket file is removed (its console's runtime
    directory deleted) or taken over by another: with no console connected it quits, and
    it never removes the socket that replaced its own."""
    srv = LinkServer(sock_path, heartbeat_s=0.05)
    srv.start()
    other = None
    try:
        time.sleep(2 * SOCKET_CHECK_S)
        assert not srv.quit_requested.is_set()  # reachable: it stays for a console to adopt
        sock_path.unlink()
        assert srv.quit_requested.wait(5 * SOCKET_CHECK_S)
        assert "no console can reach" in srv.orphaned
        other = LinkServer(sock_path, heartbeat_s=0.05)  # a new projector at the same path
        other_id = sock_path.stat().st_ino
    finally:
        srv.close()
    try:
        assert sock_path.exists() and sock_path.stat().st_ino == other_id
    finally:
        other.close()
    assert not sock_path.exists()

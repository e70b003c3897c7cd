"""Both ends of the projector link are built from one protocol module
(``console.runtime.projector.protocol``): the console's ``ProjectorLink`` talks to the
projector plugin's ``LinkServer`` over a temporary socket and every message type makes the
round trip; a line the protocol refuses is refused by both ends. No rendering: the test
plays the projector's render loop itself.
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from pathlib import Path

import pytest

from console.core.errors import UserError
from console.runtime.projector import protocol as proto
from console.runtime.projector.client import ProjectorLink
from console.runtime.projector.protocol import (
    TO_CONSOLE,
    TO_PROJECTOR,
    ProtocolError,
    decode,
    encode,
)
from plugins.projector.server import LinkServer

KNOB = {"kind": "knob", "angle_deg": 30.0}


def wait_until(cond, timeout_s=10.0, what="condition"):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if cond():
            return
        time.sleep(0.01)
    raise AssertionError(f"timed out waiting for {what}")


#: One message of every type each end sends, built by the protocol's constructors.
TO_PROJECTOR_MESSAGES = {
    "hello": proto.console_hello(),
    "state": {**proto.state_message(1, "knob", KNOB), "t_send_s": 1.5},
    "heartbeat": proto.console_heartbeat(2.0),
    "quit": proto.quit_message(),
    "snapshot": proto.snapshot_request("shown.png"),
}
TO_CONSOLE_MESSAGES = {
    "hello": proto.projector_hello("knob", {"size_px": [320, 200], "headless": True}),
    "ack": proto.ack(1, 1.25),
    "drawn": proto.drawn(1, 1.5, "knob"),
    "heartbeat": proto.projector_heartbeat(2.0, 59.987, 120, None),
    "snapshot_done": proto.snapshot_done("shown.png", Path("/tmp/shots/shown.png")),
    "error": proto.error("refused", "shown.png"),
}


@pytest.mark.parametrize(
    ("schema", "messages"),
    [(TO_PROJECTOR, TO_PROJECTOR_MESSAGES), (TO_CONSOLE, TO_CONSOLE_MESSAGES)],
    ids=["to_projector", "to_console"],
)
def test_every_message_type_has_a_constructor_whose_line_its_receiver_accepts(schema, messages):
    assert set(messages) == set(schema)  # a new type needs its constructor (and this test)
    for kind, msg in messages.items():
        assert msg["type"] == kind
        assert decode(encode(msg)[:-1], schema) == msg


@pytest.fixture
def sock_path(tmp_path):
    return tmp_path / "p.sock"


@pytest.fixture
def server(sock_path, tmp_path):
    srv = LinkServer(
        sock_path,
        heartbeat_s=0.05,
        peer_timeout_s=0.6,
        info={"size_px": [320, 200], "headless": True},
        snapshot_dir=tmp_path / "shots",
    )
    srv.start()
    yield srv
    srv.close()


@pytest.fixture
def render_loop(server):
    """The projector's render loop, played here: frames advance, snapshots are written."""
    stop = threading.Event()

    def run():
        while not stop.is_set():
            version = server.snapshot()[0]
            for request, target in server.take_snapshot_requests():
                if request.endswith("-2.png"):
                    server.snapshot_failed(request, "the renderer says no")
                else:
                    target.write_bytes(b"\x89PNG frame")
                    server.snapshot_done(request, target)
            server.frame_done(version, time.monotonic())
            time.sleep(0.01)

    t = threading.Thread(target=run, daemon=True)
    t.start()
    yield
    stop.set()
    t.join(2)


@pytest.fixture
def link(sock_path):
    link = ProjectorLink(sock_path, heartbeat_s=0.05, peer_timeout_s=0.6)
    link.start()
    yield link
    link.close()


def test_every_message_type_round_trips_between_the_console_and_the_projector(
    server, render_loop, link, tmp_path
):
    # hello both ways: the console is connected once the projector's hello is read, the
    # projector has a console once the console's hello arrives
    assert link.wait_connected(10)
    assert link.peer["role"] == "projector" and link.peer["size_px"] == [320, 200]
    assert link.peer["protocol"] == proto.PROTOCOL
    wait_until(lambda: server.connected, what="the projector sees its console")
    # state -> ack and drawn
    seq = link.send_state("knob", KNOB)
    assert link.wait_drawn(seq, 10)
    assert server.snapshot()[2:] == ("knob", KNOB)
    wait_until(lambda: link.acked_seq == seq, what="ack")
    assert link.latency_s and link.drawn_latency_s
    assert link.shown_scene == "knob"
    # heartbeats both ways keep both ends connected well past the peer timeout
    time.sleep(1.5)
    assert link.connected and server.connected
    assert link.fps > 0 and link.frames > 0 and link.hangs == 0
    assert server.consoles == 1 and server.protocol_errors == link.protocol_errors == 0
    # snapshot -> snapshot_done (the file is moved to the console's path) ...
    dest = tmp_path / "shown.png"
    assert link.snapshot(dest, 10)
    assert dest.read_bytes() == b"\x89PNG frame"
    # ... or -> error
    with pytest.raises(UserError, match="the renderer says no"):
        link.snapshot(tmp_path / "refused.png", 10)
    # quit
    link.send_quit()
    wait_until(server.quit_requested.is_set, what="quit")


#: Lines neither end accepts, whichever direction they travel.
BAD_LINES = {
    "not JSON": b'{"type": "heartbeat", ',
    "not an object": b"[1, 2]",
    "unknown type": b'{"type": "teleport"}',
    "another protocol": b'{"type": "hello", "role": "x", "pid": 1, "protocol": 2}',
    "non-finite number": b'{"type": "heartbeat", "t_s": NaN}',
    "too deep": b'{"type": "heartbeat", "x": ' + b"[" * 40 + b"]" * 40 + b"}",
    "not UTF-8": b'{"type": "heartbeat", "t_s": 1, "x": "\xff"}',
    "a field of the wrong type": b'{"type": "heartbeat", "t_s": "soon"}',
}


@pytest.mark.parametrize("line", BAD_LINES.values(), ids=BAD_LINES.keys())
def test_a_line_the_protocol_refuses_is_refused_by_the_projector(server, sock_path, line):
    for schema in (TO_PROJECTOR, TO_CONSOLE):
        with pytest.raises(ProtocolError):
            decode(line, schema)
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(5)
    s.connect(str(sock_path))
    try:
        s.sendall(encode(proto.console_hello()) + encode(proto.state_message(1, "knob", KNOB)))
        wait_until(lambda: server.snapshot()[3] == KNOB, what="the knob shown")
        s.sendall(line + b"\n")
        wait_until(lambda: server.protocol_errors == 1, what="the projector refuses it")
        assert server.snapshot()[3] is None  # black
        assert not server.connected
    finally:
        s.close()


@pytest.mark.parametrize("line", BAD_LINES.values(), ids=BAD_LINES.keys())
def test_a_line_the_protocol_refuses_is_refused_by_the_console(sock_path, line):
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(str(sock_path))
    listener.listen(1)
    listener.settimeout(10)
    link = ProjectorLink(sock_path, heartbeat_s=0.05, peer_timeout_s=5.0)
    link.start()
    try:
        conn, _ = listener.accept()
        with contextlib.closing(conn):
            conn.sendall(encode(proto.projector_hello(None, {})))
            assert link.wait_connected(10)
            conn.sendall(line + b"\n")
            wait_until(lambda: link.protocol_errors == 1, what="the console refuses it")
            assert "protocol error from the projector" in link.last_drop
    finally:
        link.close()
        listener.close()


def test_the_console_refuses_to_send_a_state_the_projector_would_refuse(server, sock_path):
    bad = {"kind": 5}  # a scene named by a number
    link = ProjectorLink(sock_path)  # not started: refused before anything is sent
    with pytest.raises(UserError, match="would refuse"):
        link.send_state(None, bad)
    with pytest.raises(ValueError):
        link.send_state("knob", {"x": float("nan")})
    link.close()
    # the projector refuses the same state when a client sends it anyway
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.settimeout(5)
    s.connect(str(sock_path))
    with contextlib.closing(s):
        s.sendall(encode(proto.state_message(1, None, bad)))
        wait_until(lambda: server.protocol_errors == 1, what="the projector refuses it")

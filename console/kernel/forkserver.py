"""A starter of table kernels with their libraries already imported (a fork server).

A table's kernel (``console.kernel.server``) imports NumPy, the profile's sections and the
kernel's plugins before it answers ``ready``: ~0.4 s of CPU per start. A process that
starts a second kernel (a bench, a console switching tables, the test suite's hundreds of
private tables) gets one of these: ``python -m console.kernel.forkserver``, started once,
imports them single-threaded and forks a kernel per request. The child is what
``python -m console.kernel`` would be: a session of its own, stdin ``/dev/null``, stdout
the start line's pipe, stderr the table's ``kernel.log``, the client's environment and
working directory as they are at the request, no other descriptor; then ``server.main``
with the start request.

The server listens only on the socket pair its client made (no path another process can
reach) and ends when its client closes it or dies. The kernels it forked outlive it (each
in its own session); those that end while it runs are reaped at once. Its client falls
back to a fresh interpreter whenever it cannot start or answer (``console.kernel.spawn``).
"""

from __future__ import annotations

import contextlib
import os
import pickle
import signal
import socket
import struct
import sys

#: the length prefix of a request (and of nothing else: the answer is a pid line)
_HEAD = struct.Struct("!I")
#: the descriptors a request carries: the start line's pipe, the table's kernel.log
FDS = 2


def send_request(sock: socket.socket, message: dict, fds: tuple[int, int]) -> None:
    """``message`` (pickled) and the two descriptors, over the client's socket."""
    data = pickle.dumps(message)
    socket.send_fds(sock, [_HEAD.pack(len(data))], list(fds))
    sock.sendall(data)


def _recv_exact(sock: socket.socket, n: int) -> bytes:
    buf = b""
    while len(buf) < n:
        chunk = sock.recv(n - len(buf))
        if not chunk:
            raise EOFError
        buf += chunk
    return buf


def _recv_request(sock: socket.socket) -> tuple[dict, list[int]]:
    head, fds, _flags, _addr = socket.recv_fds(sock, _HEAD.size, FDS)
    if not head:
        raise EOFError
    head += _recv_exact(sock, _HEAD.size - len(head))
    (n,) = _HEAD.unpack(head)
    return pickle.loads(_recv_exact(sock, n)), fds


def _preload() -> None:
    """What every kernel imports before it is ready (``server.main``, ``Kernel.start``)."""
    # lazy: the server imports these once, after it started (its client's process not)
    import console.kernel.server  # noqa: F401
    import console.kernel.table  # noqa: F401
    import console.safety  # noqa: F401
    from console.config.plugins import BUILTIN_PLUGINS, KERNEL_BUILTINS, load_plugins

    load_plugins(builtins={n: BUILTIN_PLUGINS[n] for n in KERNEL_BUILTINS})


def _reap(signum: int, frame: object) -> None:
    """A kernel that ended is reaped at once (a zombie would look alive to its table's
    next kernel, which latches a predecessor that died)."""
    while True:
        try:
            pid, _status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return


def _open_fds() -> list[int]:
    try:
        return [int(n) for n in os.listdir("/proc/self/fd")]
    except OSError:
        return list(range(3, 256))


def _name(name: str) -> None:
    """This process's name as ``ps`` and ``top`` show it (Linux; elsewhere unchanged)."""
    with contextlib.suppress(OSError), open("/proc/self/comm", "w") as f:
        f.write(name)


def _child(message: dict, fds: list[int]) -> int:
    """In the forked child: become ``python -m console.kernel`` and run it."""
    _name("haptable-kernel")
    signal.signal(signal.SIGCHLD, signal.SIG_DFL)
    os.setsid()  # its terminal's signals are not an e-stop
    out_fd, log_fd = fds
    null = os.open(os.devnull, os.O_RDONLY)
    os.dup2(null, 0)
    os.dup2(out_fd, 1)
    os.dup2(log_fd, 2)
    for fd in _open_fds():  # the client's socket, the passed originals, /dev/null
        if fd > 2:
            with contextlib.suppress(OSError):
                os.close(fd)
    os.chdir(message["cwd"])
    os.environ.clear()
    os.environ.update(message["env"])
    import numpy as np

    np.random.seed()  # NumPy's global generator: this kernel's own, not the server's copy
    # lazy: preloaded by the server (a module import here is a dictionary lookup)
    from console.kernel.server import main

    return main(message["request"])


def serve(sock: socket.socket) -> int:
    """Preload, say ``ok``, then fork a kernel per request until the client is gone."""
    _name("haptable-forks")
    _preload()
    signal.signal(signal.SIGCHLD, _reap)
    sock.sendall(b"ok\n")
    while True:
        try:
            message, fds = _recv_request(sock)
        except (EOFError, OSError):
            return 0
        if len(fds) != FDS:
            for fd in fds:
                os.close(fd)
            return 2
        pid = os.fork()
        if pid == 0:
            code = 3
            try:
                code = _child(message, fds)
            finally:
                sys.stderr.flush()
                os._exit(code)
        for fd in fds:
            os.close(fd)
        try:
            sock.sendall(f"{pid}\n".encode())
        except OSError:
            return 0


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # its client's terminal: not its business
    code = serve(socket.socket(fileno=int(sys.argv[1])))
    os._exit(code)

"""A table's identity and its files in the private runtime directory, and its latch.

A table is a profile file: its key is ``<name>-<sha1 of the file's path>[:10]``, the same
for every process that loads that file. Its kernel keeps its files in
``runtime_dir()/tables/<key>/``:

=================  =================================================================
``kernel.lock``    held (flock) by the kernel process while it runs: one per table
``kernel.json``    the running kernel: pid, profile, when it started
``kernel.sock``    clients' connections (framed messages: ``console.kernel.wire``)
``control.sock``   one-line commands: ``ping``, ``status``, ``estop``, ``reset``
``estop.json``     the latched e-stop: while it exists nothing plays on this table; its
                   first e-stop (the cause) and the later ones (``later``, ``count``)
``console.lock``   held by the table's console (its reset key is an operator's)
=================  =================================================================

A *private* table (``runtime_dir()/private/<key>/``) is a twin of one process's own (the
bench's safety fuzz, tests): a bare `haptable estop` never reaches it and its owner may
reset it; it never drives hardware. A private twin that plays a command *on* a shared
table (``haptable study run --simulate``: ``private_table(of=table)``, its ``twin-of``
file naming the table, written before its kernel starts) is stopped by that table's
e-stop as the table's own kernel is: its kernel reads the table's latch too when it
opens, and `haptable estop` and the table's kernel e-stop it (``twins_of``) after
latching the table. The operator's e-stop always wins; only its owner resets the twin.

The latch is written before the kernel's e-stop returns and read by a kernel before it
opens anything, so an e-stop sent while no kernel runs is remembered: `haptable estop`
writes the latch first and then looks for kernels; a kernel binds its control socket
first and then reads the latch. Whatever the order, one of them sees the other.
Standard library only.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from console.kernel.private_dir import (
    ensure_private_dir,
    open_private,
    runtime_dir,
    write_private,
)

#: a latch record is a few lines; anything larger is not ours
MAX_LATCH_BYTES = 16 * 1024
#: the e-stops a latch keeps after its first (the newest; ``count`` says how many came)
MAX_LATER = 12
#: a private twin's file naming the shared table it plays on (``private_table(of=)``)
TWIN_OF = "twin-of"


def table_key(profile_path: str | os.PathLike) -> str:
    """The key of the table a profile file describes (its resolved path's hash)."""
    p = Path(profile_path)
    with contextlib.suppress(OSError):
        p = p.resolve()
    stem = "".join(c if c.isalnum() or c in "-_." else "_" for c in p.stem)[:40] or "table"
    return f"{stem}-{hashlib.sha1(str(p).encode()).hexdigest()[:10]}"


@dataclass(frozen=True)
class Table:
    """Where one table's kernel keeps its files (``dir``); ``private``: a twin of one
    process; ``of``: the key of the shared table such a twin plays on (see the module's
    doc)."""

    key: str
    dir: Path
    private: bool = False
    of: str = ""

    @property
    def kernel_sock(self) -> Path:
        return self.dir / "kernel.sock"

    @property
    def control_sock(self) -> Path:
        return self.dir / "control.sock"

    @property
    def lock_path(self) -> Path:
        return self.dir / "kernel.lock"

    @property
    def info_path(self) -> Path:
        return self.dir / "kernel.json"

    @property
    def latch_path(self) -> Path:
        return self.dir / "estop.json"

    @property
    def console_lock(self) -> Path:
        return self.dir / "console.lock"

    @property
    def name(self) -> str:
        """The profile's name as the key starts with it (a twin on a table: the table's)."""
        return (self.of or self.key).rsplit("-", 1)[0]

    @property
    def shared(self) -> Table | None:
        """The shared table a private twin plays on (None: it plays on none)."""
        return Table(self.of, tables_root() / self.of) if self.of else None

    def ensure(self) -> Table:
        """Create the directory (0700, checked like the runtime directory)."""
        ensure_private_dir(self.dir)
        return self

    def info(self) -> dict[str, Any]:
        """What the running kernel wrote of itself ({} when none or unreadable)."""
        return _read_json(self.info_path) or {}


def tables_root() -> Path:
    return ensure_private_dir(runtime_dir() / "tables")


def table_for(profile_path: str | os.PathLike) -> Table:
    """The shared table of the profile file ``profile_path``."""
    key = table_key(profile_path)
    return Table(key, tables_root() / key)


_private_seq = 0


def private_table(label: str = "twin", of: Table | None = None) -> Table:
    """A new private twin table of this process; ``of``: the shared table it plays on,
    whose e-stop stops it (see the module's doc)."""
    global _private_seq
    _private_seq += 1
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in label)[:20]
    key = f"{safe}-{os.getpid()}-{_private_seq}"
    root = ensure_private_dir(runtime_dir() / "private")
    table = Table(key, root / key, private=True, of=of.key if of is not None else "")
    if of is not None:  # before its kernel binds its control socket: an e-stop finds it
        write_private(table.ensure().dir / TWIN_OF, of.key)
    return table


def table_at(directory: str | os.PathLike) -> Table:
    """The table whose files are in ``directory`` (a demo process joins its console's)."""
    d = Path(directory)
    private = d.parent.name == "private"
    return Table(d.name, d, private=private, of=_twin_of(d) if private else "")


def twins_of(table: Table) -> list[Table]:
    """The private twins playing on the shared ``table`` whose kernel has a control
    socket (alive or stale): its e-stop e-stops them too."""
    if table.private:
        return []
    try:
        dirs = sorted((runtime_dir() / "private").iterdir())
    except OSError:
        return []
    return [
        Table(d.name, d, private=True, of=table.key)
        for d in dirs
        if (d / "control.sock").exists() and _twin_of(d) == table.key
    ]


def _twin_of(d: Path) -> str:
    """The key a private twin's ``twin-of`` file names ("" when none or not ours)."""
    raw = _read_text(d / TWIN_OF)
    ok = raw and len(raw) <= 200 and all(c.isalnum() or c in "-_." for c in raw)
    return raw if ok else ""


def running_tables() -> list[Table]:
    """The shared tables whose kernel has a control socket (alive or stale)."""
    root = tables_root()
    return sorted(
        (Table(d.name, d) for d in root.iterdir() if (d / "control.sock").exists()),
        key=lambda t: t.key,
    )


def known_tables(profile_paths: list[Path]) -> list[Table]:
    """Every shared table a bare `haptable estop` latches: each one that ever ran since
    the runtime directory was made, and the tables of ``profile_paths``."""
    root = tables_root()
    found = {d.name: Table(d.name, d) for d in root.iterdir() if d.is_dir()}
    for p in profile_paths:
        key = table_key(p)
        found.setdefault(key, Table(key, root / key))
    return sorted(found.values(), key=lambda t: t.key)


# ---------------------------------------------------------------------- the latch
def latch_record(reason: str, by: str, pid: int | None = None) -> dict[str, Any]:
    """What a latch says: why, who, which process, when."""
    now = time.time()
    return {
        "reason": str(reason)[:300],
        "by": str(by)[:200],
        "pid": int(os.getpid() if pid is None else pid),
        "t": now,
        "time": time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(now)),
    }


def latch_entries(rec: dict[str, Any]) -> list[dict[str, Any]]:
    """The e-stops a latch records, the first (the cause) first, then the later ones
    kept, oldest first. A latch file of one record (as written before later e-stops were
    kept) is its first alone."""
    later = rec.get("later")
    kept = [e for e in later if _is_record(e)] if isinstance(later, list) else []
    return [rec, *kept]


def latch_count(rec: dict[str, Any]) -> int:
    """How many e-stops latched the table, those not kept included."""
    n = rec.get("count")
    kept = len(latch_entries(rec))
    return max(n, kept) if isinstance(n, int) and not isinstance(n, bool) else kept


def describe_latch(rec: dict[str, Any]) -> str:
    """One line: ``haptable estop (pid 12) at 2026-11-27 10:00:01``; several e-stops:
    ``2 e-stops: haptable estop (pid 12) at ...; haptable estop (pid 13) at ...``, those
    not kept counted after the first."""
    entries = latch_entries(rec)
    n = latch_count(rec)
    if n == 1:
        return _one(rec)
    said = [_one(entries[0])]
    if n > len(entries):
        said.append(f"({n - len(entries)} not kept)")
    said += [_one(e) for e in entries[1:]]
    return f"{n} e-stops: " + "; ".join(said)


def _one(rec: dict[str, Any]) -> str:
    why = str(rec.get("reason") or "e-stop")
    when = rec.get("time") or "?"
    return f"{why} at {when}"


def _is_record(e: Any) -> bool:
    return isinstance(e, dict) and isinstance(e.get("reason"), str)


def read_latch(table: Table) -> dict[str, Any] | None:
    """The table's latched e-stop, or None. A latch file that cannot be read as ours is
    still a latch (fail safe): its record says so."""
    return _load_latch(table)[0]


def _load_latch(table: Table) -> tuple[dict[str, Any] | None, bool]:
    """(the latch as ``read_latch`` says it, whether its file is ours as written)."""
    p = table.latch_path
    try:
        os.lstat(p)
    except FileNotFoundError:
        return None, False
    except OSError as exc:
        return {"reason": f"latch file unreadable ({exc.strerror})", "by": "?", "time": "?"}, False
    rec = _read_json(p)
    if not _is_record(rec):
        return {"reason": f"latch file {p} unreadable", "by": "?", "time": "?"}, False
    return rec, True


def latched_elsewhere(own: Table) -> list[str]:
    """The names of the other shared tables latched now (a bare `haptable estop`
    latches every table: the console shows those it cannot reset itself, each reset
    from its own console's ctrl+r or `haptable reset`). Reads only; [] for a private
    table (no shell e-stop reaches it)."""
    out: list[str] = []
    for t in latched_others(own):
        if t.name not in out:
            out.append(t.name)
    return out


def latched_others(own: Table) -> list[Table]:
    """The other shared tables latched now (``latched_elsewhere``'s tables)."""
    if own.private:
        return []
    try:
        dirs = sorted(d for d in tables_root().iterdir() if d.name != own.key and d.is_dir())
    except OSError:
        return []
    tables = [Table(d.name, d) for d in dirs]
    return [t for t in tables if read_latch(t) is not None]


def write_latch(table: Table, record: dict[str, Any]) -> None:
    """Latch the table (atomically, synced): kept until ``clear_latch``. When it is
    latched already the first e-stop stays the cause (its reason is the one an operator
    reads first) and this one is added after it (``later``: the newest ``MAX_LATER``,
    ``count``: all of them), unless an e-stop of the same reason is there (one e-stop
    reaches a table on several paths: the shell's latch, its kernel's, the gate's event).
    A latch file that is not ours as written stays as it is: it latches."""
    table.ensure()
    with _latch_lock(table.dir):
        current, ours = _load_latch(table)
        if current is None:
            data = record
        elif not ours:
            return
        else:
            data = _added(current, record)
            if data is None:
                return
        tmp = table.dir / f".estop-{os.getpid()}-{time.monotonic_ns()}.tmp"
        fd = open_private(tmp)
        try:
            os.write(fd, json.dumps(data).encode())
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, table.latch_path)
        _sync_dir(table.dir)


def _added(current: dict[str, Any], record: dict[str, Any]) -> dict[str, Any] | None:
    """``current`` with ``record`` after its e-stops, within ``MAX_LATER`` and the file's
    bound (the oldest later ones give way; the count keeps them); None: already there."""
    entries = latch_entries(current)
    if any(e.get("reason") == record.get("reason") for e in entries):
        return None
    later = [*entries[1:], record][-MAX_LATER:]
    data = {**current, "later": later, "count": latch_count(current) + 1}
    while len(json.dumps(data).encode()) > MAX_LATCH_BYTES and len(data["later"]) > 1:
        data["later"] = data["later"][1:]
    return data


@contextlib.contextmanager
def _latch_lock(d: Path, wait_s: float = 0.5) -> Iterator[None]:
    """Two e-stops at once add both (an flock on the table's directory). Never holds an
    e-stop back: not had within ``wait_s`` (its holder stopped), the latch is written
    anyway (at worst the other's record is not kept; the table is latched)."""
    import fcntl

    try:
        fd = os.open(d, os.O_RDONLY | os.O_DIRECTORY)
    except OSError:
        yield
        return
    try:
        t_end = time.monotonic() + wait_s
        while True:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > t_end:
                    break
                time.sleep(0.002)
            except OSError:
                break
        yield
    finally:
        os.close(fd)  # releases the lock


def clear_latch(table: Table) -> dict[str, Any] | None:
    """Remove the latch; what it said (None: there was none): every e-stop it removed,
    an e-stop latching at the same moment either in it or latching after it."""
    with _latch_lock(table.dir):
        rec = read_latch(table)
        with contextlib.suppress(FileNotFoundError):
            os.unlink(table.latch_path)
            _sync_dir(table.dir)
    return rec


def _read_text(p: Path) -> str:
    """A small file's text ("" when none or not ours)."""
    raw = _read_raw(p)
    try:
        return raw.decode("utf-8").strip() if raw is not None else ""
    except UnicodeDecodeError:
        return ""


def _read_json(p: Path) -> Any:
    raw = _read_raw(p)
    if raw is None:
        return None
    try:
        return json.loads(raw.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        return None


def _read_raw(p: Path) -> bytes | None:
    """A small regular file's bytes, never through a symlink (None: none, or too big)."""
    try:
        fd = os.open(p, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError:
        return None
    try:
        import stat

        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return None
        raw = os.read(fd, MAX_LATCH_BYTES + 1)
    except OSError:
        return None
    finally:
        os.close(fd)
    return None if len(raw) > MAX_LATCH_BYTES else raw


def _sync_dir(d: Path) -> None:
    with contextlib.suppress(OSError):
        fd = os.open(d, os.O_RDONLY | os.O_DIRECTORY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)

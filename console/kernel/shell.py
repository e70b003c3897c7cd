"""`haptable estop` and `haptable reset`, with the standard library only.

``haptable estop`` latches the e-stop of every table it names first (``--profile``: that
one; none: every table that ran since the runtime directory was made and every profile
found by name), then e-stops each running kernel at once (its control socket: ``estop``),
the private twins playing on those tables among them (``twins_of``), each with the same
deadline, and prints one line per table, then one per table latched with the command
that resets it (``reset_command``). A table whose kernel is not
running stays latched: the next command that opens it refuses, the console opens into
the e-stop. No numpy, no plugins, no profile parsing on this path: it must be instant.

``haptable reset`` is an operator's: typed at a terminal (this process in the foreground
of its controlling terminal), it clears the latch of the named table (none named: every
latched one) through its kernel when one runs (which checks the same of its peer), or
its latch file when none does, and says who reset what and when.

Exit status: 0 done, 1 an e-stop not confirmed (or a reset refused), 2 bad input.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import shlex
import sys
import threading
import time

from console.core.errors import UserError
from console.core.suggest import suggestion
from console.files.profile_paths import find_profile, known_profiles
from console.kernel.line_server import PeerRefused, request
from console.kernel.operator import WHO_MAY_RESET
from console.kernel.tables import (
    Table,
    clear_latch,
    describe_latch,
    known_tables,
    latch_record,
    read_latch,
    table_for,
    table_key,
    twins_of,
    write_latch,
)


@dataclasses.dataclass(frozen=True)
class Reached:
    """What one table's kernel answered to the e-stop."""

    table: str
    pid: int
    confirmed: bool
    why: str
    clients: tuple[str, ...] = ()
    server_ms: float | None = None
    stale: bool = False  # no kernel answered on its socket (it ended)

    def line(self) -> str:
        if self.stale:
            return f"table {self.table}: no outputs process answers (it ended); latched"
        who = f"table {self.table}"
        if self.pid > 0:
            who += f" (outputs pid {self.pid}"
            if self.clients:
                who += "; used by " + ", ".join(self.clients)
            who += ")"
        return f"{who}: " + ("confirmed " if self.confirmed else "NOT confirmed: ") + self.why


def whoami() -> str:
    """``haptable estop (pid 12, alice on /dev/pts/3)``-style, for the latch's reason."""
    user = os.environ.get("USER") or os.environ.get("LOGNAME")
    if not user:
        import pwd

        try:
            user = pwd.getpwuid(os.getuid()).pw_name
        except KeyError:
            user = str(os.getuid())
    try:
        tty = os.ttyname(0)
    except OSError:
        tty = "no terminal"
    return f"pid {os.getpid()}, {user} on {tty}"


def _reach(table: Table, reason: str, timeout_s: float) -> Reached | None:
    sock = table.control_sock
    if not sock.exists():
        return None
    if table.of:  # a private twin playing on it (a simulated study run)
        return dataclasses.replace(
            _reach_kernel(table, reason, timeout_s), table=f"{table.name}'s twin"
        )
    return _reach_kernel(table, reason, timeout_s)


def _reach_kernel(table: Table, reason: str, timeout_s: float) -> Reached:
    sock = table.control_sock
    try:
        reply, pid = request(sock, f"estop {reason}"[:250], timeout_s=timeout_s)
    except (ConnectionRefusedError, FileNotFoundError):
        return Reached(table.name, -1, True, "", stale=True)
    except PeerRefused as exc:
        return Reached(table.name, -1, False, f"refused: {exc}")
    except TimeoutError as exc:
        return Reached(table.name, -1, False, str(exc))
    except OSError as exc:
        return Reached(table.name, -1, False, f"{type(exc).__name__}: {exc.strerror or exc}")
    try:
        data = json.loads(reply)
        ms = data.get("ms")
        return Reached(
            table.name,
            int(data.get("pid", pid)),
            data["confirmed"] is True,
            str(data["why"]),
            tuple(str(c) for c in data.get("clients", []))[:20],
            float(ms) if isinstance(ms, (int, float)) else None,
        )
    except (ValueError, KeyError, TypeError):
        return Reached(table.name, pid, False, f"unexpected answer {reply[:80]!r}")


def _tables(profile_arg: str | None) -> list[Table]:
    if profile_arg:
        return [table_for(find_profile(profile_arg))]
    paths = list(known_profiles().values())
    with contextlib.suppress(UserError):
        paths.append(find_profile(None))
    return known_tables(paths)


def estop(
    profile_arg: str | None, timeout_s: float, who: str = "haptable estop"
) -> tuple[list[Reached], list[Table]]:
    """Latch, then e-stop every running kernel at once: what each answered, and every
    table latched. ``who`` names what asked (a console without outputs gives its own
    words: ``operator e-stop (console)``), the process and terminal added."""
    tables = _tables(profile_arg)
    reason = f"{who} ({whoami()})"
    record = latch_record(reason, who)
    for t in tables:  # first: a kernel starting now reads it (console.kernel.tables)
        write_latch(t, record)
    results: dict[str, Reached | None] = {}

    def one(t: Table) -> None:
        results[t.key] = _reach(t, reason, timeout_s)

    kernels = [*tables, *(w for t in tables for w in twins_of(t))]  # after the latches
    threads = [threading.Thread(target=one, args=(t,), daemon=True) for t in kernels]
    for th in threads:
        th.start()
    t_end = time.monotonic() + timeout_s + 0.5
    for th in threads:
        th.join(max(0.0, t_end - time.monotonic()))
    reached = []
    for t in kernels:
        if t.key not in results and t.control_sock.exists():
            reached.append(Reached(t.name, -1, False, f"no answer within {timeout_s:g} s"))
        elif results.get(t.key) is not None:
            reached.append(results[t.key])
    return reached, tables


def reset_command(table: Table, profile_arg: str | None) -> str:
    """The command typed at a terminal that resets ``table``'s latch: ``haptable
    --profile sim-4ch reset`` (by name when its name finds its file, else by the file its
    kernel runs from); ``haptable reset`` (every latched table) when neither is known."""
    if profile_arg:
        return f"haptable --profile {shlex.quote(profile_arg)} reset"
    by_name = known_profiles().get(table.name)
    if by_name is not None and table_key(by_name) == table.key:
        return f"haptable --profile {shlex.quote(table.name)} reset"
    path = table.info().get("profile_path")
    if isinstance(path, str) and path and table_key(path) == table.key:
        return f"haptable --profile {shlex.quote(path)} reset"
    return "haptable reset"


def at_terminal_here() -> bool:
    """This process runs in the foreground of its controlling terminal."""
    try:
        return os.isatty(0) and os.tcgetpgrp(0) == os.getpgrp()
    except OSError:
        return False


def reset(profile_arg: str | None, timeout_s: float) -> tuple[list[str], bool]:
    """Reset the named table's latch (none named: every latched one); one line each and
    whether all of them were reset."""
    if not at_terminal_here():
        return [f"refused: {WHO_MAY_RESET} (this process has no terminal in the foreground)"], False
    tables = _tables(profile_arg)
    who = f"haptable reset ({whoami()})"
    lines, ok = [], True
    for t in tables:
        latched = read_latch(t)
        if t.control_sock.exists():
            try:
                reply, _ = request(t.control_sock, f"reset {who}"[:250], timeout_s=timeout_s)
            except (ConnectionRefusedError, FileNotFoundError):
                reply = None  # its kernel ended: the file is all there is
            except (PeerRefused, TimeoutError, OSError) as exc:
                lines.append(f"table {t.name}: not reset: {exc}")
                ok = False
                continue
            if reply is not None:
                if reply.startswith("ok: not e-stopped"):
                    if profile_arg:
                        lines.append(f"table {t.name}: not e-stopped")
                    continue
                good = reply.startswith("ok")
                ok = ok and good
                lines.append(f"table {t.name}: {reply[4:] if good else reply}")
                continue
        if latched is None:
            if profile_arg:
                lines.append(f"table {t.name}: not e-stopped")
            continue
        latched = clear_latch(t) or latched  # every e-stop it removed
        lines.append(
            f"table {t.name}: e-stop reset by {who} at {time.strftime('%H:%M:%S')} "
            f"(was: {describe_latch(latched)})"
        )
    if not lines:
        lines.append("no table is e-stopped")
    return lines, ok


def _args(argv: list[str]) -> tuple[str, str | None, bool, float]:
    """``(command, profile, json, timeout)`` from ``[--profile P] estop|reset [--json]
    [--timeout S]``; ``UserError`` for anything else."""
    command, profile, as_json, timeout = "", None, False, 2.0
    it = iter(argv)
    for a in it:
        if a in ("-p", "--profile") or a.startswith("--profile="):
            profile = a.split("=", 1)[1] if "=" in a else next(it, None)
            if not profile:
                raise UserError("--profile needs a profile name or path")
        elif a == "--json":
            as_json = True
        elif a == "--timeout" or a.startswith("--timeout="):
            raw = a.split("=", 1)[1] if "=" in a else next(it, "")
            try:
                timeout = float(raw)
            except ValueError:
                raise UserError(f"--timeout {raw!r}: give seconds from 0.01 to 60") from None
            if not 0.01 <= timeout <= 60:
                raise UserError(f"--timeout {raw}: give seconds from 0.01 to 60")
        elif a in ("-v", "--verbose"):
            continue
        elif a in ("estop", "reset") and not command:
            command = a
        else:
            known = ["--profile", "--json", "--timeout", "--verbose", "estop", "reset"]
            hint = suggestion(a.split("=")[0], known, "; did you mean {!r}?")
            raise UserError(
                f"haptable {command or 'estop'}: unknown argument {a!r}{hint} "
                f"(see `haptable {command or 'estop'} --help`)"
            )
    return command, profile, as_json, timeout


HELP = """usage: haptable [--profile P] estop [--json] [--timeout S]
       haptable [--profile P] reset

estop: silence every output and open every relay now, and latch the e-stop: nothing
plays on a table until an operator resets it. Without --profile every table is latched;
each table latched is named with the command that resets it.
reset: an operator's, typed at a terminal: clear the latched e-stop of the table
(without --profile: of every latched table), saying who, when and every e-stop cleared.
"""


def main(argv: list[str]) -> int:
    """`haptable estop` / `haptable reset` (see the module's doc)."""
    if "-h" in argv or "--help" in argv:
        print(HELP, end="")
        return 0
    try:
        command, profile, as_json, timeout = _args(argv)
        if command == "reset":
            lines, ok = reset(profile, timeout)
            for ln in lines:
                print(f"reset: {ln}")
            return 0 if ok else 1
        reached, tables = estop(profile, timeout)
    except UserError as exc:
        if "estop" in argv:  # a mistyped profile or option: every table stops first
            return _estop_every_table(exc)
        print(f"haptable: error: {exc}", file=sys.stderr)
        return 2
    live = [r for r in reached if not r.stale]
    unconfirmed = [r for r in live if not r.confirmed]
    resets = {t.key: reset_command(t, profile) for t in tables}
    if as_json:
        print(
            json.dumps(
                {
                    "tables": [dataclasses.asdict(r) for r in reached],
                    "confirmed": not unconfirmed,
                    "latched": [t.key for t in tables],
                    "reset": resets,
                }
            )
        )
    else:
        _say_estopped(reached, tables, resets)
        if len(tables) > 1:
            print(
                "e-stop: ctrl+r in a table's console resets that table only; "
                "`haptable reset` resets every one"
            )
    return 1 if unconfirmed else 0


def _say_estopped(reached: list[Reached], tables: list[Table], resets: dict) -> None:
    """What each table answered, and each one latched with what resets it."""
    for r in reached:
        print(f"e-stop: {r.line()}")
    if not [r for r in reached if not r.stale]:
        print("e-stop: no outputs open")
    for t in tables:  # each latched: what an operator types to reset it
        print(f"e-stop: table {t.name} latched until an operator resets it: `{resets[t.key]}`")


def _estop_every_table(why: UserError) -> int:
    """``haptable estop`` typed with a mistake (a profile that is not found, an option
    it does not take): every table is e-stopped and latched as without ``--profile``,
    then the mistake is said; exit 2."""
    reached, tables = estop(None, 2.0)
    _say_estopped(reached, tables, {t.key: reset_command(t, None) for t in tables})
    print(
        f"haptable: error: {' '.join(str(why).split())}; every table was e-stopped instead "
        "(`haptable reset` resets them)",
        file=sys.stderr,
    )
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

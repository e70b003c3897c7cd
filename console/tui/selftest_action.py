"""The Devices screen's self-test (key s): the ``selftest`` command a plugin registers
(``plugins.vibrotactile.cli.selftest``), run in the screen's worker thread, its lines back.

The console knows the command by its registered name only: it runs it with ``--json``
(the operator's outputs through the gate, like ``haptable selftest``) and reads the
report. Without a plugin offering it, it says so.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
from types import SimpleNamespace
from typing import Any

from console.core.errors import EStopLatched, SafetyRefusal, UserError
from console.core.types import DeviceStatus
from console.session.events import ESTOP_FIX, estop_refusal
from console.tui.time_left import left_words

NO_PLUGIN = "self-test: no plugin offers it (the vibrotactile plugin does)"


def _run(profile: Any, pm: Any, args: list[str]) -> tuple[int, Any]:
    """(exit status, its JSON report) of the ``selftest`` command run with ``args``."""
    cmd = pm.commands.get("selftest")
    p = argparse.ArgumentParser()
    cmd.configure(p)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = int(cmd.run(p.parse_args(args), _context(profile, pm)) or 0)
    return code, json.loads(buf.getvalue())


def _context(profile: Any, pm: Any) -> SimpleNamespace:
    """The command's context inside the console: the console holds its table itself
    (its own keys wait for the self-test), so the command takes no hold of its own."""
    return SimpleNamespace(
        profile=profile, pm=pm, holding_table=lambda who=None: contextlib.nullcontext()
    )


def selftest_estimate(profile: Any, pm: Any) -> tuple[float, int, bool] | None:
    """(seconds of chirps a full self-test plays, its paths, whether the twin's map is
    measured first), nothing played; None when no plugin can say (no such command, or
    it has no estimate for this table)."""
    if pm.commands.get("selftest") is None:
        return None
    try:
        _code, got = _run(profile, pm, ["--estimate", "--json"])
        return float(got["planned_s"]), int(got["paths"]), bool(got.get("map_first"))
    except (UserError, SafetyRefusal, ValueError, KeyError, TypeError, SystemExit):
        return None  # an older plugin without --estimate, or no estimate: said as such


def quick_skipped(profile: Any, pm: Any) -> str:
    """`haptable doctor`'s quick part's line when it skips on ``profile`` (``skipped: no
    baseline yet: ...``), nothing played; "" when it would run, or no plugin can say."""
    if pm.commands.get("selftest") is None:
        return ""
    try:
        _code, got = _run(profile, pm, ["--doctor", "--estimate", "--json"])
    except (UserError, SafetyRefusal, ValueError, KeyError, TypeError, SystemExit):
        return ""  # an older plugin: the row says what was kept, or not run
    if not isinstance(got, dict) or got.get("state") != "skipped":
        return ""
    return "; ".join(str(x) for x in got.get("lines") or ()) or "skipped"


#: how long the twin's vibration map takes to measure at most (the Vibration screen's
#: m; it took 8 s of the 15 s said with the chirps on a new operator's try): a bound
TWIN_MAP_S = 10.0


def selftest_about(
    profile: Any, pm: Any, last_s: float
) -> tuple[str, float, tuple[float, int, bool] | None]:
    """(what the self-test will do, in words; its seconds expected; the estimate) before
    it starts: its paths and seconds of chirps, the twin's map first on a fresh twin, or
    the last run's seconds here (``last_s``, 0: none), which know the setup around them."""
    est = selftest_estimate(profile, pm)
    about = f"{est[1]} relay paths, {est[0]:.0f} s of chirps" if est else "time unknown"
    total_s = est[0] if est else 0.0
    if est and est[2]:  # a fresh twin: its map first (the Vibration screen's m)
        about += f", the twin's vibration map first (at most {TWIN_MAP_S:.0f} s)"
        total_s += TWIN_MAP_S
    elif last_s:
        about += f", the last run took {last_s:.0f} s"
        total_s = max(total_s, last_s)
    return about, total_s, est


def selftest_progress(gone_s: float, total_s: float, est: tuple[float, int, bool] | None) -> str:
    """The line while the self-test runs, as other long work says it: what it is doing
    (the twin's map first, then the chirps and the comparison), its seconds so far of
    those expected and the time left (``selftest_about``'s ``total_s``, ``est``), or
    that it takes longer than expected, or that its time is unknown."""
    if est is not None and est[2] and gone_s < TWIN_MAP_S:
        doing = "measuring the twin's vibration map first"
    elif est is not None:
        doing = f"chirping {est[1]} relay paths and comparing what they read"
    else:
        doing = "chirping every relay path and comparing what they read"
    if total_s <= 0:
        return f"self-test: {doing}; {gone_s:.0f} s so far (its time is unknown)"
    if gone_s < total_s:
        left = left_words(total_s - gone_s)
        if est is not None and est[2]:  # the map's time is a bound (it took 8 s of 15 s)
            left = left.replace("about ", "at most ", 1)
            return f"self-test: {doing}; {int(gone_s)} s of at most {total_s:.0f} s, {left}"
        return f"self-test: {doing}; {int(gone_s)} s of about {total_s:.0f} s, {left}"
    return (
        f"self-test: {doing}; {gone_s:.0f} s, longer than the {total_s:.0f} s expected: "
        "finishing ..."
    )


#: the quick part's advice at a shell; in the console its ``s`` runs the same full test
#: (a healthy first run keeps its baseline, as the command's does)
CLI_RUN = "run `haptable selftest`"


def selftest_row(
    done: tuple[bool, str, float] | None,
    last: dict[str, dict[str, str]] | None = None,
    stopped: str = "",
    estopped: bool = False,
    skips: str = "",
) -> DeviceStatus:
    """The Devices doctor's self-test row, saying what ran: the full one run here
    (``done``: healthy, line, seconds), else the last kept (``last``:
    ``console.runtime.selftest_last``: `haptable doctor`'s quick part, a full one before),
    else what `haptable doctor`'s quick part says now when it skips (``skips``: its line,
    ``quick_skipped``: the same word and reason), else where to run it (``haptable
    doctor`` runs its quick part; here s the full one).
    ``stopped``: the last run here was stopped before its end (when, by what): the row
    says so first, the last whole run's outcome after it (it is no longer the news), and
    its fix asks for ctrl+r first only while the table is ``estopped``. The quick part's
    CLI advice (run `haptable selftest` ...) is said with the console's key."""
    if stopped:
        before = selftest_row(done, last, skips=skips)
        was = (
            f"; the last whole one: {before.state} {before.why}"
            if before.state != "not run"
            else ""
        )
        why = f"the last run stopped before its end ({stopped}){was}"
        fix = "s runs it again" + (" (ctrl+r first)" if estopped else "")
        return DeviceStatus("selftest", "full", "stopped", why, fix)
    last = last or {}
    full, quick = last.get("full"), last.get("quick")
    if done is None and full is not None:  # a full one kept from before
        why = f"{full['line'].removeprefix('self-test: ')} ({full['by']}, {full['time']})"
        return DeviceStatus("selftest", "full", full["state"], why, "press s to run it again")
    if done is None:
        plays = "the full one not run from the console: it plays a chirp on every relay path"
        if quick is None and skips:  # as `haptable doctor` would say it now
            said = skips.removeprefix("skipped: ").replace(CLI_RUN, "press s")
            why = f"quick self-test skipped ({said}); {plays}"
            return DeviceStatus("selftest", "quick", "skipped", why, "press s (full)")
        if quick is None:
            why = "not run from the console: it plays a chirp on every relay path"
            return DeviceStatus("selftest", "full", "not run", why, "press s")
        said = quick["line"].removeprefix("skipped: ").replace(CLI_RUN, "press s")
        # its reason first (the clause a shortened row keeps whole), who and when after
        when = f"{quick['by']} at {quick['time']}"
        why = f"quick self-test {quick['state']} ({said}); {when}; {plays}"
        return DeviceStatus("selftest", "quick", quick["state"], why, "press s (full)")
    ok, line, took_s = done
    why = line.removeprefix("self-test: ")
    return DeviceStatus("selftest", "full", "ok" if ok else "error", why, "" if ok else "see log")


def run_selftest(profile: Any, pm: Any) -> tuple[bool | None, str]:
    """(healthy, one line for the status line) of a full self-test on ``profile``;
    healthy ``None``: it did not run (refused: the e-stop, the gate), which says nothing
    of the table's health."""
    if pm.commands.get("selftest") is None:
        return False, NO_PLUGIN
    try:
        code, report = _run(profile, pm, ["--json"])
    except EStopLatched as exc:  # the console's words: its key first, not the CLI's
        return None, f"self-test {estop_refusal(exc.why)}"
    except SafetyRefusal as exc:
        said = " ".join(str(exc).split())
        if ": stopped: " in said or said.startswith("stopped: "):  # under way: stopped
            return None, f"self-test stopped before its end ({said})"
        at, end = said.find("e-stop active ("), said.rfind("; reset")
        if at >= 0:  # the kernel's "reset it first": the console's key instead
            return None, f"self-test refused: {said[at : end if end > at else None]}, {ESTOP_FIX}"
        return None, f"self-test refused: {said}"
    except UserError as exc:
        return False, f"self-test: {exc}"
    except ValueError:
        return False, "self-test: its report was not readable; run `haptable selftest`"
    lines = report.get("lines") or []
    took = f" ({report.get('elapsed_s', 0):.0f} s)"
    return code == 0, "self-test: " + "; ".join(lines) + took

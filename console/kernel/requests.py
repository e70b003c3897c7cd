"""What a client may ask the kernel, one function per request (``REQUESTS``).

Each takes ``(kernel, client, header, payload)`` and returns the reply's fields (``None``:
no reply; ``"_arrays"``: arrays sent with it). Everything a header carries is checked
here before it reaches the scheduler or the gate: a wrong type, a NaN, an unknown patch or
an array that does not add up is a one-line error for that request, never an exception
further in. What a request may not do is not here: nothing sets the gate's state, nothing
opens a driver, and ``reset`` is the operator's (``console.kernel.operator``).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from console.core.errors import SafetyRefusal, TableBusy
from console.kernel import wire
from console.kernel.input_requests import INPUT_REQUESTS
from console.kernel.output_settings import output_settings, settings_key
from console.kernel.tables import read_latch

if TYPE_CHECKING:
    from console.kernel.server import Client, Kernel

#: plans one client may keep checked at once (each is its samples, copied)
MAX_PLANS = 4096
#: bytes of checked samples one client may keep
MAX_PLAN_BYTES = 512 * 1024 * 1024
#: plays the kernel remembers for the scope's "last plan" (whoever asked)
PLAYS_KEPT = 8

Reply = dict[str, Any] | None
Request = Callable[["Kernel", "Client", dict[str, Any], bytearray], Reply]


def hello(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    c.command = str(h.get("command", ""))[:200]
    c.role = str(h.get("role", "client"))[:20]
    return {
        "ok": True,
        "kernel_pid": os.getpid(),
        "table": k.table.key,
        "client": c.cid,
        "private": k.table.private,
        "fast": k.fast,
        "latched": read_latch(k.table),
        "estopped": k.gate.estopped,
        "estop_reason": k.gate.estop_reason,
        "settings": settings_key(k.profile),
        "output_settings": output_settings(k.profile),  # a refused client names the keys
    }


def plan(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    """Check a plan's samples now; it plays later by the id this returns."""
    checked = k.scheduler.check(_plan_from(h, wire.arrays(h, payload)))
    nbytes = sum(a.nbytes for seg in checked.samples for a in seg)
    if len(c.plans) >= MAX_PLANS or c.plan_bytes + nbytes > MAX_PLAN_BYTES:
        raise SafetyRefusal(
            f"{checked.name}: this process keeps {len(c.plans)} checked plans "
            f"({c.plan_bytes / 2**20:.0f} MB); forget some first"
        )
    pid_ = k.new_id()
    c.plans[pid_] = (checked, nbytes)
    c.plan_bytes += nbytes
    return {"ok": True, "plan": pid_, "duration_s": checked.duration_s}


def forget(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    got = c.plans.pop(_int(h, "plan"), None)
    if got is not None:
        c.plan_bytes -= got[1]
    return None


def hold(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    """A run that must not be mixed with other sounds (a participant's study run): until
    this client lets go (``unhold``) or leaves, every other client's plays, relay
    settings and streams are refused, naming the run. One holder at a time; an e-stop
    still silences everything."""
    who = str(h.get("who") or c.label())[:200]
    if k.holder is not None and k.holder[0] != c.cid:
        raise TableBusy(f"refused: {k.holder[1]} holds the outputs; stop it there first")
    k.holder = (c.cid, who)
    return {"ok": True}


def unhold(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    if k.holder is not None and k.holder[0] == c.cid:
        k.holder = None
    return {"ok": True}


def _not_held(k: Kernel, c: Client, what: str) -> None:
    """``TableBusy`` naming the run when another client holds the outputs."""
    held = k.holder
    if held is not None and held[0] != c.cid:
        raise TableBusy(
            f"{what}: refused: {held[1]} holds the outputs, paused or not (stop it there first)"
        )


def play(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    got = c.plans.get(_int(h, "plan"))
    if got is None:
        return {"error": f"plan {h.get('plan')!r} is not checked here; send it first"}
    _not_held(k, c, got[0].name or "plan")
    j = k.new_id()
    c.jobs[j] = k.scheduler.play(got[0], owner=c.cid, on_change=k.job_listener(c, j))
    k.plays.append((_play_words(j, got[0], c), c.jobs[j]))
    return {"ok": True, "job": j}


def _play_words(job: int, checked: Any, c: Client) -> dict[str, Any]:
    """What the scope's "last plan" says of a play: its name, who sent it, where."""
    return {
        "job": job,
        "name": checked.name,
        "client": c.cid,
        "pid": c.pid,
        "role": c.role,
        "command": c.command,
        "duration_s": float(checked.duration_s),
        "patches": sorted({p for patches, _ in checked.routes for p in patches}),
        "screen": any(screen for _, screen in checked.routes),
    }


def prearm(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    _not_held(k, c, "relays")
    j = k.new_id()
    rep = k.scheduler.prearm(
        _patches(h.get("patches")),
        h.get("screen") is True,
        owner=c.cid,
        on_change=k.job_listener(c, j),
    )
    if rep is None:
        return {"ok": True, "job": None}
    c.jobs[j] = rep
    return {"ok": True, "job": j, "done": rep.done.is_set()}


def disarm(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    j = k.new_id()
    rep = k.scheduler.disarm(owner=c.cid, on_change=k.job_listener(c, j))
    if rep is None:
        return {"ok": True, "job": None}
    c.jobs[j] = rep
    return {"ok": True, "job": j, "done": rep.done.is_set()}


def relays(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    """The operator's relay setting (refused during an e-stop)."""
    closed = h.get("closed")
    if not isinstance(closed, list) or len(closed) > 64 or not all(type(x) is int for x in closed):
        raise ValueError("'closed' must be a list of relay channel numbers")
    _not_held(k, c, "relays")
    j = k.new_id()
    c.jobs[j] = k.scheduler.set_relays(
        frozenset(closed), owner=c.cid, on_change=k.job_listener(c, j)
    )
    return {"ok": True, "job": j}


def cancel(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    rep = c.jobs.get(_int(h, "job"))
    dropped = rep is not None and k.scheduler.cancel(rep, str(h.get("why", "cancelled"))[:200])
    return {"ok": True, "dropped": dropped}


def stream(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    """A live stream from its parameters: checked against the limits, synthesised here."""
    # lazy: keeps NumPy out of this module's import
    from console.signals.stream_synth import StreamSpec

    spec = StreamSpec.from_json(h.get("spec"))
    name = str(h.get("name", "stream"))[:100]
    _not_held(k, c, name)
    j = k.new_id()
    rep, synth = k.scheduler.stream(spec, name, owner=c.cid, on_change=k.job_listener(c, j))
    c.jobs[j] = rep
    c.streams[j] = synth
    return {"ok": True, "job": j}


def post(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    """Crossings and carrier targets for a stream (no reply: on the knob's path)."""
    synth = c.streams.get(_int(h, "job"))
    if synth is not None:
        ids = h.get("ids") or []
        if not isinstance(ids, list) or len(ids) > 1000 or not all(type(i) is int for i in ids):
            raise ValueError("'ids' must be a list of at most 1000 crossing ids")
        synth.post(ids, _finite_or_none(h.get("hz")), _finite_or_none(h.get("v")))
    return None


def stop_stream(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    synth = c.streams.get(_int(h, "job"))
    if synth is not None:
        synth.request_stop()
    return None


def release(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    """Ramp down what this client plays, drop what it queued (no e-stop)."""
    return {
        "ok": True,
        "jobs": k.scheduler.abort_owner(c.cid, str(h.get("reason", "released"))[:200]),
    }


def estop(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    return {"ok": True, **k.estop(str(h.get("reason") or "e-stop")[:300], by=c.label())}


def reset(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    """An operator's only (``console.kernel.operator``); anyone else gets the line why."""
    line = k.reset(c.pid, str(h.get("who") or c.label())[:200], via_terminal=False)
    if line.startswith("ok"):
        return {"ok": True, "message": line[4:], "t": k.reset_t}
    return {"error": line, "refused": True}


def status(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    return {"ok": True, "status": wire.jsonable(k.status())}


def events(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    since = _int(h, "since", 0)
    evs = [e for e in k.gate.events if e.clock >= since] if since else list(k.gate.events)
    return {
        "ok": True,
        "events": [[e.t_s, int(e.clock), e.kind, e.message, bool(e.cut)] for e in evs[-1000:]],
    }


def recording(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    """What the twin's amplifiers got, in sound-card units (float32: half the bytes)."""
    # lazy: keeps NumPy out of this module's import
    from console.core.contracts import RecordsUnderruns, SimulatedAudio

    if not isinstance(k.audio, SimulatedAudio):
        return {"ok": True, "recording": False}
    since = max(0, _int(h, "since", 0))
    logs = isinstance(k.audio, RecordsUnderruns)
    if h.get("as_played") is True and logs:
        rec = k.audio.dac_output_card()[since:]  # underrun gaps inserted: not clock-indexed
    else:
        rec = k.audio.recording_card(since=since)  # only the rows asked for are copied
    # where the DAC starved (the gap fell before that clock) and for how many samples
    gaps = [[int(g.clock), int(g.samples)] for g in list(k.audio.underrun_log)] if logs else []
    return {"ok": True, "recording": True, "underruns": gaps, "_arrays": [rec]}


def relay_log(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    log = k.outputs.relay_log()
    if log is None:
        return {"ok": True, "log": None}
    return {
        "ok": True,
        "log": [
            [r.t_s, int(r.clock), int(r.channel), bool(r.closed), list(r.level_v)]
            for r in list(log)[max(0, _int(h, "since", 0)) :]
        ],
    }


def scope(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    sec = _finite_or_none(h.get("seconds"))
    trace = k.gate.scope.read(None if sec is None else max(0.0, sec))
    return {
        "ok": True,
        "clock": int(trace.clock),
        "last_plan": last_plan(k),
        "_arrays": [trace.volts.astype("<f4")],
    }


def last_plan(k: Kernel) -> dict[str, Any] | None:
    """The newest plan the gate started passing, whoever asked (None: none yet): its
    name, who sent it, where it plays and its segments' clocks."""
    for words, rep in reversed(list(k.plays)):
        start = list(rep.segment_start)
        if start:
            done = rep.done.is_set()
            end = list(rep.segment_end)
            return {**words, "start": start, "end": end, "done": done, "error": rep.error}
    return None


def playing(k: Kernel) -> dict[str, Any] | None:
    """The play the gate passes now, whoever asked (None: none): its name and who sent
    it (``command``, ``pid``), for a relay routed its way to say by whom."""
    for words, rep in reversed(list(k.plays)):
        if not rep.done.is_set():  # routing its relays, or passing its samples
            return {key: words[key] for key in ("name", "pid", "command", "client")}
    return None


def retire(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    """A client with other settings takes the table, if nobody else uses it."""
    others = [o.label() for o in k.client_list() if o is not c]
    if others or k.scheduler.busy:
        return {"ok": False, "clients": others or ["a plan that plays"]}
    k.quit()
    return {"ok": True}


def bye(k: Kernel, c: Client, h: dict[str, Any], payload: bytearray) -> Reply:
    c.gone.set()
    return {"ok": True}


REQUESTS: dict[str, Request] = {
    fn.__name__: fn
    for fn in (
        hello,
        plan,
        forget,
        play,
        hold,
        unhold,
        prearm,
        disarm,
        relays,
        cancel,
        stream,
        post,
        stop_stream,
        release,
        estop,
        reset,
        status,
        events,
        recording,
        relay_log,
        scope,
        retire,
        bye,
        *INPUT_REQUESTS,
    )
}


# ---------------------------------------------------------------------- fields
def _int(h: dict[str, Any], key: str, default: int | None = None) -> int:
    v = h.get(key, default)
    if type(v) is not int:
        raise ValueError(f"{key!r} must be an integer")
    return v


def _finite_or_none(v: Any) -> float | None:
    if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v):
        return float(v)
    return None


def _patches(v: Any) -> frozenset[str]:
    if not isinstance(v, list) or not all(isinstance(p, str) for p in v) or len(v) > 16:
        raise ValueError("'patches' must be a list of patch names")
    return frozenset(v)


def _plan_from(h: dict[str, Any], arrays: list) -> Any:
    """The ``OutputPlan`` a ``plan`` request describes (its arrays in order: each
    segment's piezo, screen, then its own patch drives)."""
    # lazy: keeps NumPy out of this module's import
    from console.core.types import OutputPlan, Segment

    segs_in = h.get("segments")
    if not isinstance(segs_in, list) or len(segs_in) > 10000:
        raise ValueError("'segments' must be a list")
    it = iter(arrays)
    segs = []
    try:
        for s in segs_in:
            if not isinstance(s, dict):
                raise ValueError("a segment is not an object")
            piezo, screen = next(it), next(it)
            own = s.get("own", [])
            if not isinstance(own, list) or not all(isinstance(p, str) for p in own):
                raise ValueError("'own' must be a list of patch names")
            patch_v = {p: next(it) for p in own}
            segs.append(
                Segment(
                    piezo,
                    screen,
                    _patches(s.get("patches", [])),
                    s.get("screen") is True,
                    str(s.get("label", ""))[:200],
                    patch_v,
                )
            )
    except StopIteration:
        raise ValueError("fewer arrays than the segments name") from None
    if next(it, None) is not None:
        raise ValueError("more arrays than the segments name")
    fs = h.get("fs")
    gap = h.get("gap_s", 0.0)
    if type(fs) is not int:
        raise ValueError("'fs' must be an integer sample rate")
    if not isinstance(gap, (int, float)) or isinstance(gap, bool):
        raise ValueError("'gap_s' must be a number")
    return OutputPlan(fs, tuple(segs), str(h.get("name", ""))[:200], float(gap))

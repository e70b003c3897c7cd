"""Replay a study's recording (``trial_recording``): each recorded trial's stimulus is
rendered again from its recorded parameters through the same code the run used
(``EffectPlayer.prepare``: the registered ``FlowEffect`` / ``HandFlowEffect`` with the
recorded vibration map and the participant's level; no output is needed) and the plan's
samples are hashed (``plan_hash``) against every plan the trial handed its outputs.
Simulated knob trials are run again with their seed (``KnobTrials.knob_trial``) and
their measures compared.

``haptable study replay PATH`` (and ``haptable replay PATH``): PATH a trial file, a
participant's ``recording`` folder, a participant folder or a study's ``--out`` folder.
One line: every trial the same (exit 0) or the first differing trial (exit 1)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from console.plugin_api import (
    GATE_EVENTS,
    UserError,
    gate_events_text,
    load_map,
    plan_hash,
    read_gate_events,
)

from .stimuli import EffectPlayer, knob_trial
from .trial_recording import (
    FOLDER,
    FORMAT,
    FORMAT_VERSION,
    MAP_FILE,
    file_sha256,
    first_difference,
)

FIX = "give a study recording (haptable study run ... --record)"
#: the knob measures a simulated knob trial's replay compares
KNOB_KEYS = ("completion_time_s", "overshoots", "recovery_time_s", "timed_out")


def trial_files(path: str | Path) -> list[Path]:
    """The trial files under ``path`` (see the module), in participant and trial order."""
    p = Path(path).expanduser()
    if p.is_file():
        return [p]
    if not p.is_dir():
        raise UserError(f"study recording {p}: no such file or folder; {FIX}")
    for pattern in ("trial_*.h5", f"{FOLDER}/trial_*.h5", f"*/{FOLDER}/trial_*.h5"):
        found = sorted(p.glob(pattern))
        if found:
            return found
    raise UserError(f"study recording {p}: no recorded trial (trial_NNNN.h5) in it; {FIX}")


def is_study_recording(path: str | Path) -> bool:
    """Whether ``path`` is a study recording (a folder with trial files, or a trial file)."""
    p = Path(path).expanduser()
    if p.is_dir():
        try:
            return bool(trial_files(p))
        except UserError:
            return False
    if not p.is_file():
        return False
    try:
        return _format(p) == FORMAT
    except Exception:
        return False


def _format(p: Path) -> str:
    import h5py  # lazy: only when replaying

    with h5py.File(p, "r") as f:
        fmt = f.attrs.get("format", "")
    return fmt.decode() if isinstance(fmt, bytes) else str(fmt)


def _text(f: Any, key: str) -> str:
    v = f[key][()]
    return v.decode() if isinstance(v, bytes) else str(v)


def read_trial(p: Path) -> dict[str, Any]:
    """A trial file's contents (one ``UserError`` line naming the file otherwise)."""
    import h5py  # lazy: only when replaying

    try:
        f = h5py.File(p, "r")
    except OSError:
        raise UserError(f"study recording {p}: not an HDF5 file (or unreadable); {FIX}") from None
    with f:
        attrs = {k: (v.decode() if isinstance(v, bytes) else v) for k, v in f.attrs.items()}
        if attrs.get("format") != FORMAT:
            raise UserError(f"study recording {p}: an HDF5 file but not a study trial; {FIX}")
        if int(attrs.get("format_version", 0)) > FORMAT_VERSION:
            raise UserError(f"study recording {p}: a newer format than this HapTable; update it")
        try:
            trial = json.loads(_text(f, "trial"))
            done = json.loads(_text(f, "done"))
            outputs = [json.loads(x) for x in _text(f, "outputs").splitlines() if x.strip()]
        except (KeyError, ValueError) as exc:
            raise UserError(f"study recording {p}: damaged ({exc}); {FIX}") from None
        n_frames = int(f["frames"].shape[0]) if "frames" in f else 0
        gate = read_gate_events(f[GATE_EVENTS][:]) if GATE_EVENTS in f else []
    return {
        "attrs": attrs,
        "trial": trial,
        "done": done,
        "outputs": outputs,
        "frames": n_frames,
        "gate_events": gate,
    }


class _Maps:
    """The recorded vibration maps, loaded once each and checked against their hash."""

    def __init__(self) -> None:
        self._maps: dict[Path, Any] = {}

    def get(self, trial_file: Path, sha: str) -> Any:
        path = trial_file.parent / MAP_FILE
        if path not in self._maps:
            if not path.is_file():
                raise UserError(f"study recording {trial_file}: {path} is missing; restore it")
            if sha and file_sha256(path) != sha:
                raise UserError(
                    f"study recording {trial_file}: {path} is not the map the trial was "
                    "rendered with (its SHA-256 differs); restore it"
                )
            self._maps[path] = load_map(path, require_all=False)
        return self._maps[path]


def _where(p: Path, rec: dict[str, Any]) -> str:
    a = rec["attrs"]
    return f"trial {int(a.get('trial_index', -1)) + 1} ({a.get('participant', '?')}, {p.name})"


def replay_trial(p: Path, rec: dict[str, Any], ctx: Any, maps: _Maps) -> tuple[str | None, int]:
    """(first difference or None, plans compared; -1: a person's knob trial, which
    nothing renders again) for one recorded trial."""
    trial, attrs = rec["trial"], rec["attrs"]
    if "adaptive" in trial:  # an adaptive threshold run's trial
        from .adaptive_recording import replay_adaptive  # lazy: only for adaptive runs

        return replay_adaptive(p, rec, ctx, lambda: maps.get(p, str(attrs.get("map_sha256", ""))))
    stim = trial.get("stimulus") or {}
    if stim.get("task") == "knob":
        if not rec["done"].get("simulated"):
            return None, -1  # a person turned the knob: nothing to render again
        res = knob_trial(ctx.pm, ctx.profile, trial, int(attrs.get("participant_seed", 0)), 0)
        for key in KNOB_KEYS:
            a, b = rec["done"].get(key), res.get(key)
            if json.dumps(a) != json.dumps(b):
                return f"{key} recorded {a!r} vs run again {b!r}", 0
        return None, 0
    played = [x for x in rec["outputs"] if x.get("kind") == "plan" and not x.get("refused")]
    if not played:
        return "no plan was recorded as handed to the outputs", 0
    vmap = maps.get(p, str(attrs.get("map_sha256", "")))
    try:
        plan = EffectPlayer(ctx.pm, ctx.profile, vmap, lambda plan: True).prepare(trial)
    except (KeyError, TypeError, ValueError) as exc:
        return f"its recorded stimulus {json.dumps(stim)} does not render ({exc})", 0
    return first_difference(played, plan.name, plan_hash(plan))


def replay_study(path: str | Path, ctx: Any) -> tuple[bool, str]:
    """(same, one line) for a study recording (see the module)."""
    files = trial_files(path)
    maps = _Maps()
    n_plans, n_knob, n_live, who, frames = 0, 0, 0, set(), 0
    experiment = ""
    gate: list[dict[str, Any]] = []
    for p in files:
        rec = read_trial(p)
        gate += rec["gate_events"]
        experiment = str(rec["attrs"].get("experiment", ""))
        who.add(str(rec["attrs"].get("participant", "")))
        frames += rec["frames"]
        diff, n = replay_trial(p, rec, ctx, maps)
        if diff is not None:
            return False, f"replay: first difference at {_where(p, rec)}: {diff}"
        if n < 0:
            n_live += 1
            continue
        n_plans += n
        n_knob += (rec["trial"].get("stimulus") or {}).get("task") == "knob"
    people = ", ".join(sorted(who))
    seen = f", {frames} camera frames recorded" if frames else ""
    how = []
    if n_knob + n_live < len(files):
        how.append(
            "every stimulus re-rendered from its recorded parameters, "
            f"{n_plans} plans' samples hashed"
        )
    if n_knob:
        how.append(f"{n_knob} simulated knob trials run again with their seed, measures equal")
    if n_live:
        how.append(f"{n_live} knob trials of a person not re-run (nothing to render)")
    return True, (
        f"replay: {len(files)} trials of {experiment} ({people}) the same: {'; '.join(how)}{seen}"
        f"; {gate_events_text(gate)} recorded"
    )

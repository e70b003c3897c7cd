"""An adaptive threshold run recorded per trial (``haptable study run threshold_... --record``
or ``[recording] study_trials``), as the fixed-plan studies are (``trial_recording``): one
``DIR/<participant>/recording/trial_0003.h5`` per trial, written to a ``.part`` file,
fsynced and renamed into place before the trial's ``done`` line is appended to
``adaptive_trials.jsonl`` (a killed trial leaves only a ``.part`` the resume overwrites).

Its ``trial`` is ``{"index": i, "adaptive": {trial, track, level_db, target_interval}}``
(what the procedure proposed); ``plan_sha256`` is ``adaptive.json``'s; root attributes
``kind`` = ``adaptive``, ``protocol_toml`` (the protocol's text) and ``protocol_sha256``.
``replay_adaptive`` renders the trial's plan again from those (the protocol parsed from
the recorded text, the gate's limits of the replaying profile, the recorded map) through
``adaptive_run.trial_plan`` and compares its hash with every plan the trial played."""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

from console.plugin_api import Limits, UserError, append_json_line, parse_toml_text, plan_hash

from . import adaptive_protocol as ap
from .adaptive_run import RUN, Setup, make_setup, trial_plan
from .stimuli import play_on_session
from .trial_recording import TrialRecorder, first_difference, spec_wants_recording

#: what a recorded adaptive trial keeps of the procedure's proposal
TRIAL_KEYS = ("trial", "track", "level_db", "target_interval")


class AdaptiveTrialRecorder(TrialRecorder):
    """A ``TrialRecorder`` for an adaptive run (see the module)."""

    def __init__(self, root: Path, setup: Setup, *, profile: Any, vmap: Any, seed: int) -> None:
        proto = setup.protocol
        try:
            text = Path(proto.path).read_text(encoding="utf-8")
        except OSError as exc:
            raise UserError(
                f"{proto.path}: cannot read the protocol to record it ({exc.strerror or exc}); "
                "restore it"
            ) from None
        super().__init__(
            root,
            {"experiment": proto.name, "trials": None},
            profile=profile,
            vmap=vmap,
            seed=seed,
            plan_file=RUN,
            attrs={"kind": "adaptive", "protocol_toml": text, "protocol_sha256": proto.sha256},
        )

    def trial_record(self, index: int, done: dict[str, Any]) -> dict[str, Any]:
        return {"index": int(index), "adaptive": {k: done[k] for k in TRIAL_KEYS}}


def recorded_log(rec: TrialRecorder) -> Callable[[Path, dict[str, Any]], None]:
    """``append_json_line`` for ``adaptive_trials.jsonl`` that also drives ``rec``: a
    ``start`` begins the trial's recording, a ``done`` writes its file first (then the
    line), an ``interrupted`` forgets it."""

    def log_event(path: Path, record: dict[str, Any]) -> None:
        rec.note(record)
        append_json_line(path, record)

    return log_event


def screen_recorded(
    session: Any, spec: dict[str, Any], root: Path, setup: Setup, vmap: Any, seed: int, holder: str
) -> tuple[Callable[[Any], Any], Callable[[Path, dict[str, Any]], None]]:
    """(play, log_event) of an adaptive run on the Studies screen: each trial recorded
    when its "record trials" switch (else ``[recording] study_trials``) says so."""
    play = play_on_session(session, holder)
    if not spec_wants_recording(spec, session.profile):
        return play, append_json_line
    rec = AdaptiveTrialRecorder(root, setup, profile=session.profile, vmap=vmap, seed=seed)
    return rec.noted_play(play, session.outputs), recorded_log(rec)


def recorded_setup(p: Path, rec: dict[str, Any], ctx: Any, vmap: Callable[[], Any]) -> Setup:
    """The run's ``Setup`` from a trial file: its protocol text (checked against its
    SHA-256), the replaying profile's limits, the recorded map when the levels need it."""
    attrs = rec["attrs"]
    text = str(attrs.get("protocol_toml", ""))
    if hashlib.sha256(text.encode("utf-8")).hexdigest() != attrs.get("protocol_sha256"):
        raise UserError(
            f"study recording {p}: its protocol text is not the one the run used (SHA-256 "
            "differs); restore the file"
        )
    where = f"{p} (recorded protocol)"
    proto = ap.parse(parse_toml_text(text, where=where, what="study protocol"), where)
    s = proto.stimulus
    needs_map = s["modality"] == "vibrotactile" and s["reference"] == "dB re 1 um"
    return make_setup(proto, Limits.from_profile(ctx.profile), vmap() if needs_map else None)


def replay_adaptive(
    p: Path, rec: dict[str, Any], ctx: Any, vmap: Callable[[], Any]
) -> tuple[str | None, int]:
    """(first difference or None, plans compared) for one recorded adaptive trial."""
    played = [x for x in rec["outputs"] if x.get("kind") == "plan" and not x.get("refused")]
    if not played:
        return "no plan was recorded as handed to the outputs", 0
    setup = recorded_setup(p, rec, ctx, vmap)
    t = rec["trial"]["adaptive"]
    try:
        plan = trial_plan(setup, t)
    except (KeyError, TypeError, ValueError) as exc:
        return f"its recorded trial {t} does not render ({exc})", 0
    return first_difference(played, plan.name, plan_hash(plan))

"""Starting a participant: protocol, participant record, plan, run folder (CLI and screen).

``prepare(...)`` checks everything before the first trial and stores it: the protocol
(``protocol.load``), the participant (given, already stored for a resume, or simulated),
the plan (``plan.make_plan``) written atomically to ``plan.json`` (``store.open_run``).

Simulated participants (``simulated_participant``): demographics drawn, seeded by the
participant, from the paper's experiment 2 sample (age N(29.6, 6.0) years clipped to
18..65; 4 of 11 female; 2 of 11 left-handed; hand width N(8.48, 0.52) cm; hand length
N(18.42, 1.0) cm: the paper's SD of 6.24 cm for hand length is not plausible, 1 cm is
used) and the observer's own parameters.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError

from . import protocol as protocols
from .plan import make_plan, participant_seed
from .store import (
    Participant,
    RunFiles,
    check_id,
    load_participant,
    make_participant,
    open_run,
    participant_dir,
    save_participant,
)
from .words import CLI, Words

PARTICIPANT_KEYS = ("age", "sex", "handedness", "hand_width_cm", "hand_length_cm", "consent")


@dataclass
class Prepared:
    protocol: protocols.Protocol
    files: RunFiles
    plan: dict[str, Any]
    participant: dict[str, Any]

    @property
    def participant_seed(self) -> int:
        return int(self.plan["seed"])


def simulated_participant(pid: str, seed: int, observer_parameters: dict[str, Any]) -> Participant:
    rng = np.random.default_rng([int(seed) % (2**63), 7])
    return Participant(
        id=pid,
        age=int(np.clip(round(rng.normal(29.6, 6.0)), 18, 65)),
        sex="female" if rng.random() < 4 / 11 else "male",
        handedness="left" if rng.random() < 2 / 11 else "right",
        hand_width_cm=round(float(rng.normal(8.48, 0.52)), 2),
        hand_length_cm=round(float(rng.normal(18.42, 1.0)), 2),
        consent_noted=False,
        consent_time="",
        simulated=True,
        observer=dict(observer_parameters),
    )


def stored_participant(out: Path, pid: str, words: Words = CLI) -> dict[str, Any] | None:
    """The participant already stored under ``out`` (a resume), else None."""
    return load_participant(RunFiles(participant_dir(out, check_id(pid))), words)


def prepare(
    study: str,
    pid: str,
    out: Path,
    *,
    details: dict[str, Any] | None = None,
    simulate: bool = False,
    observer: Any = None,
    seed: int | None = None,
    row: int | None = None,
    words: Words = CLI,
    resolve: Callable[[dict[str, Any], Path, dict[str, Any]], dict[str, Any]] | None = None,
) -> Prepared:
    """Everything checked and stored before the first trial (see the module docstring).
    ``details``: the participant's fields (``PARTICIPANT_KEYS``) for a new participant;
    ``observer``: the ``SimulatedObserver`` when ``simulate``; ``words``: how refusals
    name the fix (the CLI's flags or the screen's fields)."""
    proto = protocols.load(study)
    check_id(pid)
    plan = make_plan(proto, pid, seed=seed, row=row, row_hint=words.row)
    stored = stored_participant(out, pid, words)
    if stored is not None:
        if bool(stored.get("simulated")) != bool(simulate):
            sim = bool(stored.get("simulated"))
            how = words.resume_simulated if sim else words.resume_person
            raise UserError(
                f"{participant_dir(out, pid)}: participant {pid} is "
                f"{'simulated' if sim else 'a person'}; {how}, or use another {words.out}"
            )
        person = None
    elif simulate:
        pseed = participant_seed(proto, pid) if seed is None else int(seed)
        params = (
            observer.parameters(pseed)
            if observer is not None
            else {"model": "the knob task's simulated finger (KnobTrials)"}
        )
        person = simulated_participant(pid, pseed, params)
    else:
        d = dict(details or {})
        person = make_participant(pid, **{k: d.get(k) for k in PARTICIPANT_KEYS}, words=words)
    if proto.level:  # the participant's stimulus level (sensation.py), before plan.json
        if resolve is None:
            raise UserError(
                f"{proto.path}: study.level = {proto.level!r}: run it with `haptable study "
                f"run {proto.name} --participant {pid} --out DIR`"
            )
        who = stored if stored is not None else asdict(person)
        plan = resolve(plan, participant_dir(out, pid), who)
    files, plan = open_run(out, pid, plan, words)
    if person is not None:
        save_participant(files, person)
        stored = asdict(person)
    return Prepared(proto, files, plan, stored)

"""How a message tells the fix where the user is: the CLI's flags (``CLI``) or the Studies
screen's fields (``SCREEN``, as its labels read: "folder", "simulated", "consent noted").

The code both share (``store``, ``start``, ``plan``, ``analysis``) takes a ``Words`` and
words its refusals with it: "give a writable --out" at a shell, "give a writable folder"
on the screen. The CLI's messages keep their flag names.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any


@dataclass(frozen=True)
class Words:
    #: the results folder ("--out" / "folder"): "give a writable {out}", "use another {out}"
    out: str
    #: how to point the analysis at the runs, after "give" / "set"
    runs: str
    #: each participant field as the user gives it
    fields: Any = field(default_factory=dict)
    #: how the consent is noted
    consent: str = ""
    #: how to resume a stored simulated participant / a stored person
    resume_simulated: str = ""
    resume_person: str = ""
    #: how to pick the counterbalancing row ("" when the user cannot: the id picks it)
    row: str = ""
    #: how to leave participants out of the analysis
    exclude: str = ""
    #: how a stopped run resumes
    resume: str = ""


CLI = Words(
    out="--out",
    runs="give the --out folder of `haptable study run`",
    fields=MappingProxyType(
        {
            "age": "--age",
            "sex": "--sex",
            "handedness": "--handedness",
            "hand_width_cm": "--hand-width-cm",
            "hand_length_cm": "--hand-length-cm",
        }
    ),
    consent="--consent",
    resume_simulated="resume it with --simulate",
    resume_person="resume without --simulate",
    row="or give --row",
    exclude="leave the participants out with --exclude",
    resume="the same `study run` command resumes",
)

SCREEN = Words(
    out="folder",
    runs="set folder to the study's results folder (the one holding P01/ ...)",
    fields=MappingProxyType(
        {
            "age": "age",
            "sex": "sex",
            "handedness": "handedness",
            "hand_width_cm": "hand width cm",
            "hand_length_cm": "hand length cm",
        }
    ),
    consent="tick 'consent noted'",
    resume_simulated="tick 'simulated' to resume it",
    resume_person="untick 'simulated' to resume",
    row="",
    exclude="move their folders out of the results folder",
    resume="s with the same participant resumes",
)


def listing(items: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]

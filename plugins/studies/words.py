"""How a message tells the fix where the user is: the CLI's flags (``CLI``) or the Studies
screen's fields (``SCREEN``, as its labels read: "folder", "simulated", "consent noted").

The console's rule (``console.core.words``, through the plugin API): a message names the fix
where the user is. The code both share (``store``, ``start``, ``plan``, ``analysis``)
takes a ``Words`` and words its refusals with it: "give a writable --out" at a shell,
"give a writable folder" on the screen; each ``Words`` is for one place (``where``), and
``Words.worded`` words an error that carries its fix per place (``Placed``) for it. The
CLI's messages keep their flag names.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from console.plugin_api import AT_CLI, AT_CONSOLE, listing, worded


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
    #: the place these words are for (``console.core.words``: ``AT_CLI``, ``AT_CONSOLE``)
    where: str = AT_CLI

    def worded(self, exc: BaseException) -> str:
        """``exc`` as one line for this place (its fix for here, when it has one)."""
        return worded(exc, self.where)


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
    where=AT_CLI,
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
    where=AT_CONSOLE,
)


__all__ = ["CLI", "SCREEN", "Words", "listing"]

"""The console session: what the operator's console runs, outside the screens.

``ConsoleSession`` owns the outputs and their hand-over to a demo process, the control
server (one console at a time, ``haptable estop`` reaches it), the camera service, the
vibration session, the demo lifecycle and the projector service. Screens call it from
worker threads and observe it: it reports what happened as ``console.session.events``
values to its subscribers (the Textual app turns them into messages for every screen).
Nothing here imports Textual.
"""

from console.session.core import ConsoleSession
from console.session.events import Failed, Progress, SessionEvent, Snapshot, Started, Stopped

__all__ = [
    "ConsoleSession",
    "Failed",
    "Progress",
    "SessionEvent",
    "Snapshot",
    "Started",
    "Stopped",
]

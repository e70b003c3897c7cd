"""What a panel opened over a screen (a plugin's ``ModalScreen``, e.g. the Gestures
panel) may offer the console, as Protocols the app asks for (never a name probed)."""

from __future__ import annotations

from typing import Protocol, runtime_checkable


@runtime_checkable
class LeavesForScreen(Protocol):
    """A panel that an F-key may close to show another screen: ``leave_for_screen()``
    closes it (True), or keeps it open and says on its own line why (False)."""

    def leave_for_screen(self) -> bool: ...

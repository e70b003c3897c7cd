"""A registered demo: the factory ``haptable_register_demos`` registers for ``flow`` and
``knob`` (``console.core.contracts.DemoFactory``)."""

from __future__ import annotations

from typing import Any


class DemoFactory:
    """A registered demo (``console.core.contracts.DemoFactory``): called ``(profile, plugins,
    outputs, **params)`` it starts the demo (``plugins.demos.run.start_demo``);
    ``status_lines(snapshot)`` formats a snapshot of it (``plugins.demos.status``)."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.__doc__ = f"Start the {name} demo (``plugins.demos.run.start_demo``)."

    def __call__(self, profile: Any, plugins: Any, outputs: Any, **params: Any) -> Any:
        # lazy: this module loads at every haptable start; run only when used
        from .run import start_demo

        return start_demo(self.name, profile, plugins, outputs, **params)

    def status_lines(self, snapshot: dict[str, Any]) -> list[str]:
        from .status import status_lines  # lazy: it keeps Textual (its markup) lazy

        return status_lines(snapshot)

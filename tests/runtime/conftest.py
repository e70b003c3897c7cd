"""Load the runtime's plugins (demos, tuio) with the built-ins, whether listed there or not."""

from __future__ import annotations

import pytest


@pytest.fixture
def plugins():
    import plugins.demos
    import plugins.tuio
    from console.plugins import BUILTIN_PLUGINS, load_plugins

    mine = {"demos": plugins.demos, "tuio": plugins.tuio}
    listed = set(BUILTIN_PLUGINS)
    return load_plugins(extra={k: v for k, v in mine.items() if k not in listed})

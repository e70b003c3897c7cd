"""Hermetic tests: no installed third-party plugins, private runtime dir, sim profile."""

from __future__ import annotations

import os

import pytest

os.environ["HAPTABLE_LOAD_ENTRYPOINTS"] = "0"
os.environ.pop("HAPTABLE_BLOCK_PLUGINS", None)
os.environ.pop("HAPTABLE_PROFILE", None)
os.environ.pop("HAPTABLE_PROFILES", None)


@pytest.fixture(autouse=True)
def _private_runtime(tmp_path_factory, monkeypatch):
    run = tmp_path_factory.mktemp("run")
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(run))
    monkeypatch.setenv("HOME", str(tmp_path_factory.mktemp("home")))


@pytest.fixture
def plugins():
    from console.plugins import load_plugins

    return load_plugins()


@pytest.fixture
def profile(plugins):
    from console.profile import load_profile

    return load_profile("sim", plugins)


@pytest.fixture
def outputs(profile, plugins):
    """The sim profile's outputs behind the safety gate, fast-forwarded; closed after."""
    from console.runtime.outputs import open_outputs

    out = open_outputs(profile, plugins, fast=True)
    yield out
    out.close()

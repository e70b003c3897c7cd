"""Hermetic tests: no installed third-party plugins, private runtime dir, sim profile, and
every directory ``console.files.paths`` names under one tmp root per session (per xdist worker),
a fresh set of them for each test."""

from __future__ import annotations

import asyncio
import contextlib
import faulthandler
import gc
import os
import shutil
import sys
import tempfile
import threading
from pathlib import Path
from types import SimpleNamespace

import pytest

# One thread per BLAS / OpenMP pool, in the workers and in every process they start: the
# suite runs a worker per core and one more, and pools of a thread per core on top of
# them only spin for work (OpenBLAS waits busily), costing CPU the others need.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"
with contextlib.suppress(ImportError):
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)  # the pools of libraries already imported (numpy's OpenBLAS)

# Bytecode cached, whatever the shell says: the suite starts hundreds of Python processes
# (kernels, cameras, demos, the CLI), and each would compile the modules it imports anew.
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

# Fewer garbage collections, none through what the imports and the collection made (frozen
# once the tests are collected): the console tests make many short-lived objects, and
# the collector's passes over every module's objects cost ~8 % of the suite's CPU.
gc.set_threshold(10_000, 20, 20)


@pytest.hookimpl(trylast=True)
def pytest_collection_finish(session):
    gc.collect()
    gc.freeze()


os.environ["HAPTABLE_LOAD_ENTRYPOINTS"] = "0"
# A runtime dir of this process's own (each xdist worker's) for what starts outside a
# test's own (``_private_runtime``): a module's or the session's kernels. Unset, they
# would all meet in /tmp/haptable-<uid>, every worker's and the machine's.
_WORKER_RUNTIME = tempfile.mkdtemp(prefix="ht-w-", dir="/tmp")
os.environ["XDG_RUNTIME_DIR"] = _WORKER_RUNTIME
os.environ.pop("HAPTABLE_BLOCK_PLUGINS", None)
os.environ.pop("HAPTABLE_PROFILE", None)
os.environ.pop("HAPTABLE_PROFILES", None)


@pytest.hookimpl(tryfirst=True)
def pytest_cmdline_main(config):
    """pytest-xdist by default: one worker per core and one more, ``--dist loadgroup``
    (tests marked ``xdist_group`` share one worker), unless ``-n`` is given (``-n0``: one
    process) or xdist is off (``-p no:xdist``). The extra worker fills the time the
    console tests spend waiting for frames and screens (2-core VM: 698 s with three
    workers, 828 s with two). Here rather than in pyproject's addopts, which would make
    ``-p no:xdist`` an error."""
    if hasattr(config, "workerinput") or not config.pluginmanager.hasplugin("xdist"):
        return
    if config.option.numprocesses is None and not config.option.collectonly:
        config.option.numprocesses = len(os.sched_getaffinity(0)) + 1
        if config.option.dist == "no":
            config.option.dist = "loadgroup"
    if config.option.maxworkerrestart is None:
        # a worker that dies ends the run, naming the test it died in: xdist 3.8's
        # loadgroup scheduler hangs for good after replacing a crashed worker
        # (pytest-xdist#1323, #1378; seen as a CI run stalled at 98 % until its limit)
        config.option.maxworkerrestart = "0"


#: A test (its setup and teardown, the session's at the last) still running after this
#: many seconds is ended with every thread's stack on the run's stderr, even when a C
#: call holds the interpreter (pyproject's ``timeout`` fails it first from Python).
#: Under xdist a worker's stdout is /dev/null: pytest-timeout's own stack dump for its
#: thread method went there, and the worker died without a word.
HARD_TIMEOUT_S = 420.0
_STDERR_FD: int | None = None


def pytest_unconfigure(config):
    shutil.rmtree(_WORKER_RUNTIME, ignore_errors=True)


def pytest_configure(config):
    global _STDERR_FD
    with contextlib.suppress(AttributeError, OSError, ValueError):
        _STDERR_FD = os.dup(sys.__stderr__.fileno())


#: A test still running after this many seconds has its event loop's tasks (what each
#: coroutine awaits: a thread's stack ends at the loop's idle ``select``) written to the
#: run's stderr, before pyproject's ``timeout`` fails it.
TASKS_DUMP_S = 240.0


def _main_loop():
    """The asyncio loop the main thread runs now (found on its stack), or None."""
    frame = sys._current_frames().get(threading.main_thread().ident)
    while frame is not None:
        candidate = frame.f_locals.get("self")
        if isinstance(candidate, asyncio.AbstractEventLoop):
            return candidate
        frame = frame.f_back
    return None


def _dump_tasks(nodeid: str) -> None:
    """Each pending task's stack on the run's stderr (called in the loop's thread)."""
    with os.fdopen(os.dup(_STDERR_FD), "w") as out:
        tasks = asyncio.all_tasks()
        print(f"\n+++ {nodeid}: {len(tasks)} asyncio tasks after {TASKS_DUMP_S:g} s", file=out)
        for task in tasks:
            print(f"--- {task.get_name()}", file=out)
            task.print_stack(limit=30, file=out)


def _tasks_later(nodeid: str) -> threading.Timer:
    def fire() -> None:
        loop = _main_loop()
        if loop is not None:
            with contextlib.suppress(RuntimeError):  # the loop just closed
                loop.call_soon_threadsafe(_dump_tasks, nodeid)

    timer = threading.Timer(TASKS_DUMP_S, fire)
    timer.daemon = True
    timer.start()
    return timer


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    if _STDERR_FD is None:
        yield
        return
    faulthandler.dump_traceback_later(HARD_TIMEOUT_S, exit=True, file=_STDERR_FD)
    tasks = _tasks_later(item.nodeid)
    try:
        yield
    finally:
        tasks.cancel()
        faulthandler.cancel_dump_traceback_later()


#: The slowest tests of a full run (``--durations``, 7 s or more), slowest first: they are
#: scheduled first, so no worker is left running a long one while the others wait at the
#: end (longest first: the shortest run). Names no longer collected are ignored.
SLOWEST = Path(__file__).with_name("slowest.txt")


#: Tests whose module- or session-scoped fixtures take seconds to build (a measured twin
#: map and its flow rows, a synthesised gesture set, a hostile-file kit): each group runs
#: on one xdist worker, which builds them once rather than once per worker.
SHARED_FIXTURE_GROUPS = {
    "tests/closed_loop/": "closed_loop",
    "tests/gestures/test_cli.py": "gestures_cli",
    "tests/gestures/test_classify_folder.py": "gestures_classify_folder",
    "tests/gestures/test_jobs.py": "gestures_jobs",
    "tests/malformed/test_config_files.py": "malformed_config_files",
    "tests/vibrotactile/test_modal_fit.py": "modal_fit",
    "tests/console/test_plan_info.py": "plan_info",
    "tests/recording/test_cut_samples.py": "cut_samples",
    "tests/instrument/test_selftest.py": "selftest",
    "tests/twin_plate/test_observer.py": "observer",
}


def pytest_collection_modifyitems(config, items):
    """The tests named in ``slowest.txt`` first, in its order; the rest as collected
    (the same order in every xdist worker: it sorts the same list the same way). Tests
    of ``SHARED_FIXTURE_GROUPS`` get their group (unless marked with one already)."""
    for item in items:
        group = next(
            (g for where, g in SHARED_FIXTURE_GROUPS.items() if item.nodeid.startswith(where)),
            None,
        )
        if group and not item.get_closest_marker("xdist_group"):
            item.add_marker(pytest.mark.xdist_group(group))
    try:
        order = {name: i for i, name in enumerate(SLOWEST.read_text().split())}
    except OSError:
        return
    items.sort(key=lambda item: order.get(item.nodeid, len(order)))


#: ``console.files.paths``' variables, each pinned below the session's tmp root.
PINNED_DIRS = (
    "HAPTABLE_CONFIG_DIR",
    "HAPTABLE_STATE_DIR",
    "HAPTABLE_CACHE_DIR",
    "HAPTABLE_DATA_DIR",
    "XDG_CONFIG_HOME",
    "XDG_STATE_HOME",
    "XDG_CACHE_HOME",
    "XDG_DATA_HOME",
)


def _pin(mp: pytest.MonkeyPatch, base: Path) -> None:
    for var in PINNED_DIRS:
        mp.setenv(var, str(base / var.lower()))


@pytest.fixture(scope="session", autouse=True)
def pinned_root(tmp_path_factory):
    """The session's root for config, state, cache and data: no test writes to ~/.cache.
    Session and module fixtures use ``session/`` below it."""
    root = tmp_path_factory.mktemp("pinned")
    with pytest.MonkeyPatch.context() as mp:
        _pin(mp, root / "session")
        yield root


@pytest.fixture(autouse=True)
def _pinned_dirs(pinned_root, monkeypatch):
    """Each test its own directories below the root: what one test cached (a measured map
    the Vibration screen loads at start, lookup tables) never changes what another sees,
    whichever worker ran what before. A module that shares a cache between its tests sets
    ``HAPTABLE_CACHE_DIR`` in an autouse fixture of its own."""
    _pin(monkeypatch, Path(tempfile.mkdtemp(prefix="test-", dir=pinned_root)))


@pytest.fixture(autouse=True)
def _no_question_written_over():
    """No timed question's line is written over behind its hold in any test: every
    setter that can replace a question waits for it (``console.tui.question_hold``)."""

    def overwritten() -> list:  # a test with no screen has none
        return getattr(sys.modules.get("console.tui.question_hold"), "OVERWRITTEN", [])

    overwritten().clear()
    yield
    found = list(overwritten())
    overwritten().clear()
    assert not found, f"a question written over past its hold (where, question, line): {found}"


@pytest.fixture(autouse=True)
def _private_runtime(tmp_path_factory, monkeypatch):
    """A private runtime dir per test, short whatever pytest's base temp is (sockets in
    it must fit the 107 bytes of a Unix socket address: pytest's own run counters grow)."""
    run = Path(tempfile.mkdtemp(prefix="ht-run-", dir="/tmp"))
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(run))
    monkeypatch.setenv("HOME", str(tmp_path_factory.mktemp("home")))
    yield
    shutil.rmtree(run, ignore_errors=True)


@pytest.fixture
def one_model_setting(monkeypatch):
    """Gesture training with one candidate setting (4 harmonics, 4 frames, one SVC
    point): for tests of where a model goes and what the screen says, not of the model
    selection (tests/gestures test that): the training takes seconds, not half a minute."""
    from plugins.gestures import model, selection

    monkeypatch.setattr(selection, "HARMONICS_CANDIDATES", (4,))
    monkeypatch.setattr(selection, "FRAMES_CANDIDATES", (4,))
    monkeypatch.setattr(model, "SVC_GRID", {"svc__C": [10.0], "svc__gamma": ["scale"]})


@pytest.fixture
def plugins():
    from console.config.plugins import load_plugins

    return load_plugins()


@pytest.fixture
def profile(plugins):
    from console.config.profile import load_profile

    return load_profile("sim", plugins)


@pytest.fixture
def outputs(profile, plugins):
    """The sim profile's outputs behind the safety gate, fast-forwarded; closed after."""
    from console.kernel.client import open_outputs

    out = open_outputs(profile, plugins, fast=True)
    yield out
    out.close()


@pytest.fixture
def table(profile, plugins):
    """The sim profile's table core built in this process (``TableOutputs``: the relay
    board and audio driver behind the gate and the scheduler), fast-forwarded; closed
    after. For tests of the gate's and the scheduler's internals (``table.gate``,
    ``table.scheduler``, ``table.board``, ``table.audio``)."""
    from console.kernel.table import TableOutputs

    t = TableOutputs(profile, plugins, fast=True)
    yield t
    t.close()


@pytest.fixture
def fake_vibrometer(profile):
    """Plugins (demos, tuio) with a counting vibrometer ``fake`` measuring an analytic plate,
    and the sim profile naming it: ``pm``, ``profile``, ``calls``, ``map``."""
    import plugins.demos
    import plugins.tuio
    from console.config.plugins import BUILTIN_PLUGINS, load_plugins
    from console.core.hookspecs import hookimpl
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map

    m = analytic_map(SSPlate())
    calls: list[int] = []

    class Vib:
        def __init__(self, profile):
            pass

        def measure(self, progress=None):
            calls.append(1)
            if progress is not None:
                progress(1, 1)
            return {
                "frf_um_per_v": m.frf_um_per_v,
                "freq_hz": m.freq_hz,
                "points": m.points,
                "points_mm": m.points_mm,
                "excitations": m.excitations,
                "masked": m.masked,
                "source": "fake vibrometer",
                "meta": {},
            }

    class FakePlugin:
        @hookimpl
        def haptable_register_vibrometers(self, register):
            register("fake", Vib)

    mine = {"demos": plugins.demos, "tuio": plugins.tuio, "fakevib": FakePlugin()}
    pm = load_plugins(extra={k: v for k, v in mine.items() if k not in BUILTIN_PLUGINS})

    class P:
        """The sim profile naming the fake vibrometer (``plate`` overridable)."""

        plate: dict = {}

        def get(self, key, default=None):
            return "fake" if key == "vibrometer.driver" else profile.get(key, default)

        def section(self, name):
            return self.plate if name == "plate" and self.plate else profile.section(name)

        def resolve(self, p):
            return profile.resolve(p)

    return SimpleNamespace(pm=pm, profile=P(), calls=calls, map=m)

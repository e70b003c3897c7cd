"""``console.runtime.prep_cancel``: a cancel from another thread ends the main thread's
armed block at once, even while it waits; a cancel before the block stops it on entry;
one after it is dropped; without the signal installed nothing is signalled; the
``multiprocessing`` children a cancelled preparation started are ended."""

from __future__ import annotations

import signal
import threading
import time

import pytest

from console.runtime.prep_cancel import SIGNAL, Preparation, PreparationCancelled, reap_children


@pytest.fixture
def prep():
    old = signal.getsignal(SIGNAL)
    p = Preparation()
    p.install()
    yield p
    signal.signal(SIGNAL, old)


def test_a_cancel_ends_a_wait_in_the_armed_block(prep):
    waited = threading.Event()
    threading.Timer(0.2, prep.cancel).start()
    t0 = time.monotonic()
    with pytest.raises(PreparationCancelled), prep.armed():
        waited.wait(30.0)  # a step that would wait long (a process's first frame)
        waited.set()
    assert not waited.is_set()  # cut in its wait, not after it
    assert time.monotonic() - t0 < 20.0


def test_a_cancel_before_the_block_stops_it_on_entry_and_one_after_is_dropped(prep):
    ran = []
    with prep.armed():
        ran.append(1)
    prep.cancel()  # after a block: nothing raises here
    time.sleep(0.05)
    with pytest.raises(PreparationCancelled), prep.armed():
        ran.append(2)
    assert ran == [1] and prep.asked


def test_an_exception_handler_of_a_step_lets_the_cancel_through(prep):
    threading.Timer(0.1, prep.cancel).start()
    with pytest.raises(PreparationCancelled), prep.armed():
        try:
            threading.Event().wait(30.0)
        except Exception:  # noqa: BLE001 - a step's own "one line for any failure"
            pytest.fail("a cancel is not an Exception")


def test_without_the_signal_installed_a_cancel_only_records_the_wish():
    old = signal.getsignal(SIGNAL)
    p = Preparation()  # not installed: a signal would kill the process by default
    with p.armed():
        p.cancel()
        time.sleep(0.05)
    assert signal.getsignal(SIGNAL) == old
    with pytest.raises(PreparationCancelled), p.armed():
        pass


def test_reap_children_ends_what_the_preparation_started():
    import multiprocessing

    ctx = multiprocessing.get_context("spawn")
    child = ctx.Process(target=time.sleep, args=(60.0,), daemon=True)
    child.start()
    assert reap_children() >= 1
    assert not child.is_alive() and child.exitcode == -signal.SIGTERM

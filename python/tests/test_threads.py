"""Watching a running system: a callback every k steps, and reads
from other threads while it steps (a consistent snapshot, never PyO3's borrow error)."""

import threading
import time

import numpy as np
import pytest

import hydrorattle as hr


def chain(n=12, dt=0.01, **kw):
    pos = np.zeros((n, 3))
    pos[:, 0] = 2.2 * np.arange(n)
    bonds = [[i, i + 1] for i in range(n - 1)]
    return hr.System(pos, 1.0, 2.0, bonds=bonds, dt=dt, **kw)


def test_callback_runs_every_k_steps_and_sees_the_state():
    s = chain()
    seen = []
    s.step(50, callback=lambda sys: seen.append((sys.time, sys.positions[0, 2])), every=10)
    assert [t for t, _ in seen] == pytest.approx([0.1, 0.2, 0.3, 0.4, 0.5])
    # The same bits as steps made without it.
    t = chain()
    t.step(50)
    assert s.state_bits() == t.state_bits()
    # With a force callable too (the GIL held throughout).
    u = chain()
    calls = []
    u.step(6, force=lambda p: np.zeros_like(p), callback=lambda sys: calls.append(sys.time), every=3)
    assert calls == pytest.approx([0.03, 0.06])


def test_an_exception_in_the_callback_stops_the_call_keeping_its_steps():
    s = chain()

    def stop(sys):
        if sys.time > 0.27:
            raise KeyError("stop")

    with pytest.raises(KeyError) as e:
        s.step(100, callback=stop, every=5)
    assert e.value.completed == 30 and s.time == pytest.approx(0.3)


def test_stepping_inside_the_callback_is_refused():
    s = chain()
    with pytest.raises(hr.SystemBusyError):
        s.step(3, callback=lambda sys: sys.step(1))
    with pytest.raises(hr.SystemBusyError):
        s.step(3, callback=lambda sys: sys.set_state(time=0.0))


def test_a_force_callable_reading_its_own_system_gets_a_typed_error():
    s = chain()

    def force(p):
        return np.zeros_like(s.positions)

    with pytest.raises(hr.SystemBusyError, match="positions it is passed"):
        s.step(1, force=force)
    assert s.time == 0.0


def test_reads_from_another_thread_see_whole_steps():
    """A reader thread polls while step(n) runs with the GIL released: every snapshot
    keeps the bond lengths (the state between two steps), no borrow error."""
    s = chain(n=40, method="overdamped", solver="newton")
    lengths = s.lengths
    errors, snaps = [], []
    done = threading.Event()

    def reader():
        try:
            while not done.is_set():
                p = s.positions
                snaps.append(np.abs(np.linalg.norm(p[1:] - p[:-1], axis=1) - lengths).max())
        except Exception as e:  # noqa: BLE001 (the test reports any)
            errors.append(e)

    th = threading.Thread(target=reader)
    th.start()
    try:
        s.step(300)
    finally:
        done.set()
        th.join()
    assert not errors, errors
    assert len(snaps) > 0 and max(snaps) < 1e-8


def test_a_second_step_from_another_thread_is_refused():
    s = chain(n=60)
    out = []
    started = threading.Event()

    def long_run():
        started.set()
        s.step(400)

    th = threading.Thread(target=long_run)
    th.start()
    started.wait()
    for _ in range(1000):
        try:
            s.step(1)
        except hr.SystemBusyError as e:
            out.append(e)
            break
    th.join()
    assert out, "the second step ran while the first was stepping"


def test_a_reader_waits_at_most_about_one_step():
    """The lock is fair: a stepping call gives way to a waiting reader between two
    steps, so a read waits for the end of the current step, not for tens of steps (the
    stepping thread used to win the lock back within microseconds, every step)."""
    # About 7 ms a step (300 beads, RPY, Newton) on an idle core.
    s = chain(n=300, method="overdamped", solver="newton")
    t0 = time.perf_counter()
    s.step(5)
    per_step = (time.perf_counter() - t0) / 5
    waits = []
    done = threading.Event()

    def reader():
        while not done.is_set():
            t = time.perf_counter()
            s.positions
            waits.append(time.perf_counter() - t)
            time.sleep(per_step * 0.37)  # reads fall anywhere in a step

    steps = 40
    th = threading.Thread(target=reader)
    th.start()
    try:
        t0 = time.perf_counter()
        s.step(steps)
        stepping = time.perf_counter() - t0
    finally:
        done.set()
        th.join()
    # Per step while read: the machine's load may have changed since the first timing.
    per_step = max(per_step, stepping / steps)
    assert len(waits) >= 10, f"{len(waits)} reads in {steps} steps of {per_step * 1e3:.1f} ms"
    assert max(waits) < 3 * per_step + 0.02, (
        f"a read waited {max(waits) * 1e3:.1f} ms; a step takes {per_step * 1e3:.1f} ms"
    )

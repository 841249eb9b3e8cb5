"""flowcurve.clock: the model clock against schedules worked out by hand, and the wall clock."""

import threading
import time

import pytest

from flowcurve.clock import WALL, ModelClock


def test_a_lone_sleeper_jumps_to_its_deadline():
    clock = ModelClock(start_s=2.0)
    clock.sleep(1.5)
    assert clock.now() == 3.5
    clock.sleep(0.0)
    assert clock.now() == 3.5


def test_timers_run_in_order_at_their_time_and_cancelled_ones_never():
    clock = ModelClock()
    seen = []
    clock.call_at(0.3, lambda: seen.append(("b", clock.now())))
    clock.call_at(0.1, lambda: seen.append(("a", clock.now())))
    dropped = clock.call_at(0.2, lambda: seen.append(("x", clock.now())))
    dropped.cancel()
    # a timer may schedule another one within the same advance
    clock.call_at(0.15, lambda: clock.call_at(0.25, lambda: seen.append(("c", clock.now()))))
    clock.advance(1.0)
    assert seen == [("a", 0.1), ("c", 0.25), ("b", 0.3)]
    assert clock.now() == 1.0
    with pytest.raises(ValueError):
        clock.advance(-0.1)


def test_threads_wake_in_the_order_of_their_own_schedules():
    """Two periodic threads (0.3 s and 0.5 s) on one clock: every wake-up at its multiple of
    the period, and together in the order of those multiples (written out here)."""
    clock = ModelClock()
    log, lock = [], threading.Lock()

    def periodic(name, period, n):
        for _ in range(n):
            clock.sleep(period)
            with lock:
                log.append((round(clock.now(), 9), name))

    threads = [threading.Thread(target=periodic, args=("a", 0.3, 5)),
               threading.Thread(target=periodic, args=("b", 0.5, 3))]
    for t in threads:
        clock.enlist(t)
    for t in threads:
        t.start()
    for t in threads:
        t.join(10)
    assert [t for t, _ in log] == [0.3, 0.5, 0.6, 0.9, 1.0, 1.2, 1.5, 1.5]  # in time order
    assert sorted(log) == [(0.3, "a"), (0.5, "b"), (0.6, "a"), (0.9, "a"), (1.0, "b"), (1.2, "a"),
                           (1.5, "a"), (1.5, "b")]  # (the two at 1.5 in either order)


def test_wait_returns_when_the_event_is_set_on_the_clock_or_at_the_time_out():
    clock = ModelClock()
    event = threading.Event()

    def setter():
        clock.sleep(0.2)
        event.set()
        clock.notify()

    t = threading.Thread(target=setter)
    clock.enlist(t)
    t.start()
    assert clock.wait(event, timeout=1.0) is True and clock.now() == pytest.approx(0.2)
    t.join(5)
    assert clock.wait(threading.Event(), timeout=0.5) is False
    assert clock.now() == pytest.approx(0.7)


def test_a_thread_waiting_for_a_lock_held_across_a_clock_wait_is_idle():
    clock = ModelClock()
    lock = threading.Lock()
    got_it_at = []
    holder_ready = threading.Event()

    def holder():
        with lock:
            holder_ready.set()
            clock.sleep(1.0)  # an exchange waiting for its reply, holding the port

    t = threading.Thread(target=holder)
    clock.enlist(t)
    t.start()
    holder_ready.wait(5)
    with clock.idle():
        lock.acquire()
    got_it_at.append(clock.now())
    lock.release()
    t.join(5)
    assert got_it_at == [1.0]


def test_a_participant_stuck_outside_the_clock_does_not_stop_time():
    clock = ModelClock(stall_s=0.01)
    release = threading.Event()
    stuck = threading.Thread(target=release.wait, args=(10,))  # a driver hanging in a real wait
    clock.enlist(stuck)
    stuck.start()
    try:
        clock.sleep(0.5)  # only the stall rule moves time on here
        assert clock.now() == 0.5
    finally:
        release.set()
        stuck.join(5)


def test_a_participant_computing_holds_time_however_slow():
    """A thread that is working (on a loaded machine: slowly) is not stuck: time waits for it,
    so the run's samples fall at the same model times on a busy machine as on an idle one."""
    clock = ModelClock(stall_s=0.01)
    seen = []

    def compute_then_read():
        clock.sleep(0.1)
        end = time.monotonic() + 0.3  # 30 stall periods of computing (a busy loop: CPU time grows)
        while time.monotonic() < end:
            pass
        seen.append(clock.now())
        clock.sleep(0.1)

    worker = threading.Thread(target=compute_then_read)
    clock.enlist(worker)
    worker.start()
    clock.sleep(1.0)  # the other participant: it would be the one to move time on a stall
    worker.join(5)
    assert seen == [pytest.approx(0.1)] and clock.stalls == 0


def test_a_computing_participant_is_still_given_up_after_the_hard_stall():
    clock = ModelClock(stall_s=0.01, hard_stall_s=0.05)
    stop = threading.Event()

    def spin():
        clock.sleep(0.0)
        while not stop.is_set():
            pass

    spinner = threading.Thread(target=spin)
    clock.enlist(spinner)
    spinner.start()
    try:
        clock.sleep(0.5)  # the spinner never waits again: only the hard stall moves time
        assert clock.now() == 0.5 and clock.stalls >= 1
    finally:
        stop.set()
        spinner.join(5)


def test_manual_clock_moves_only_by_hand():
    clock = ModelClock(auto=False)
    done = threading.Event()
    t = threading.Thread(target=lambda: (clock.sleep(2.0), done.set()))
    t.start()
    assert not done.wait(0.05) and clock.now() == 0.0
    clock.advance(2.0)
    assert done.wait(5)
    t.join(5)


def test_wall_clock_is_real_time():
    t0 = WALL.now()
    event = threading.Event()
    WALL.call_at(t0, event.set)
    assert WALL.wait(event, 5.0)
    assert WALL.now() >= t0
    with WALL.idle():
        pass


def test_a_waiter_woken_by_its_event_acts_at_that_time_before_time_moves_on():
    """A port's reply set by a device timer at 1.0 s wakes the reader waiting for it; a second
    thread that then sleeps must not move time on before the reader has run (it read at 1.5 s
    or 5.0 s, whichever thread took the clock's lock first: the start of in-process runs raced)."""
    for _ in range(50):
        clock = ModelClock()
        reply, seen = threading.Event(), []

        def reader():
            clock.wait(reply, 10.0)
            seen.append(clock.now())
            clock.notify()  # ending: the main thread need not wait a stall out to see it gone

        clock.call_at(1.0, reply.set)
        t = threading.Thread(target=reader)
        clock.enlist(threading.current_thread())  # the main thread: the clock's other participant
        clock.enlist(t)
        t.start()
        clock.sleep(5.0)
        t.join(5.0)
        assert seen == [1.0]

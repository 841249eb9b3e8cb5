"""The page's event stream at the end of a test, with the test thread held at the two moments
that a loaded machine can stretch: between the procedure's end and the runner taking its
outcome (the rig being released), and between the runner's last state and the thread's end.

A page told that the test is done (or faulted) must have the test's outcome with it; before
the fix the stream said "done" with the outcome still empty, and the page's outcome line
stayed blank for good under load.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import threading

import pytest

pytest.importorskip("starlette", reason="starlette is not installed (pip install -e .[test])")

import flowcurve.acquisition.session as session  # noqa: E402
from flowcurve.console.live_state import ENDED_STATES, ConsoleView  # noqa: E402
from flowcurve.console.runner import OPERATOR_STOP  # noqa: E402
from flowcurve.console.server import Console, _event_stream  # noqa: E402
from flowcurve.console.setup_form import validate  # noqa: E402

RUN_STATES = ("starting", "heating", "soaking", "tare", "waiting", "recording")
HOLD_BOUND_S = 30.0  # a bound for a hung test, not a speed check
TEST_THREAD_PREFIX = "flowcurve-console-test"


class StillConnected:
    """The request as the stream sees it: a page that stays."""

    async def is_disconnected(self) -> bool:
        return False


def _parse(chunk: bytes) -> tuple[str | None, dict | None]:
    event = data = None
    for line in chunk.decode().splitlines():
        if line.startswith("event: "):
            event = line[len("event: "):]
        elif line.startswith("data: "):
            data = json.loads(line[len("data: "):])
    return event, data


class Hold:
    """Stops the test thread at one point until the page has seen what it should see there."""

    def __init__(self, name: str):
        self.name = name
        self.reached = threading.Event()
        self.release = threading.Event()
        self.overran = False

    def __call__(self) -> None:
        if threading.current_thread().name.startswith(TEST_THREAD_PREFIX):
            self.reached.set()
            self.overran = not self.release.wait(HOLD_BOUND_S)


def test_a_page_told_the_test_ended_has_the_outcome_with_it_however_slow_the_end(tmp_path, monkeypatch):
    before_outcome = Hold("after the procedure, before the runner has its outcome")
    after_final_state = Hold("after the runner's last state, before the thread ends")

    real_run_virtual_test = session.run_virtual_test

    def slow_to_return(*args, **kwargs):  # the rig released slowly: the outcome comes late
        result = real_run_virtual_test(*args, **kwargs)
        before_outcome()
        return result

    real_set_state = ConsoleView.set_state

    def set_state_then_linger(self, state, message=""):  # the thread still alive after telling the pages
        real_set_state(self, state, message)
        if state in ENDED_STATES:
            after_final_state()

    monkeypatch.setattr(session, "run_virtual_test", slow_to_return)
    monkeypatch.setattr(ConsoleView, "set_state", set_state_then_linger)

    console = Console(tmp_path / "out", time_scale=60.0)
    run = console.runner.start(validate({"test": "compression", "specimen_id": "C-events"}, virtual=True, time_scale=60.0))

    async def page() -> tuple[list[str], dict | None, dict]:
        """Reads the stream as the page does, up to the first state that says the test ended."""
        states: list[str] = []
        last_test = None
        async with contextlib.aclosing(_event_stream(console, StillConnected())) as stream:
            async for chunk in stream:
                event, data = _parse(chunk)
                if event == "test":
                    last_test = data
                elif event == "status":
                    states.append(data["state"])
                    if data["state"] == "recording" and data["samples"] >= 20:
                        console.runner.stop()
                    if data["state"] not in RUN_STATES:
                        before_outcome.release.set()  # the page has been shown the procedure's end
                    if data["state"] in ENDED_STATES:
                        after_final_state.release.set()
                        return states, last_test, data
        raise AssertionError("the event stream ended")

    try:
        states, test_shown, final = asyncio.run(asyncio.wait_for(page(), 120))  # a bound for a hung stream
    finally:
        before_outcome.release.set()
        after_final_state.release.set()
        run.thread.join(60)
    assert not run.thread.is_alive()
    assert before_outcome.reached.is_set() and after_final_state.reached.is_set()
    assert not before_outcome.overran, "the page was not shown the procedure's end while the outcome was pending"
    assert "recording" in states and final["state"] == "complete"
    # what the page had been sent when it was told "complete": the finished test and its outcome
    assert test_shown is not None and test_shown["running"] is False, f"'complete' sent while the test still showed as running: {test_shown}"
    assert (test_shown["status"], test_shown["reason"]) == ("complete", OPERATOR_STOP), test_shown
    assert final["message"] == f"complete: {OPERATOR_STOP}"
    assert test_shown["samples"] == run.outcome.samples > 20

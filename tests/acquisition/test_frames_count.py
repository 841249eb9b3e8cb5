"""Issue 42: frames lost with no fault were counted four ways (header 'samples_missing: 3', the
events '4 so far', identify 'frames_missing, 3×' — events, not frames —, the operator's '1 frames
missing'). One count of frames, the same in the header, the events' last word, identify's warning
and the operator's line, with its plural right. The load cell's estimate may come down as later
frames arrive (it counts from the stream's timing): the scripted rig below does just that."""

import re

import pytest

from flowcurve.acquisition.live import LiveView
from flowcurve.acquisition.procedure import Procedure, TestSpec
from flowcurve.acquisition.stopping import StopCriteria
from flowcurve.identification.identify import fault_warnings
from flowcurve.record.format import read_record
from tests.acquisition.conftest import FakeRig


class LossyRig(FakeRig):
    """The load cell's estimate of its missing frames: ``counts`` as the crosshead passes 0.2,
    0.4, 0.6 mm, and ``final`` once the crosshead has stopped."""

    def __init__(self, counts, final, **kw):
        super().__init__(**kw)
        self.counts, self.final, self.stopped = counts, final, False

    @property
    def frames_lost(self) -> int:
        if self.stopped:
            return self.final
        x = abs(self.x(self.clock())) if self.clock else 0.0
        passed = sum(x >= at for at in (0.2, 0.4, 0.6)[: len(self.counts)])
        return self.counts[passed - 1] if passed else 0

    def stop_crosshead(self):
        super().stop_crosshead()
        self.stopped = True


class Told(LiveView):
    def __init__(self):
        super().__init__(quiet=True)
        self.alerts = []

    def alert(self, text):
        self.alerts.append(text)


def one_test(tmp_path, counts, final):
    rig = LossyRig(counts, final, x_frac_mm=5.0)
    view = Told()
    spec = TestSpec("tension", geometry_mm={"d0_mm": 6.0, "l0_mm": 30.0}, speed_mm_per_s=0.1, stop=StopCriteria(target_displacement_mm=0.8))
    out = Procedure(rig, spec, tmp_path / "t.csv", view=view).run()
    return read_record(out.path), view.alerts


@pytest.mark.parametrize("counts,final", [((1, 4), 3), ((1,), 1), ((2, 3), 3)])
def test_one_count_of_missing_frames_everywhere(tmp_path, counts, final):
    """Failed on the old code for (1, 4) → 3: header 3, the events '4 so far'; and for 1: '1 frames'."""
    rec, alerts = one_test(tmp_path, counts, final)
    header = int(rec.meta["samples_missing"])
    assert header == final
    events = [e.text for e in rec.events if e.name == "frames_missing"]
    last = re.search(r"\((\d+) so far|(\d+) frames? missing from its stream in all", events[-1])
    assert int(last.group(1) or last.group(2)) == header  # the events' last word is the header's count
    told = [a for a in alerts if "missing from its stream" in a]
    plural = "frame" if header == 1 else "frames"
    assert len(told) == 1 and f"load cell: {header} {plural} missing" in told[0]
    for text in events + told:
        assert not re.search(r"\b1 frames\b", text) and not re.search(r"\b([02-9]|\d\d+) frame\b", text)
    warnings, _ = fault_warnings(rec)
    named = [w for w in warnings if "frames_missing" in w]
    assert len(named) == 1 and f"(frames_missing, {header} {plural})" in named[0]  # frames, not events

"""What stops first at the end of a test. The matrix's compression at 20 C with a furnace dropping 5 % of
its replies (seed 150985987714739): the heater-off was retried for 9 s of model time while the crosshead
ran on, unrecorded, past its 3 mm target; hk came out 0.38 mm shorter than the rows say, K_l 1.17 and the
flow stress 14 % low inside a U of 18 MPa. A test that ends on its criterion stops the motion first; on a
device fault the heater still goes first (the failing device may be the drive)."""

import numpy as np

from flowcurve.acquisition.procedure import Procedure, TestSpec
from flowcurve.acquisition.stopping import StopCriteria
from flowcurve.record.format import read_record

from .conftest import FakeRig

SLOW_OFF_S = 0.4  # host s the heater-off takes (the furnace's retries): 8 s of model time at time scale 20


class SlowFurnaceRig(FakeRig):
    """A furnace whose heater-off takes :data:`SLOW_OFF_S`; each stop and heater-off logged in order."""

    def __init__(self, **kw):
        super().__init__(**kw)
        self.order = []

    def heater_off(self):
        self.order.append("heater_off")
        self.timebase.sleep(SLOW_OFF_S)
        super().heater_off()

    def stop_crosshead(self):
        self.order.append(("stop_crosshead", self.x(self.clock())))
        super().stop_crosshead()


def _compression(**kw) -> TestSpec:
    s = TestSpec(test="compression", material="fake", geometry_mm={"d0_mm": 10.0, "h0_mm": 15.0}, speed_mm_per_s=0.05, **kw)
    s.stop = StopCriteria(target_displacement_mm=0.5)
    return s


def test_a_target_stop_stops_the_crosshead_before_a_slow_heater_off(tmp_path):
    rig = SlowFurnaceRig(x_frac_mm=1e9)
    out = Procedure(rig, _compression(), tmp_path / "c.csv").run()
    assert "target displacement" in out.reason
    first_stop = next(i for i, o in enumerate(rig.order) if o[0] == "stop_crosshead")
    assert first_stop < rig.order.index("heater_off"), rig.order
    # where the crosshead stood is where the record ends: nothing ran on unrecorded
    stood = abs(rig.order[first_stop][1])
    last = abs(read_record(out.path).column("crosshead_mm")[-1])
    assert stood - last <= 3 * 0.05 * 0.05 * rig.time_scale, (stood, last)  # a loop tick or two of travel
    assert stood < 0.5 + 3 * 0.05 * 0.05 * rig.time_scale
    assert not rig.heater


def test_a_device_fault_switches_the_heater_off_first(tmp_path):
    rig = SlowFurnaceRig(x_frac_mm=1e9, die_after_s=4.0)
    out = Procedure(rig, _compression(), tmp_path / "u.csv").run()
    assert out.status == "aborted"
    assert rig.order[0] == "heater_off" and any(o[0] == "stop_crosshead" for o in rig.order[1:]), rig.order
    assert not rig.heater and np.isfinite(read_record(out.path).column("crosshead_mm")).any()

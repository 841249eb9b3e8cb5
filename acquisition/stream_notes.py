"""What the rig's streams met during a test, as record events and operator lines: readings
rejected as corrupt, frames missing from the load cell's stream, its latency and restarts, late
replies, retries and wrongly addressed replies; the data-loss summary and its header keys."""

from __future__ import annotations

from flowcurve.acquisition.sampler import Sampler

LOSS_NOISE_FRAMES = 5  # the load cell's lost frames are declared beyond this many ...
LOSS_NOISE_FRACTION = 0.005  # ... and this fraction (a loaded PC's scheduling; the count is an estimate)
LATENCY_NOTED_S = 0.01  # host seconds: a growth of the load cell's stream latency named as an event


def frames_text(n: int) -> str:
    """``'1 frame'``, ``'3 frames'``."""
    return f"{n} frame{'s' if n != 1 else ''}"


class StreamNotes:
    """The notes a :class:`~flowcurve.acquisition.procedure.Procedure` keeps of its streams (it
    provides ``rig``, ``writer``, ``_event``, ``_alert`` and the ``_*_noted`` counters)."""

    def _note_losses(self, sampler: Sampler, final: bool = False) -> None:
        """Events for what the channels rejected, the load cell's stream restarts and the late
        replies discarded since the last call; at the end one ``data_loss`` summary."""
        for ch in sampler.channels.values():
            if ch.guard is None:
                continue
            done = self._rejected_noted.get(ch.device, 0)
            for t, v, why in ch.guard.rejected[done:]:
                self._event("corrupt", f"{ch.device}: reading {v:.6g} at {t:.3f} s rejected as corrupt: {why}")
            self._rejected_noted[ch.device] = len(ch.guard.rejected)
        missing = getattr(self.rig, "frames_lost", 0)
        if missing > self._missing_noted:  # every gap the stream's timing shows, named (an event, not a failure)
            self._event("frames_missing", f"load cell: {frames_text(missing - self._missing_noted)} missing from its stream ({missing} so "
                                          "far, from the gaps in its timing: lost on the line, garbled, skipped, or late)")
            self._missing_noted = missing
        elif final and missing < self._missing_noted:  # the estimate came down as later frames arrived: the events say the count
            self._event("frames_missing", f"load cell: {frames_text(missing)} missing from its stream in all (the count revised from "
                                          f"{self._missing_noted} as later frames arrived)")
            self._missing_noted = missing
        lag = getattr(self.rig, "stream_latency_s", 0.0)
        if lag > self._latency_noted + LATENCY_NOTED_S:
            self._event("stream_latency", f"load cell: its frames arrive {lag:.3f} s (host) after they were sent, from here on; "
                                          "the force's step across the gap shows no frame lost: each is stamped at its send time")
            self._latency_noted = lag
        if final and self._latency_noted:
            self._alert(f"load cell: its stream arrived {self._latency_noted:.2f} s late from mid-test (the line delays it); "
                        "the force is stamped at its send time — check the cable or converter")
        undecided = getattr(self.rig, "stream_gaps_undecided", None) or []
        for t, doubt in undecided[self._undecided_noted:]:  # a gap neither rule could tell: the later forces' stamps in doubt
            self._event("stream_gap_undecided", f"load cell: a gap in its stream after {t:.3f} s could be lost frames or "
                                                f"the line's latency growing — stamped as lost, so every later force may be "
                                                f"stamped up to {doubt:.3f} s late against the crosshead")
        self._undecided_noted = len(undecided)
        in_doubt = getattr(self.rig, "stream_gaps_in_doubt", None) or []
        for t, doubt in in_doubt[getattr(self, "_in_doubt_noted", 0):]:  # the force within its noise there: identify judges the rest
            self._event("stream_gap_in_doubt", f"load cell: a gap in its stream after {t:.3f} s, across which the force stayed "
                                               f"within its noise, taken as lost frames; had it been the line's latency growing, "
                                               f"every later force is stamped up to {doubt:.3f} s late against the crosshead")
        self._in_doubt_noted = len(in_doubt)
        restarts = getattr(self.rig, "stream_restarts", 0)
        if restarts > self._restarts_noted:
            self._event("stream_restart", f"load cell: garbled stream restarted ({restarts - self._restarts_noted} more, {restarts} so far; frames lost meanwhile)")
            self._restarts_noted = restarts
        for device, late in (getattr(self.rig, "late_replies", None) or {}).items():
            if late > self._late_noted.get(device, 0):
                self._event("late_reply", f"{device}: {late - self._late_noted.get(device, 0)} late replies discarded ({late} so far)")
                self._late_noted[device] = late
        self._note_retries()
        if final and self._loss_summary():
            self._event("data_loss", self._loss_summary())
        elif final and self._missing_noted:  # below the data-loss limit: no failure, but the operator hears of it
            self._alert(f"load cell: {frames_text(self._missing_noted)} missing from its stream (the record's events name them; "
                        "below the data-loss limit) — check its cable if this recurs")

    def _note_retries(self, final: bool = False) -> None:
        """A ``retry`` event per device for the exchanges repeated since the last call after a
        silent, garbled or wrongly addressed reply — whether the retry got the reading, or failed
        too (the channel then counts a failed read); a ``wrong_address`` event per reply from
        another module's address; at the end one line to the operator per device that needed any."""
        self._note_wrong_addresses()
        failed_now = self._failed_after_retry()
        for device, retried in (getattr(self.rig, "retried_exchanges", None) or {}).items():
            if retried > self._retried_noted.get(device, 0):
                failed = failed_now.get(device, 0) - self._failed_noted.get(device, 0)
                outcome = (f"{failed} exchange{'s' if failed != 1 else ''} failed on every retry too: no reading taken from "
                           f"{'them' if failed != 1 else 'it'}" if failed > 0 else "the readings were taken on the retry")
                new = retried - self._retried_noted.get(device, 0)
                self._event("retry", f"{device}: {new} retr{'ies' if new != 1 else 'y'} after a silent, garbled or wrongly "
                                     f"addressed reply ({retried} so far; {outcome})")
                self._retried_noted[device] = retried
                self._failed_noted[device] = failed_now.get(device, 0)
        if final:
            for device, retried in self._retried_noted.items():
                failed = self._failed_noted.get(device, 0)
                lost = (f"{failed} exchange{'s' if failed != 1 else ''} failed on every retry too" if failed else "nothing lost")
                self._alert(f"{device}: {retried} retr{'ies' if retried != 1 else 'y'} after silent, garbled or wrongly "
                            f"addressed replies ({lost}) — check its cable and connector if this recurs")

    def _drivers(self) -> list:
        """The rig's devices that keep what their transport met (the drivers; none on a fake rig)."""
        devices = (getattr(self.rig, name, None) for name in ("loadcell", "encoder", "furnace"))
        return [d for d in devices if d is not None and hasattr(d, "transport")]

    def _failed_after_retry(self) -> dict[str, int]:
        return {d.name: getattr(d.transport, "failed_after_retry", 0) for d in self._drivers()}

    def _note_wrong_addresses(self) -> None:
        """A ``wrong_address`` event per reply that came from another module's address than the
        one asked (rig.transport.DconDevice.wrong_address_replies): the device, the command, the
        address that answered, and what became of it."""
        for dev in self._drivers():
            replies = getattr(dev, "wrong_address_replies", None) or []
            done = self._wrong_noted.get(dev.name, 0)
            first_command = not any(commanded for *_, commanded in replies[:done])
            for _, command, answered, commanded in replies[done:]:
                ours = f"{getattr(dev, 'address', 0):02X}"
                if commanded and first_command:
                    then = ("a heater command: no acknowledgement of this module is believed from here on, the heater is left "
                            "to the module's watchdog")
                    first_command = False
                else:
                    then = "a heater command, not believed" if commanded else "not taken; asked again"
                self._event("wrong_address", f"{dev.name}: reply to {command} from address {answered}, not {ours} — {then}")
            self._wrong_noted[dev.name] = len(replies)

    def _loss_summary(self) -> str:
        parts = []
        missing = self._missing_noted  # the one count of missing frames: the events', the header's, the operator's
        expected = (self.writer.rows_written if self.writer else 0) + missing
        if self._restarts_noted or missing > max(LOSS_NOISE_FRAMES, LOSS_NOISE_FRACTION * expected):
            restarts = f"{self._restarts_noted} stream restarts; " if self._restarts_noted else ""
            parts.append(f"load cell: {restarts}{missing} of {expected} force samples lost "
                         f"({100.0 * missing / max(expected, 1):.1f} %)")
        rejected = [f"{device}: {n} reading{'s' if n != 1 else ''} rejected as corrupt" for device, n in self._rejected_noted.items() if n]
        if rejected:  # each device by name: the operator's warning says where to look
            parts.append("; ".join(rejected))
        if self._dropped:
            parts.append(f"{self._dropped} force samples after the fault left out")
        if getattr(self, "_undecided_noted", 0):
            parts.append(f"load cell: {self._undecided_noted} stream gap(s) that could be lost frames or latency: the forces after "
                         "them may be misaligned against the crosshead by up to the gap")
        return "; ".join(parts)

    def _loss_meta(self) -> dict[str, object]:
        """Header keys: the load cell's lost samples whenever any (an estimate: below the noise
        limit no data_loss event and no exit 5), and the whole summary when there is one."""
        missing = self._missing_noted
        meta: dict[str, object] = {"samples_missing": missing} if missing else {}
        if self._loss_summary():
            meta.update({"samples_missing": missing, "stream_restarts": self._restarts_noted,
                         "readings_rejected": sum(self._rejected_noted.values()), "data_loss": self._loss_summary()})
        return meta

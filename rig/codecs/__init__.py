"""Pure encode/decode functions for the rig's serial protocols (no I/O here).

* :mod:`rig.codecs.aed` — HBM AED command set of the load-cell amplifier;
* :mod:`rig.codecs.dcon` — ICP DAS DCON ASCII protocol (furnace module, encoder box framing);
* :mod:`rig.codecs.encoder` — the crosshead encoder box (docs/encoder-protocol.md).

Decoders raise :class:`ProtocolError` on a malformed reply; the drivers turn it into a
:class:`~flowcurve.errors.DeviceError` that names the device.
"""

from __future__ import annotations


class ProtocolError(ValueError):
    """A reply that does not follow the protocol (garbled, wrong length, bad checksum)."""

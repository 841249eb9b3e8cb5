"""Virtual twins of the rig's devices on pseudo-terminals (real time) or in-process as
``virtual://`` ports (on any :mod:`flowcurve.clock`, e.g. model time in the fast tests),
driven by :mod:`flowcurve.rig.virtual.physics`.

:class:`rig.virtual.rig.VirtualRig` starts all three; the devices can also run alone
(:class:`~rig.virtual.aed.AEDAmplifier`, :class:`~rig.virtual.dcon.I7011`,
:class:`~rig.virtual.encoder_box.EncoderBox`).
"""

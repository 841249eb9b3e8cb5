"""Virtual twins of the rig's devices on pseudo-terminals, driven by :mod:`flowcurve.rig.virtual.physics`.

:class:`rig.virtual.rig.VirtualRig` starts all three; the devices can also run alone
(:class:`~rig.virtual.aed.AEDAmplifier`, :class:`~rig.virtual.dcon.I7011`,
:class:`~rig.virtual.encoder_box.EncoderBox`).
"""

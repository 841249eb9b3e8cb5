"""Which physics the virtual rig's specimen follows after yield: names only, no numerics.

Light on purpose: the CLI builds its ``--compression-response`` / ``--tension-response``
options from these without importing numpy or scipy (``flowcurve --help`` stays fast);
:mod:`flowcurve.rig.virtual.physics` checks its arguments against the same names.
"""

COMPRESSION_RESPONSES = ("fe", "slab")  # FE runs (default) / slab factor and (3.18), the analytic mirror
TENSION_RESPONSES = ("fe", "bridgman")  # FE necking runs (default) / Bridgman with Le Roy's a/R, the analytic mirror

COMPRESSION_HELP = ("virtual rig's compression response: fe (default) = force factor and barrel from CalculiX upsetting "
                    "runs, independent of the identification's formulas; slab = the slab friction factor and the seed's "
                    "barrel regression (3.18), the analytic mirror of the identification")
TENSION_HELP = ("virtual rig's tension neck: fe (default) = force, elongation and neck shape from CalculiX necking runs, "
                "independent of the identification's formulas; bridgman = Bridgman's factor with Le Roy's a/R, the "
                "analytic mirror of the identification's neck corrections")


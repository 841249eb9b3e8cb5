"""flowcurve: tension and compression tests from rig to material card."""

__version__ = "0.1.0"

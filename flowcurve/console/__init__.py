"""The operator's console: ``flowcurve console`` serves a local web page that sets up, runs,
watches and evaluates tests on the same acquisition code as ``flowcurve run``."""

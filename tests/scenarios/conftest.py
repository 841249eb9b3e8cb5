"""The scenario matrix's seed, printed at the end of every run."""

from .matrix import matrix_seed


def pytest_terminal_summary(terminalreporter):
    terminalreporter.write_line(f"scenario matrix: seed {matrix_seed()} (FLOWCURVE_MATRIX_SEED=<seed> draws the same cells; "
                                "FLOWCURVE_MATRIX_CELLS=<cell id>,... runs those cells)")

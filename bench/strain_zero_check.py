"""The strain zero's actual error |toe − 0.02 mm|/h0 (the generator's seating toe closes at 0.02 mm) against its
stated δε0 and its parts, and A's shift under εp + δε0, on the coverage campaign's 36 closed-form compression
records (docs/methods.md §2.11). Run: PYTHONPATH=. python bench/strain_zero_check.py"""

import warnings

import numpy as np

from flowcurve.identification.compression.identify import identify_compression
from tests.coverage import campaign as cp
from tests.series import compression_series as cs


def main() -> None:
    ratios, stated, shifts = [], [], []
    for case in cp.compression_cases():
        T, rate, mu, seed = case.make.args
        record, _ = cs.compression_record(T, rate, mu=mu, seed=seed, response=cp.COMPRESSION_RESPONSE, reading_mm=0.01)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = identify_compression(record).result
        start = result["hardening"]["start_uncertainty"]
        actual = abs(result["indicator"]["toe_compensation_mm"] - 0.02) / cs.H0_MM
        ratios.append(actual / start["delta_eps0"]), stated.append(start["delta_eps0"]), shifts.append(start["constants_shift"].get("A", 0.0))
        parts = " ".join(f"{k} {v:.1e}" for k, v in start["components"].items())
        print(f"{case.name:28s} |error| {actual:.2e}  δε0 {start['delta_eps0']:.2e} ({ratios[-1]:.2f})  A shift {shifts[-1]:.3g} MPa  {parts}")
    print(f"|error|/δε0 {min(ratios):.2f}–{max(ratios):.2f} (median {np.median(ratios):.2f}); largest δε0 {max(stated):.2e}; A shift at most {max(shifts):.3g} MPa")


if __name__ == "__main__":
    main()

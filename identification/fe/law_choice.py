"""The hardening law an inverse FE fit uses when none is given: the one that best follows a curve.

Both inverses (compression, :mod:`.inverse`; tension, :mod:`.inverse_tension`) choose with it, so
neither imports the other.
"""

from __future__ import annotations

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.hardening import LAWS, fit_hardening


def best_law_for(true_curve) -> tuple[str, dict[str, float]]:
    """(law, {law: RMS error %}): the hardening law of :data:`LAWS` whose fit to the fast curve
    has the smallest RMS error. The inverse can only be as good as its law: Johnson–Cook on a
    saturating (Voce) material's record left a force misfit of 1.9 % RMS and the curve 3.6 % off.
    ``true_curve``: a frame with ``true_plastic_strain`` and ``true_stress_MPa``."""
    e, s = true_curve["true_plastic_strain"].to_numpy(), true_curve["true_stress_MPa"].to_numpy()
    rms = {}
    for name in LAWS:
        try:
            rms[name] = float(fit_hardening(e, s, name).rms_error_pct)
        except IdentificationError:
            continue
    if not rms:
        raise IdentificationError("inverse FE: no hardening law fits the fast identification's curve")
    return min(rms, key=rms.get), rms


def check_law(law: str) -> None:
    """An :class:`IdentificationError` unless ``law`` is one of :data:`LAWS` or ``auto``."""
    if law not in LAWS and law != "auto":
        raise IdentificationError(f"unknown hardening law {law!r}; choose one of {', '.join(LAWS)} or auto")

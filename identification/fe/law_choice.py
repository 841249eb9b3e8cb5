"""The hardening law an inverse FE fit uses when none is given: the one that best follows a curve.

Both inverses (compression, :mod:`.inverse`; tension, :mod:`.inverse_tension`) choose with it, so
neither imports the other.
"""

from __future__ import annotations

from flowcurve.errors import IdentificationError
from flowcurve.identification.laws.hardening import fit_hardening, static_form, static_law_names

# the laws 'auto' chooses among (the inverse's guarded numbers were made with these three)
AUTO_LAWS = ("johnson_cook", "swift", "voce")


def best_law_for(true_curve) -> tuple[str, dict[str, float]]:
    """(law, {law: RMS error %}): the hardening law of :data:`AUTO_LAWS` whose fit to the fast curve
    has the smallest RMS error. The inverse can only be as good as its law: Johnson–Cook on a
    saturating (Voce) material's record left a force misfit of 1.9 % RMS and the curve 3.6 % off.
    ``true_curve``: a frame with ``true_plastic_strain`` and ``true_stress_MPa``."""
    e, s = true_curve["true_plastic_strain"].to_numpy(), true_curve["true_stress_MPa"].to_numpy()
    rms = {}
    for name in AUTO_LAWS:
        try:
            rms[name] = float(fit_hardening(e, s, name).rms_error_pct)
        except IdentificationError:
            continue
    if not rms:
        raise IdentificationError("inverse FE: no hardening law fits the fast identification's curve")
    return min(rms, key=rms.get), rms


def check_law(law: str) -> None:
    """An :class:`IdentificationError` unless ``law`` is a law one record can identify
    (:func:`.hardening.static_law_names`) or ``auto``."""
    if law != "auto":
        try:
            static_form(law)
        except IdentificationError as exc:
            raise IdentificationError(f"{exc} (inverse FE: one of {', '.join(static_law_names())} or auto)") from None

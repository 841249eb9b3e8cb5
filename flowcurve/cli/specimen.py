"""The specimen options of ``flowcurve run`` and ``flowcurve identify``, declared once.

``--d0``/``--l0``/``--lc``/``--h0`` give the specimen's initial geometry in mm (the record keys
``specimen.*_mm``; ``--lc`` is ``specimen.parallel_length_mm``), ``--E`` the material's elastic
modulus in MPa. Each command says in one
sentence what it does with the modulus; the names, units, types and the check of the values
are the same everywhere.
"""

from __future__ import annotations

# option (without --) → (record metadata key, help)
GEOMETRY_OPTIONS = {
    "d0": ("specimen.d0_mm", "initial specimen diameter, mm"),
    "l0": ("specimen.l0_mm", "initial gauge length (tension), mm"),
    "lc": ("specimen.parallel_length_mm", "parallel length Lc (tension), mm: the length the crosshead's strain refers to; "
           "default l0 (ISO 6892-1 round bars: Lc ≥ l0 + d0/2, usually l0 + 2·d0; ignored for compression)"),
    "h0": ("specimen.h0_mm", "initial specimen height (compression), mm"),
}
MODULUS_OPTION, MODULUS_DEST = "--E", "E_MPa"


def add_geometry_options(target) -> None:
    """--d0, --l0, --lc, --h0 (mm) on a parser or an argument group."""
    for option, (_, help_text) in GEOMETRY_OPTIONS.items():
        target.add_argument(f"--{option}", type=float, metavar="MM", help=help_text)


def add_modulus_option(target, use: str) -> None:
    """--E (MPa) on a parser or an argument group; ``use`` says what the command does with it."""
    target.add_argument(MODULUS_OPTION, dest=MODULUS_DEST, type=float, metavar="MPA",
                        help=f"elastic modulus of the material, MPa: {use}")


def measurement(option: str, value: float) -> float:
    """A number option (dimension, speed, stiffness, modulus): finite, > 0, not an overflow.

    ``option`` is the option's name without dashes; the one-line error (a FieldError) names it.
    """
    from flowcurve.services import measured

    return measured(option, f"--{option.replace('_', '-')}", value)


def check_specimen_options(args) -> None:
    """A given geometry or modulus must be a finite positive number, and a given --lc at least the
    given --l0 (one-line error naming the option)."""
    for option, dest in [(o, o) for o in GEOMETRY_OPTIONS] + [(MODULUS_OPTION[2:], MODULUS_DEST)]:
        value = getattr(args, dest, None)
        if value is not None:
            measurement(option, value)
    from flowcurve.services import FieldError, parallel_length_refusal

    refusal = parallel_length_refusal(getattr(args, "lc", None), getattr(args, "l0", None))
    if refusal:
        raise FieldError("lc", refusal)


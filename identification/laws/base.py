"""Constitutive laws as objects: a :class:`Law` is a flow stress σ(εp[, ε̇, T]) with named,
bounded, unit-carrying parameters, a start-value guess from the data and its equation — in the
manner of lmfit's ``Model``. Each law lives in one module of this package and registers itself
with :func:`register`; :func:`get_law` and :func:`registered_laws` find every law without a list
to edit (adding a law is one file; docs/extending.md).

Conventions every law keeps: strain is true plastic strain (εp ≥ 0), strain rate in 1/s,
temperature in °C at the interface (a law written in kelvin converts inside), stress in MPa.
"""

from __future__ import annotations

import importlib
import pkgutil
from dataclasses import dataclass
from typing import ClassVar, Mapping

import numpy as np

from flowcurve.errors import IdentificationError

KELVIN_OFFSET = 273.15


@dataclass(frozen=True)
class Parameter:
    """One named constant of a law.

    Attributes
    ----------
    name : str
        The symbol in the equation (``A``).
    key : str
        The JSON key with its unit (``A_MPa``).
    unit : str
        The unit as printed ("" for a pure number).
    lower, upper : float
        The bounds a fit keeps.
    meaning : str
        One line for the docs and reports.
    """

    name: str
    key: str
    unit: str = ""
    lower: float = -np.inf
    upper: float = np.inf
    meaning: str = ""

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies within the bounds (inclusive)."""
        return self.lower <= value <= self.upper


class Law:
    """A constitutive law σ(εp, ε̇, T) in MPa with named parameters.

    Subclasses set the class attributes and implement :meth:`evaluate` and :meth:`guess`.

    Attributes
    ----------
    name : registry key (``johnson_cook``), as given to ``--law``.
    display_name : as printed (``Johnson–Cook``).
    parameters : the fitted constants, in the order of the equation.
    conditions : stated inputs that are never fitted (e.g. Johnson–Cook's reference rate,
        reference and melt temperatures), with their keys and units.
    rate_dependent, temperature_dependent : whether σ depends on ε̇ and on T.
    equation : the equation in plain text; latex : the same for docs/methods.md.
    source : the literature it comes from.
    """

    name: ClassVar[str] = ""
    display_name: ClassVar[str] = ""
    parameters: ClassVar[tuple[Parameter, ...]] = ()
    conditions: ClassVar[tuple[Parameter, ...]] = ()
    rate_dependent: ClassVar[bool] = False
    temperature_dependent: ClassVar[bool] = False
    equation: ClassVar[str] = ""
    latex: ClassVar[str] = ""
    source: ClassVar[str] = ""

    # -- to implement -------------------------------------------------------------------

    def evaluate(self, eps_p: np.ndarray, strain_rate_per_s: np.ndarray, temperature_C: np.ndarray,
                 **values: float) -> np.ndarray:
        """σ (MPa) at arrays of εp, ε̇ (1/s), T (°C) already broadcast; ``values`` holds every
        parameter and condition by name."""
        raise NotImplementedError

    def guess(self, eps_p, stress_MPa, strain_rate_per_s=None, temperature_C=None, **conditions: float) -> dict[str, float]:
        """Start values for a fit, from the data (and the stated conditions)."""
        raise NotImplementedError

    # -- provided -----------------------------------------------------------------------

    @property
    def names(self) -> tuple[str, ...]:
        """The fitted parameters' names, in order."""
        return tuple(p.name for p in self.parameters)

    def parameter(self, name: str) -> Parameter:
        """The :class:`Parameter` called ``name`` (fitted or condition)."""
        for p in self.parameters + self.conditions:
            if p.name == name:
                return p
        raise KeyError(f"{self.name} has no parameter {name!r}")

    def stress(self, eps_p, strain_rate_per_s=None, temperature_C=None, **values: float) -> np.ndarray:
        """The law's flow stress σ(εp, ε̇, T), broadcast over the arrays.

        Parameters
        ----------
        eps_p : array_like
            True plastic strain (clipped at 0).
        strain_rate_per_s, temperature_C : array_like, optional
            Strain rate, 1/s, and temperature, °C; required when the law depends on them.
        **values : float
            The law's constants by name (:attr:`names`) and its conditions.

        Returns
        -------
        ndarray
            σ, MPa.

        Raises
        ------
        IdentificationError
            A constant, condition, rate or temperature the law needs not given.
        """
        missing = [p.name for p in self.parameters + self.conditions if p.name not in values]
        if missing:
            raise IdentificationError(f"{self.display_name}: no value for {', '.join(missing)}")
        if self.rate_dependent and strain_rate_per_s is None:
            raise IdentificationError(f"{self.display_name} depends on the strain rate: give strain_rate_per_s")
        if self.temperature_dependent and temperature_C is None:
            raise IdentificationError(f"{self.display_name} depends on the temperature: give temperature_C")
        eps = np.clip(np.asarray(eps_p, dtype=float), 0.0, None)
        rate = np.asarray(np.nan if strain_rate_per_s is None else strain_rate_per_s, dtype=float)
        temp = np.asarray(np.nan if temperature_C is None else temperature_C, dtype=float)
        eps, rate, temp = np.broadcast_arrays(eps, rate, temp)
        return self.evaluate(eps, rate, temp, **values)

    def check(self, values: Mapping[str, float]) -> None:
        """An :class:`IdentificationError` naming the first value outside its bounds."""
        for p in self.parameters:
            v = values.get(p.name)
            if v is not None and not p.contains(float(v)):
                raise IdentificationError(f"{self.display_name}: {p.name} = {v:g} is outside [{p.lower:g}, {p.upper:g}]")

    def to_keys(self, values: Mapping[str, float]) -> dict[str, float]:
        """Values by name → the same by unit-carrying JSON key (parameters, then conditions)."""
        return {p.key: float(values[p.name]) for p in self.parameters + self.conditions if p.name in values}

    def from_keys(self, block: Mapping[str, float]) -> dict[str, float]:
        """The inverse of :meth:`to_keys`: a JSON block → values by name (unknown keys ignored)."""
        return {p.name: float(block[p.key]) for p in self.parameters + self.conditions if p.key in block}

    def __repr__(self) -> str:
        return f"<Law {self.name}: {self.equation}>"


_REGISTRY: dict[str, Law] = {}
_DISCOVERED = False


def register(cls: type[Law]) -> type[Law]:
    """Class decorator: put one instance of the law in the registry under ``cls.name``.

    Parameters
    ----------
    cls : type
        A :class:`Law` subclass.

    Returns
    -------
    type
        ``cls``, unchanged.
    """
    if not cls.name:
        raise ValueError(f"{cls.__name__} has no name")
    if cls.name in _REGISTRY and type(_REGISTRY[cls.name]) is not cls:
        raise ValueError(f"two laws are called {cls.name!r}")
    _REGISTRY[cls.name] = cls()
    return cls


def _discover() -> None:
    """Import every module of this package once, so each law's ``@register`` runs."""
    global _DISCOVERED
    if _DISCOVERED:
        return
    _DISCOVERED = True
    package = importlib.import_module(__package__)
    for info in pkgutil.iter_modules(package.__path__):
        importlib.import_module(f"{__package__}.{info.name}")


def registered_laws() -> dict[str, Law]:
    """Every registered law by name.

    Returns
    -------
    dict of str to Law
        In registration order.
    """
    _discover()
    return dict(_REGISTRY)


def get_law(name: str) -> Law:
    """The registered law called ``name``.

    Parameters
    ----------
    name : str
        A registry key (``johnson_cook``).

    Returns
    -------
    Law
        The law's instance.

    Raises
    ------
    IdentificationError
        One line with the nearest names when there is none.
    """
    laws = registered_laws()
    try:
        return laws[name]
    except KeyError:
        import difflib
        near = difflib.get_close_matches(name, list(laws), n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise IdentificationError(f"unknown law {name!r}{hint}; registered: {', '.join(laws)}") from None


def display_name_of(name: str) -> str:
    """A law's display name for reports and plots (``johnson_cook`` → ``Johnson–Cook``); an
    unregistered name in words."""
    law = registered_laws().get(name)
    return law.display_name if law is not None else (name or "").replace("_", " ")


def constant_keys(name: str) -> list[tuple[str, str, str]]:
    """(symbol, JSON key, unit) of a law's fitted constants as one record's result carries them
    (Johnson–Cook's static part A, B, n on one record); [] for an unknown law."""
    law = registered_laws().get(name)
    if law is None:
        return []
    params = law.parameters[:3] if name == "johnson_cook" else law.parameters
    return [(p.name, p.key, p.unit) for p in params]

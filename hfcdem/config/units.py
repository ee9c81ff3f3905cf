"""Quantities with explicit units, as scene files write them ("33.44 mm", "60 deg").

Every dimensional value a user types carries its unit; :func:`parse_quantity`
turns it into SI (m, rad, Pa, s, m3/s, Pa s, kg/m3) and refuses plain numbers,
unknown units and units of the wrong kind, naming the field (a dotted path such
as ``geometry.wellbore.diameter``) in the error.
"""

from __future__ import annotations

import math
import re
from typing import Any

# unit -> factor to SI, per dimension; spellings are case-sensitive (mm vs Mm)
UNITS: dict[str, dict[str, float]] = {
    "length": {
        "m": 1.0,
        "cm": 1e-2,
        "mm": 1e-3,
        "um": 1e-6,
        "nm": 1e-9,  # tight joints' apertures
        "km": 1e3,
        "in": 0.0254,
        "ft": 0.3048,
    },
    "angle": {"deg": math.pi / 180.0, "rad": 1.0},
    "stress": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "psi": 6894.757293168},
    "time": {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0},
    "flow_rate": {
        "m3/s": 1.0,
        "m3/min": 1.0 / 60.0,
        "L/s": 1e-3,
        "L/min": 1e-3 / 60.0,
        "mL/min": 1e-6 / 60.0,
        "bbl/min": 0.158987294928 / 60.0,
    },
    "volume": {"m3": 1.0, "L": 1e-3, "cm3": 1e-6, "mL": 1e-6, "bbl": 0.158987294928},
    "viscosity": {"Pa.s": 1.0, "mPa.s": 1e-3, "cP": 1e-3},
    "density": {"kg/m3": 1.0, "g/cm3": 1e3},
    "pressure_rate": {
        "Pa/s": 1.0,
        "kPa/s": 1e3,
        "MPa/s": 1e6,
        "GPa/s": 1e9,
        "MPa/min": 1e6 / 60.0,
        "psi/min": 6894.757293168 / 60.0,
    },
}

EXAMPLES = {
    "length": "70 mm",
    "angle": "60 deg",
    "stress": "38 MPa",
    "time": "60 s",
    "flow_rate": "1e-7 m3/s",
    "volume": "0.5 L",
    "viscosity": "1 mPa.s",
    "density": "1000 kg/m3",
    "pressure_rate": "1 MPa/s",
}

# other spellings people type; mapped before lookup
_ALIASES = {
    "m^3/s": "m3/s",
    "m³/s": "m3/s",
    "m^3/min": "m3/min",
    "m³/min": "m3/min",
    "l/s": "L/s",
    "l/min": "L/min",
    "µm": "um",
    "°": "deg",
    "degree": "deg",
    "degrees": "deg",
    "Pa s": "Pa.s",
    "Pa·s": "Pa.s",
    "mPa s": "mPa.s",
    "mPa·s": "mPa.s",
    "kg/m^3": "kg/m3",
    "kg/m³": "kg/m3",
    "g/cm^3": "g/cm3",
    "g/cm³": "g/cm3",
    "sec": "s",
}

_QUANTITY = re.compile(
    r"^\s*(?P<number>[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?)\s*(?P<unit>\S.*?)?\s*$"
)


class FieldError(ValueError):
    """A value of a named input field is wrong; ``path`` names the field (dotted)."""

    def __init__(self, path: str, reason: str) -> None:
        self.path = path
        self.reason = reason
        super().__init__(f"{path}: {reason}" if path else reason)

    def within(self, prefix: str) -> FieldError:
        """Return the same error with ``prefix`` prepended to its path."""
        return type(self)(join_path(prefix, self.path), self.reason)


class UnitError(FieldError):
    """A quantity is missing its unit, has an unknown one, or one of the wrong kind."""


def join_path(prefix: str, path: str) -> str:
    """Join dotted field paths: ``join_path("geometry", "block.size")``; indices stay glued."""
    if not prefix:
        return path
    if not path:
        return prefix
    return f"{prefix}{path}" if path.startswith("[") else f"{prefix}.{path}"


def _article(word: str) -> str:
    return "an" if word[0] in "aeiou" else "a"


def _describe(value: Any) -> str:
    return repr(value) if isinstance(value, str) else str(value)


def _dimension_of(unit: str) -> str | None:
    for dim, table in UNITS.items():
        if unit in table:
            return dim
    return None


def parse_quantity(value: Any, dimension: str, path: str = "") -> float:
    """Return the SI value of ``value`` (a string such as ``"33.44 mm"``) of kind ``dimension``.

    Raises :class:`UnitError` naming ``path`` for plain numbers, unknown units,
    units of another kind and non-finite numbers.
    """
    if dimension not in UNITS:
        raise ValueError(f"unknown dimension {dimension!r}; known: {', '.join(UNITS)}")
    what = dimension.replace("_", " ")
    expected = f"expected {_article(what)} {what} such as '{EXAMPLES[dimension]}'"
    if not isinstance(value, str):
        raise UnitError(path, f"{expected}, got {_describe(value)}")
    match = _QUANTITY.match(value)
    if match is None:
        raise UnitError(path, f"{expected}, got {_describe(value)}")
    unit = match.group("unit")
    if not unit:
        raise UnitError(path, f"{expected}, got {_describe(value)} (no unit)")
    unit = _ALIASES.get(unit, unit)
    table = UNITS[dimension]
    if unit not in table:
        other = _dimension_of(unit)
        if other is not None:
            what_else = other.replace("_", " ")
            reason = f"{expected}, got {_describe(value)} ({_article(what_else)} {what_else})"
        else:
            reason = (
                f"{expected}, got {_describe(value)}: unknown unit {unit!r} "
                f"(use one of {', '.join(table)})"
            )
        raise UnitError(path, reason)
    number = float(match.group("number"))
    result = number * table[unit]
    if not math.isfinite(result):
        raise UnitError(path, f"{expected}, got {_describe(value)} (not finite)")
    return result


def format_quantity(value: float, unit: str, digits: int = 4) -> str:
    """Format an SI ``value`` in ``unit``: ``format_quantity(0.03486, "mm") == "34.86 mm"``."""
    dim = _dimension_of(unit)
    if dim is None:
        raise ValueError(f"unknown unit {unit!r}")
    return f"{value / UNITS[dim][unit]:.{digits}g} {unit}"


def show_stress(value: float) -> str:
    """Say a stress in Pa the way a scene would write it: ``show_stress(-5e6) == "-5 MPa"``."""
    if not math.isfinite(value):
        return f"{value!r} Pa"
    for unit, factor in (("GPa", 1e9), ("MPa", 1e6), ("kPa", 1e3)):
        if abs(value) >= factor:
            return f"{value / factor:.4g} {unit}"
    return f"{value:.4g} Pa"


__all__ = [
    "EXAMPLES",
    "UNITS",
    "FieldError",
    "UnitError",
    "format_quantity",
    "join_path",
    "parse_quantity",
    "show_stress",
]

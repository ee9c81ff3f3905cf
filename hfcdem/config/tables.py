"""Reading TOML tables: typed getters whose errors name the field, and SceneError.

The scene reader (:mod:`hfcdem.config.scene`) and the physics reader
(:mod:`hfcdem.config.physics`) both read through :class:`TomlTable`; they share
this module so that neither imports the other for it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

from hfcdem.config.units import EXAMPLES, FieldError, join_path, parse_quantity

MISSING: Any = object()  # "no default": a missing key is an error
T = TypeVar("T")


class SceneError(FieldError):
    """A scene is invalid; ``path`` names the offending field."""


class SceneErrors(SceneError):
    """Several sections of a scene are invalid: ``errors``, one line each when said."""

    def __init__(self, errors: Sequence[FieldError]) -> None:
        self.errors = tuple(SceneError(e.path, e.reason) for e in errors)
        lines = "\n".join(f"  {e}" for e in self.errors)
        super().__init__("", f"{len(self.errors)} sections have an error:\n{lines}")

    def within(self, prefix: str) -> SceneErrors:
        """Return the same errors with ``prefix`` prepended to each path."""
        return SceneErrors([e.within(prefix) for e in self.errors])

    @staticmethod
    def raise_any(errors: Sequence[FieldError]) -> None:
        """Raise nothing, the one error as a SceneError, or all of them together."""
        found = [e for group in errors for e in getattr(group, "errors", (group,))]
        if len(found) == 1:
            raise SceneError(found[0].path, found[0].reason)
        if found:
            raise SceneErrors(found)


class TomlTable:
    """One TOML table being read: typed getters that name fields, and unknown-key checks."""

    def __init__(self, data: Any, path: str) -> None:
        if not isinstance(data, Mapping):
            raise SceneError(path, f"expected a table, got {data!r}")
        self.data = dict(data)
        self.path = path
        self.used: set[str] = set()
        self.asked: set[str] = set()  # keys looked for, given or not: what the table takes

    def sub(self, key: str) -> str:
        """Return the dotted path of ``key`` in this table."""
        return join_path(self.path, key)

    def has(self, key: str) -> bool:
        """Tell whether the table gives ``key``."""
        self.asked.add(key)
        return key in self.data

    def raw(self, key: str, default: Any = MISSING, expected: str = "a value") -> Any:
        """Return ``key`` as read (``default`` if absent), marked as used."""
        self.used.add(key)
        if key in self.data:
            return self.data[key]
        if default is MISSING:
            raise SceneError(self.sub(key), f"missing; expected {expected}")
        return default

    def quantity(self, key: str, dimension: str, default: Any = MISSING) -> Any:
        """Read a quantity with a unit of ``dimension``, in SI."""
        value = self.raw(key, default, f"a {dimension} such as '{EXAMPLES[dimension]}'")
        if value is default and default is not MISSING:
            return default
        return parse_quantity(value, dimension, self.sub(key))

    def quantities(self, key: str, dimension: str, default: Any = MISSING) -> Any:
        """Read a list of quantities of ``dimension``, in SI, as a tuple."""
        value = self.raw(key, default, f"a list of {dimension}s")
        if value is default and default is not MISSING:
            return default
        if not isinstance(value, list):
            raise SceneError(self.sub(key), f"expected a list of {dimension}s, got {value!r}")
        return tuple(
            parse_quantity(v, dimension, f"{self.sub(key)}[{i}]") for i, v in enumerate(value)
        )

    def number(self, key: str, default: Any = MISSING, integer: bool = False) -> Any:
        """Read a plain number (no unit); ``integer`` refuses a fraction."""
        what = "an integer" if integer else "a number"
        value = self.raw(key, default, what)
        if value is default and default is not MISSING:
            return default
        ok = isinstance(value, int) if integer else isinstance(value, int | float)
        if isinstance(value, bool) or not ok:
            raise SceneError(self.sub(key), f"expected {what} (no unit), got {value!r}")
        return value

    def string(self, key: str, default: Any = MISSING, choices: Sequence[str] = ()) -> Any:
        """Read a string, one of ``choices`` when they are given."""
        value = self.raw(key, default, "a string")
        if value is default and default is not MISSING:
            return default
        if not isinstance(value, str):
            raise SceneError(self.sub(key), f"expected a string, got {value!r}")
        if choices and value not in choices:
            raise SceneError(
                self.sub(key), f"expected one of {', '.join(map(repr, choices))}, got {value!r}"
            )
        return value

    def table(self, key: str) -> TomlTable | None:
        """Return the sub-table ``key``, or None if absent."""
        value = self.raw(key, None)
        return None if value is None else TomlTable(value, self.sub(key))

    def tables(self, key: str) -> list[TomlTable]:
        """Return the array of tables ``key`` (empty if absent)."""
        value = self.raw(key, [])
        if not isinstance(value, list):
            raise SceneError(self.sub(key), f"expected an array of tables, got {value!r}")
        return [TomlTable(v, f"{self.sub(key)}[{i}]") for i, v in enumerate(value)]

    def finish(self, extra: Sequence[str] = ()) -> None:
        """Refuse any key not read (nor listed in ``extra``)."""
        unknown = sorted(set(self.data) - self.used - set(extra))
        if unknown:
            known = ", ".join(sorted(self.used | self.asked | set(extra)))
            raise SceneError(self.sub(unknown[0]), f"unknown key; this table takes: {known}")


def build_within(path: str, make: Callable[..., T], *args: Any, **kwargs: Any) -> T:
    """Call ``make`` and prefix the field path of any validation error with ``path``."""
    try:
        return make(*args, **kwargs)
    except FieldError as exc:
        raise exc.within(path) from None


__all__ = ["MISSING", "SceneError", "SceneErrors", "T", "TomlTable", "build_within"]

"""Scene fingerprints that survive fields added later.

A run, a study case and a report case count as done when the hash of their
scene's repr (:func:`hfcdem.workflows.run.scene_fingerprint`) matches the one
they recorded.  Each configuration dataclass is decorated with
:func:`fingerprinted`, whose repr is the dataclass's own except that a field
declared with :func:`added_field` is left out while it holds its default.  So a
field added to a scene's dataclasses after runs were written does not make
every run and report case count as not done: only scenes that set it change.

The rule this needs: an added field's default never changes, since a run
written with the old default would then pass for one with the new.
``tests/test_fingerprint.py`` lists every added field with its default.
"""

from __future__ import annotations

import dataclasses
from typing import Any, TypeVar

ADDED = "hfcdem_added"  # field metadata key: the date the field was added
T = TypeVar("T")


def added_field(default: Any, since: str) -> Any:
    """Declare a dataclass field added on ``since`` (a date), hashed only when set."""
    return dataclasses.field(default=default, metadata={ADDED: since})


def fingerprinted(cls: type[T]) -> type[T]:
    """Give dataclass ``cls`` the repr that leaves added fields out at their defaults."""
    dataclass: bool = dataclasses.is_dataclass(cls)  # a bool: no narrowing of cls
    if not dataclass:
        raise TypeError(f"fingerprinted expects a dataclass, got {cls!r}")
    cls.__repr__ = _repr  # type: ignore[method-assign]
    return cls


def added_fields(cls: type) -> dict[str, tuple[Any, str]]:
    """Map the added fields of dataclass ``cls`` to (default, date added)."""
    return {
        f.name: (f.default, f.metadata[ADDED])
        for f in dataclasses.fields(cls)
        if ADDED in f.metadata
    }


def _repr(self: Any) -> str:
    # the dataclass's generated repr, field for field, so fingerprints written
    # before this module existed still match
    parts = []
    for f in dataclasses.fields(self):
        if not f.repr:
            continue
        value = getattr(self, f.name)
        if ADDED in f.metadata and _equal(value, f.default):
            continue
        parts.append(f"{f.name}={value!r}")
    return f"{type(self).__qualname__}({', '.join(parts)})"


def _equal(value: Any, default: Any) -> bool:
    try:
        return bool(value == default)
    except (TypeError, ValueError):  # e.g. arrays
        return False


__all__ = ["ADDED", "added_field", "added_fields", "fingerprinted"]

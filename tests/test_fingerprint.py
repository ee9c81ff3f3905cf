"""Scene fingerprints: fields added later leave older runs' fingerprints alone."""

from __future__ import annotations

import dataclasses
import inspect
import math
from pathlib import Path

import pytest

from hfcdem.config import geometry, materials, parts, physics, plates
from hfcdem.config.fingerprint import added_field, added_fields, fingerprinted
from hfcdem.config.scene import load_scene
from hfcdem.workflows.run import scene_fingerprint

SCENES = Path(__file__).resolve().parents[1] / "meshes" / "scenes"
CONFIG_MODULES = (geometry, materials, parts, physics, plates)

# Every added field and its default.  A default here must never change: a run
# written with the old default would pass for one with the new (see
# hfcdem/config/fingerprint.py).  Add a row when you add a field.
ADDED_FIELDS = {
    ("InterfaceModel", "strength_length"): (0.0, "2026-12-05"),
}


def _config_dataclasses() -> list[type]:
    found = {}
    for module in CONFIG_MODULES:
        for _, cls in inspect.getmembers(module, inspect.isclass):
            if dataclasses.is_dataclass(cls) and cls.__module__ == module.__name__:
                found[cls.__qualname__] = cls
    return sorted(found.values(), key=lambda c: c.__qualname__)


def _before(name: str) -> type:
    """A class as it was before a field was added to it."""

    @fingerprinted
    @dataclasses.dataclass(frozen=True)
    class Settings:
        step: float = 0.01
        rule: str = "all"

    Settings.__qualname__ = name
    return Settings


def _after(name: str) -> type:
    @fingerprinted
    @dataclasses.dataclass(frozen=True)
    class Settings:
        step: float = 0.01
        rule: str = "all"
        until: str = added_field("end", since="2026-12-07")

    Settings.__qualname__ = name
    return Settings


def test_repr_is_the_dataclass_repr_without_added_fields() -> None:
    @dataclasses.dataclass(frozen=True)
    class Plain:
        step: float = 0.01
        rule: str = "all"
        hidden: int = dataclasses.field(default=3, repr=False)
        limit: float = math.inf

    generated = repr(Plain(step=0.5, limit=2.0))
    assert repr(fingerprinted(Plain)(step=0.5, limit=2.0)) == generated
    assert generated.endswith("Plain(step=0.5, rule='all', limit=2.0)")


def test_added_field_at_its_default_leaves_the_repr_as_before() -> None:
    old, new = _before("Settings"), _after("Settings")
    assert repr(new()) == repr(old())
    assert repr(new(step=0.2)) == repr(old(step=0.2))
    assert repr(new(until="first crack")) != repr(old())
    assert repr(new(until="first crack")).endswith(", until='first crack')")


def test_fingerprinted_refuses_a_plain_class() -> None:
    with pytest.raises(TypeError, match="expects a dataclass"):
        fingerprinted(int)


def test_every_config_dataclass_is_fingerprinted() -> None:
    classes = _config_dataclasses()
    assert len(classes) >= 20
    ours = "hfcdem.config.fingerprint"
    plain = [c.__qualname__ for c in classes if c.__repr__.__module__ != ours]
    assert plain == []


def test_added_fields_keep_their_defaults() -> None:
    found = {
        (cls.__qualname__, name): value
        for cls in _config_dataclasses()
        for name, value in added_fields(cls).items()
    }
    assert found == ADDED_FIELDS


def test_scene_fingerprint_changes_only_when_an_added_field_is_set() -> None:
    path = SCENES / "perforation_no2.toml"
    shipped = scene_fingerprint(load_scene(path, resolution="coarse"))
    at_default = load_scene(path, resolution="coarse", overrides={"rock.strength_length": "0 mm"})
    assert scene_fingerprint(at_default) == shipped
    assert "strength_length" not in repr(at_default.physics)
    set_ = load_scene(path, resolution="coarse", overrides={"rock.strength_length": "6 mm"})
    assert scene_fingerprint(set_) != shipped
    assert "strength_length=0.006" in repr(set_.physics)

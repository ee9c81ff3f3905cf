"""Scenes read from TOML into frozen, validated dataclasses (SI units inside).

The ``[geometry]`` table becomes a geometry of :mod:`hfcdem.config.geometry`,
the physics sections (``rock``, ``stress``, ``fluid``, ``injection`` or
``load``, ``solver``, ``output``) a :class:`~hfcdem.config.physics.Physics`;
any other top-level key is an error.  Every dimensional value carries its unit
(``"33.44 mm"``, ``"2 m"``, ``"60 deg"``; :mod:`hfcdem.config.units`), and every
error names the field by its dotted path
(``geometry.perforations[0].diameters[2]``) and the expected range, before Gmsh
runs.

Conventions (3D scenes)
-----------------------
* x points along SH, y along Sh, z up (along Sv).  The block is centred at the
  origin.
* The wellbore runs through the block centre along ``wellbore.axis`` (default
  ``"y"``: horizontal, along Sh, as in the paper's 2 m cube, so that a
  perforation along SH is perpendicular to it; the lab specimen uses ``"z"``).
* A perforation leaves the wellbore radially.  Its direction is given by
  ``azimuth`` (from +x towards +y in the horizontal plane) and ``inclination``
  (from the horizontal towards +z), or by a ``direction`` vector, then turned
  by ``phase`` about the wellbore axis (right-handed).  ``entry`` is the
  position of its axis along the wellbore axis, from the block centre.
* Sections are circles of diameters ``d1..dn`` at stations ``0, l1,
  l1+l2, ...`` measured along the perforation axis from the wellbore wall.
* ``symmetry`` lists mirror planes through the block centre (``"x"`` is the
  plane x = 0, ...); the model keeps the positive side.  ``"auto"`` picks every
  plane the scene is symmetric about, ``"none"`` (default) keeps it whole.

2D scenes lie in the x-y plane (plane strain): a crack plate (crack along x
through the centre), a KGD strip (initial crack and fracture path along x,
injection at the origin) and a borehole in a square.
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from collections.abc import Mapping
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from hfcdem.config import catalogue
from hfcdem.config.geometry import Geometry, PerforatedBlock, Scene
from hfcdem.config.parts import (
    AXES,
    MM,
    Block,
    Crack,
    FracturableZone,
    MeshSizing,
    Perforation,
    Plate,
    Profile,
    SlabZone,
    SphereZone,
    TunnelZone,
    Vector,
    Wellbore,
    axis_vector,
    check_vector,
    show_length,
)
from hfcdem.config.physics import PHYSICS_SECTIONS, field_default, parse_physics
from hfcdem.config.plates import AngledPathPlate, BoreholeSquare, CrackPlate, KGDStrip
from hfcdem.config.tables import MISSING, SceneError, SceneErrors, TomlTable, build_within
from hfcdem.config.units import FieldError, join_path

RESERVED_SECTIONS = ("rock", "stress", "fluid", "injection", "load", "solver", "output")


_REPLACED_WHOLE = ("fracturable",)  # a zone of another shape shares no keys


def _merge(base: Mapping[str, Any], over: Mapping[str, Any]) -> dict[str, Any]:
    """Deep-merge ``over`` onto ``base``: tables merge, anything else is replaced."""
    out = dict(base)
    for key, value in over.items():
        if key in _REPLACED_WHOLE:
            out[key] = value
        elif isinstance(value, Mapping) and isinstance(out.get(key), Mapping):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


_PROFILE_KEYS = ("profile", "diameters", "lengths", "diameter", "length")
_DIRECTION_KEYS = ("azimuth", "inclination", "direction", "phase")


def _read_profile(t: TomlTable) -> Profile:
    name = t.string("profile", None, catalogue.profile_names())
    explicit = [k for k in ("diameters", "lengths", "diameter", "length") if t.has(k)]
    if any(k in explicit for k in ("diameter", "length")) and any(
        k in explicit for k in ("diameters", "lengths")
    ):
        raise SceneError(t.path, "give either diameters and lengths, or diameter and length")
    base = catalogue.lookup_profile(name) if name else None
    if base is None and not explicit:
        raise SceneError(
            t.path,
            "give a profile (one of " + ", ".join(catalogue.profile_names()) + ") or "
            "diameters and lengths",
        )
    if t.has("diameter") or t.has("length"):
        d = t.quantity("diameter", "length")
        length = t.quantity("length", "length")
        return build_within(t.path, Profile.from_lengths, (d, d), (length,), name="cylinder")
    if base is not None:
        d_default = tuple(v * MM for v in base["diameters_mm"])
        l_default = tuple(v * MM for v in base["lengths_mm"])
    else:
        d_default = l_default = MISSING
    diameters = t.quantities("diameters", "length", d_default)
    lengths = t.quantities("lengths", "length", l_default)
    changed = base is not None and bool(explicit)
    assumed = bool(base and base["assumed"]) and not {"diameters", "lengths"} <= set(explicit)
    label = (name or "custom") + (" (modified)" if changed else "")
    source = "user sections" if base is None else base["source"]
    if changed:
        source = f"{source}; {' and '.join(explicit)} given in the scene"
    return build_within(
        t.path,
        Profile.from_lengths,
        diameters,
        lengths,
        name=label,
        assumed=assumed,
        source=source,
    )


def _read_direction(t: TomlTable, wellbore: Wellbore, phase_offset: float = 0.0) -> Vector:
    if t.has("direction") and (t.has("azimuth") or t.has("inclination")):
        raise SceneError(t.path, "give either direction or azimuth/inclination, not both")
    if t.has("direction"):
        raw = t.raw("direction")
        if not isinstance(raw, list) or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in raw
        ):
            raise SceneError(t.sub("direction"), f"expected three numbers, got {raw!r}")
        v = np.asarray(build_within(t.sub("direction"), check_vector, "", raw))
    else:
        az = t.quantity("azimuth", "angle", 0.0)
        inc = t.quantity("inclination", "angle", 0.0)
        v = np.array([math.cos(inc) * math.cos(az), math.cos(inc) * math.sin(az), math.sin(inc)])
    phase = t.quantity("phase", "angle", 0.0) + phase_offset
    return _rotate(v, axis_vector(wellbore.axis), phase)


def _rotate(v: np.ndarray, axis: np.ndarray, angle: float) -> Vector:
    """Rodrigues rotation of ``v`` by ``angle`` about the unit ``axis``."""
    c, s = math.cos(angle), math.sin(angle)
    out = v * c + np.cross(axis, v) * s + axis * (axis @ v) * (1.0 - c)
    out[np.abs(out) < 1e-15] = 0.0
    return (float(out[0]), float(out[1]), float(out[2]))


def _read_perforation(t: TomlTable, wellbore: Wellbore) -> Perforation:
    profile = _read_profile(t)
    direction = _read_direction(t, wellbore)
    entry = t.quantity("entry", "length", 0.0)
    t.finish()
    return build_within(t.path, Perforation, profile, direction, entry)


def _read_cluster(t: TomlTable, wellbore: Wellbore) -> list[Perforation]:
    count = t.number("count", integer=True)
    if not 1 <= count <= 100:
        raise SceneError(t.sub("count"), f"expected 1..100 perforations, got {count}")
    spacing = t.quantity("spacing", "length", 0.0)
    if spacing < 0.0:
        raise SceneError(t.sub("spacing"), f"must not be negative, got {show_length(spacing)}")
    phasing = t.quantity("phasing", "angle", 0.0)
    first = t.quantity("first_phase", "angle", 0.0)
    centre = t.quantity("entry", "length", 0.0)
    if t.has("phase"):
        raise SceneError(t.sub("phase"), "a cluster takes first_phase and phasing")
    profile = _read_profile(t)
    out = []
    for k in range(count):
        direction = _read_direction(t, wellbore, first + k * phasing)
        entry = centre + (k - 0.5 * (count - 1)) * spacing
        out.append(build_within(t.path, Perforation, profile, direction, entry))
    t.finish(extra=("phase",))
    return out


def _read_zone(t: TomlTable | None) -> FracturableZone | None:
    if t is None:
        return None
    shape = t.string("shape", choices=("sphere", "tunnel", "slab"))
    zone: FracturableZone
    if shape == "sphere":
        centre = t.quantities("centre", "length", (0.0, 0.0, 0.0))
        zone = build_within(t.path, SphereZone, t.quantity("radius", "length"), centre)
    elif shape == "tunnel":
        zone = build_within(
            t.path,
            TunnelZone,
            t.quantity("radius", "length"),
            t.number("perforation", 1, integer=True),
            t.quantity("beyond_tip", "length", None),
        )
    else:
        zone = build_within(
            t.path,
            SlabZone,
            t.string("axis", choices=AXES),
            t.quantity("thickness", "length"),
            t.quantity("offset", "length", 0.0),
        )
    t.finish()
    return zone


_MESH_KEYS = (
    "size",
    "size_far",
    "grading",
    "circle_elements",
    "wellbore_size",
    "algorithm",
    "wall_rings",
    "path_size",
    "size_integration",
    "resolutions",
)


def _read_mesh(
    t: TomlTable | None, path: str, resolution: str | None, size: float | None
) -> tuple[MeshSizing, str]:
    if t is None:
        raise SceneError(join_path(path, "mesh"), "missing; expected a table with at least size")
    chosen = "default"
    if resolution is not None and resolution != "default":
        named = t.data.get("resolutions", {})
        if not isinstance(named, Mapping) or resolution not in named:
            have = ", ".join(["default", *sorted(named)]) if isinstance(named, Mapping) else ""
            raise SceneError(
                t.sub("resolutions"), f"no resolution named {resolution!r}; this scene has: {have}"
            )
        override = named[resolution]
        if not isinstance(override, Mapping):
            raise SceneError(t.sub(f"resolutions.{resolution}"), "expected a table")
        bad = sorted(set(override) - set(_MESH_KEYS[:-1]))
        if bad:
            raise SceneError(t.sub(f"resolutions.{resolution}.{bad[0]}"), "unknown key")
        t = TomlTable({**t.data, **override}, t.path)
        chosen = resolution
    t.raw("resolutions", None)
    value = t.quantity("size", "length")
    if size is not None:
        value, chosen = size, f"{chosen}, size {show_length(size)}"
    default = partial(field_default, MeshSizing)
    kwargs: dict[str, Any] = {
        "size": value,
        "size_far": t.quantity("size_far", "length"),
        "grading": t.number("grading", default("grading")),
        "circle_elements": t.number("circle_elements", default("circle_elements"), integer=True),
        "wellbore_size": t.quantity("wellbore_size", "length", default("wellbore_size")),
        "algorithm": t.string("algorithm", default("algorithm")),
        "wall_rings": t.number("wall_rings", default("wall_rings"), integer=True),
        "path_size": t.quantity("path_size", "length", default("path_size")),
        "size_integration": t.string(
            "size_integration", default("size_integration"), MeshSizing.SIZE_INTEGRATIONS
        ),
    }
    t.finish()
    return build_within(t.path, MeshSizing, **kwargs), chosen


def _read_symmetry(t: TomlTable) -> str | tuple[str, ...]:
    value = t.raw("symmetry", "none")
    if value in ("none", "auto"):
        return str(value)
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise SceneError(
            t.sub("symmetry"), f"expected 'none', 'auto' or a list such as ['z'], got {value!r}"
        )
    return tuple(value)


_KIND_KEYS = {
    "perforated_block": ("block", "wellbore", "perforations", "cluster"),
    "crack_plate": ("plate", "crack"),
    "kgd_strip": ("plate", "crack"),
    "borehole_plate": ("plate", "wellbore"),
    "angled_path_plate": ("plate", "crack", "support"),
}


def parse_geometry(
    data: Mapping[str, Any],
    path: str = "geometry",
    resolution: str | None = None,
    size: float | None = None,
) -> tuple[Geometry, str | None, str]:
    """Read a ``[geometry]`` table; return (geometry, catalogue name, resolution used).

    ``catalogue = NAME`` starts from a preset (:mod:`hfcdem.config.catalogue`) that the
    other keys override (tables merge key by key; lists and the ``fracturable``
    table are replaced whole).
    ``resolution`` picks a named ``mesh.resolutions`` entry; ``size`` (m)
    overrides ``mesh.size``.
    """
    top = TomlTable(data, path)
    name = top.string("catalogue", None)
    if name is not None:
        if name not in catalogue.PRESETS:
            raise SceneError(
                top.sub("catalogue"),
                f"unknown entry {name!r}; the catalogue has: {', '.join(catalogue.preset_names())}",
            )
        preset = catalogue.lookup_preset(name)
        if "kind" in data and data["kind"] != preset["kind"]:
            raise SceneError(
                top.sub("kind"),
                f"catalogue entry {name!r} is a {preset['kind']}, not {data['kind']!r}",
            )
        merged = _merge(preset, {k: v for k, v in data.items() if k != "catalogue"})
        top = TomlTable({**merged, "catalogue": name}, path)
        top.used.add("catalogue")
    kind = top.string("kind", choices=tuple(_KIND_KEYS))
    symmetry = _read_symmetry(top)
    zone = _read_zone(top.table("fracturable"))
    sizing, chosen = _read_mesh(top.table("mesh"), path, resolution, size)
    axes = () if isinstance(symmetry, str) else symmetry
    geom: Geometry
    if kind == "perforated_block":
        geom = _read_block_scene(top, sizing, zone, axes)
    else:
        geom = _read_plate_scene(top, kind, sizing, zone, axes)
    if symmetry == "auto":
        geom = dataclasses.replace(geom, symmetry=geom.symmetric_axes())
    top.finish()
    return geom, name, chosen


def _read_wellbore(top: TomlTable, axis: str | None = None) -> Wellbore:
    """Read ``[wellbore]``; a 2D borehole has its ``axis`` fixed (the table may not set it)."""
    wt = top.table("wellbore")
    if wt is None:
        raise SceneError(top.sub("wellbore"), "missing; expected a table with diameter")
    diameter = wt.quantity("diameter", "length")
    wellbore = build_within(wt.path, Wellbore, diameter, axis or wt.string("axis", "y", AXES))
    wt.finish()
    return wellbore


def _read_block_scene(
    top: TomlTable, sizing: MeshSizing, zone: FracturableZone | None, axes: tuple[str, ...]
) -> PerforatedBlock:
    bt = top.table("block")
    if bt is None:
        raise SceneError(top.sub("block"), "missing; expected a table with size")
    raw = bt.raw("size", expected="a length such as '2 m' or a list of three")
    size = (
        bt.quantities("size", "length")
        if isinstance(raw, list)
        else (bt.quantity("size", "length"),) * 3
    )
    bt.finish()
    block = build_within(bt.path, Block, size)
    wellbore = _read_wellbore(top)
    perforations = [_read_perforation(t, wellbore) for t in top.tables("perforations")]
    ct = top.table("cluster")
    if ct is not None:
        perforations += _read_cluster(ct, wellbore)
    return build_within(
        top.path,
        PerforatedBlock,
        block,
        wellbore,
        tuple(perforations),
        sizing,
        zone,
        axes,
    )


def _read_plate_scene(
    top: TomlTable,
    kind: str,
    sizing: MeshSizing,
    zone: FracturableZone | None,
    axes: tuple[str, ...],
) -> Geometry:
    for key in ("block", "perforations", "cluster"):
        if top.has(key):
            raise SceneError(top.sub(key), f"not used by a {kind}")
    pt = top.table("plate")
    if pt is None:
        raise SceneError(top.sub("plate"), "missing; expected a table with width and height")
    plate = build_within(
        pt.path, Plate, pt.quantity("width", "length"), pt.quantity("height", "length")
    )
    pt.finish()
    if kind == "borehole_plate":
        wellbore = _read_wellbore(top, axis="z")
        return build_within(top.path, BoreholeSquare, plate, wellbore, sizing, zone, axes)
    ct = top.table("crack")
    if ct is None:
        raise SceneError(top.sub("crack"), "missing; expected a table with length")
    if kind == "angled_path_plate":
        return _read_angled_plate(top, ct, plate, sizing, zone, axes)
    if top.has("support"):
        raise SceneError(top.sub("support"), f"not used by a {kind}")
    length = ct.quantity("length", "length")
    path_length = ct.quantity("path_length", "length", None) if kind == "kgd_strip" else None
    ct.finish()
    crack = build_within(ct.path, Crack, length, path_length)
    if kind == "crack_plate":
        return build_within(top.path, CrackPlate, plate, crack, sizing, zone, axes)
    return build_within(top.path, KGDStrip, plate, crack, sizing, zone, axes)


def _read_angled_plate(
    top: TomlTable,
    ct: TomlTable,
    plate: Plate,
    sizing: MeshSizing,
    zone: FracturableZone | None,
    axes: tuple[str, ...],
) -> AngledPathPlate:
    """``[crack]`` (length, width, path_length, path_angle, wings); ``[support]`` (corners)."""
    length = ct.quantity("length", "length")
    width = ct.quantity("width", "length", 0.0)
    path_length = ct.quantity("path_length", "length")
    angle = ct.quantity("path_angle", "angle")
    wings = ct.string("wings", "point", ("point", "mirror"))
    ct.finish()
    crack = build_within(ct.path, Crack, length)
    st = top.table("support")
    corners = 0.0
    if st is not None:
        corners = st.quantity("corners", "length")
        st.finish()
    return build_within(
        top.path,
        AngledPathPlate,
        plate,
        crack,
        sizing,
        path_length,
        angle,
        wings,
        corners,
        width,
        zone,
        axes,
    )


def parse_scene(
    data: Mapping[str, Any],
    default_name: str = "scene",
    resolution: str | None = None,
    size: float | None = None,
    source: str | None = None,
) -> Scene:
    """Build a :class:`Scene` from a parsed TOML document; any invalid field raises SceneError."""
    try:
        return _parse_scene(data, default_name, resolution, size, source)
    except SceneError:
        raise
    except FieldError as exc:  # unit errors are scene errors too
        raise SceneError(exc.path, exc.reason) from None


def _parse_scene(
    data: Mapping[str, Any],
    default_name: str,
    resolution: str | None,
    size: float | None,
    source: str | None,
) -> Scene:
    top = TomlTable(data, "")
    name = top.string("name", default_name)
    description = top.string("description", "")
    gt = top.table("geometry")
    if gt is None:
        raise SceneError("geometry", "missing; every scene needs a [geometry] table")
    # [output] alone (a geometry-only scene) does not ask for physics: it is ignored
    wanted = any(k in data for k in PHYSICS_SECTIONS if k != "output")
    errors: list[FieldError] = []  # the geometry's and the physics', said together
    try:
        geometry, preset, chosen = parse_geometry(gt.data, "geometry", resolution, size)
    except FieldError as exc:
        errors.append(exc)
    try:
        physics = parse_physics(data) if wanted else None
    except FieldError as exc:
        errors.append(exc)
    SceneErrors.raise_any(errors)
    ignored = tuple(
        k for k in RESERVED_SECTIONS if k in data and (k not in PHYSICS_SECTIONS or not wanted)
    )
    top.finish(extra=RESERVED_SECTIONS)
    return build_within(
        "",
        Scene,
        name=name,
        geometry=geometry,
        description=description,
        catalogue=preset,
        resolution=chosen,
        source=source,
        ignored_sections=ignored,
        physics=physics,
    )


def set_field(doc: dict[str, Any], dotted: str, value: Any) -> None:
    """Set ``dotted`` in a scene document; a number indexes an array (``perforations.0``).

    ``None`` removes a table key (e.g. to swap ``duration`` for ``max_pressure``).
    """
    keys = dotted.split(".")
    node: Any = doc
    for depth, key in enumerate(keys):
        last = depth == len(keys) - 1
        if isinstance(node, list):
            if not (key.isdigit() and int(key) < len(node)):
                raise SceneError(dotted, f"{key!r}: expected an index below {len(node)}")
            if last:
                node[int(key)] = value
            else:
                node = node[int(key)]
            continue
        if not isinstance(node, dict):
            raise SceneError(dotted, f"{keys[depth - 1]!r} is not a table in the scene")
        if last and value is None:
            node.pop(key, None)
        elif last:
            node[key] = value
        else:
            node = node.setdefault(key, {})


def apply_overrides(
    doc: dict[str, Any], overrides: Mapping[str, Any], resolution: str | None
) -> None:
    """Set each dotted key of ``overrides`` in ``doc`` (:func:`set_field`).

    A named resolution's table replaces ``geometry.mesh``'s own fields, so a
    ``geometry.mesh.FIELD`` override is also written into the chosen
    resolution's table where that table (the scene's or its catalogue entry's)
    sets FIELD: given explicitly, it wins at any resolution.
    """
    for key, value in overrides.items():
        set_field(doc, key, value)
        parts = key.split(".")
        if value is None or len(parts) != 3 or parts[:2] != ["geometry", "mesh"]:
            continue
        if resolution is None or resolution == "default" or parts[2] == "resolutions":
            continue
        if parts[2] in _named_resolution(doc.get("geometry", {}), resolution):
            set_field(doc, f"geometry.mesh.resolutions.{resolution}.{parts[2]}", value)


def _named_resolution(geometry: Any, resolution: str) -> Mapping[str, Any]:
    """Return the fields the named ``resolution`` sets (the geometry table or its catalogue's)."""
    if not isinstance(geometry, Mapping):
        return {}
    tables = [geometry]
    if geometry.get("catalogue") in catalogue.PRESETS:
        tables.insert(0, catalogue.lookup_preset(geometry["catalogue"]))
    fields: dict[str, Any] = {}
    for table in tables:
        mesh = table.get("mesh", {})
        named = mesh.get("resolutions", {}) if isinstance(mesh, Mapping) else {}
        chosen = named.get(resolution, {}) if isinstance(named, Mapping) else {}
        fields |= dict(chosen) if isinstance(chosen, Mapping) else {}
    return fields


def load_scene(
    path: str | Path,
    resolution: str | None = None,
    size: float | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> Scene:
    """Read and validate the scene file ``path`` (TOML).

    ``overrides`` maps dotted keys to values that replace the file's
    (``{"injection.duration": "120 s"}``), validated like the file.
    """
    p = Path(path)
    try:
        with p.open("rb") as fh:
            data = tomllib.load(fh)
    except OSError as exc:
        raise SceneError("", f"cannot read scene file {p}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise SceneError("", f"{p} is not valid TOML: {exc}") from None
    apply_overrides(data, overrides or {}, resolution)
    try:
        return parse_scene(data, p.stem, resolution, size, str(p))
    except FieldError as exc:
        raise SceneError(f"{p.name}: {exc.path}" if exc.path else p.name, exc.reason) from None


__all__ = [
    "RESERVED_SECTIONS",
    "apply_overrides",
    "load_scene",
    "parse_geometry",
    "parse_scene",
    "set_field",
]

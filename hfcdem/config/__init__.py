"""Configuration: a scene file becomes frozen, validated dataclasses in SI units.

``units`` parses quantities with units; ``tables`` reads TOML tables and holds
:class:`~hfcdem.config.tables.SceneError`; ``parts`` (profiles, perforations,
block, wellbore, zones, sizing, plates, cracks) and ``geometry`` (the 3D block
and 2D plates, :class:`~hfcdem.config.geometry.Scene`) are the validated
dataclasses; ``scene`` reads a scene file into them; ``materials`` holds the rock, stress,
interface, fluid and pump dataclasses; ``physics`` reads its rock,
stress, fluid, injection/load, solver and output sections; ``catalogue`` holds
the perforation profiles and scene presets.
Nothing here meshes or solves: the data flows on to :mod:`hfcdem.mesh`.
"""

__all__: list[str] = []

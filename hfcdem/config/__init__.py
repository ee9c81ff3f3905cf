"""Configuration: a scene file becomes frozen, validated dataclasses in SI units.

``units`` parses quantities with units; ``scene`` reads the geometry of a scene
file; ``physics`` its rock, stress, fluid, injection/load, solver and output
sections; ``catalogue`` holds the perforation profiles and scene presets.
Nothing here meshes or solves: the data flows on to :mod:`hfcdem.mesh`.
"""

__all__: list[str] = []

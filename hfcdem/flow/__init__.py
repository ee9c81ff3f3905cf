"""Fluid in the fractures: leak-off and the facet flow network.

``fluid`` holds Carter leak-off (the fluid and pump data live in
:mod:`hfcdem.config.materials`);
``network`` turns broken facets into finite-volume cells joined at shared
edges (3D) or vertices (2D) for the cubic law; ``balance`` is the mass balance
of the pressure groups on it (plain NumPy) and ``newton`` solves it (SNES);
``seepage`` is transient flow through intact joints of given aperture, and
``apertures`` holds those apertures at a reference cell size.
"""

__all__: list[str] = []

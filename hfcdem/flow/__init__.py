"""Fluid in the fractures: the fluid and pump schedule, and the facet flow network.

``fluid`` holds :class:`Fluid`, :class:`Injection` and Carter leak-off;
``network`` turns broken facets into finite-volume cells joined at shared
edges (3D) or vertices (2D) for the cubic law; ``balance`` is the mass balance
of the pressure groups on it (plain NumPy) and ``newton`` solves it (SNES).
"""

__all__: list[str] = []

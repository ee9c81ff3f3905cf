"""Meshing: a scene's geometry becomes a distributed, tagged DOLFINx mesh.

``tagged`` holds :class:`~hfcdem.mesh.tagged.TaggedMesh` (the mesh with its cell
and facet groups by name) and the Gmsh-to-DOLFINx transfer (Gmsh on rank 0);
``block`` builds the 3D wellbore and perforation tunnels in a rock block,
``plates`` the 2D plates, both placed with ``frames`` and sized by
``grading``; ``build`` meshes a scene and reports how the mesh measures against
the analytic shapes; ``picture`` draws it.  The verified 2D set-ups are scenes
too (``MeshSizing.wall_rings``, ``path_size``, ``size_integration = "exact"``);
``penny`` meshes the quarter block with a penny crack of the 3D check.
"""

__all__: list[str] = []

"""What a user runs: a scene end to end, a static load, a study.

``run`` meshes a scene, builds the solid and the fracture, steps it and writes
the outputs; ``static`` solves a ``[load]`` scene once; ``study`` sweeps scene
fields; ``convergence`` runs a scene over resolutions and estimates each
answer's discretisation error (``richardson``).
"""

__all__: list[str] = []

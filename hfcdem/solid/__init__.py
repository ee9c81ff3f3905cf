"""The CDEM solid: elastic blocks joined by interface springs that break.

``elastic`` holds the rock (:class:`ElasticMaterial`), the in-situ stress and
continuous elasticity; ``interfaces`` the strengths and failure checks (pure
NumPy); ``cdem`` the DG blocks, springs, contact and break state machine.
"""

__all__: list[str] = []

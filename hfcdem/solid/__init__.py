"""The CDEM solid: elastic blocks joined by interface springs that break.

``elastic`` holds Hooke's law under the in-situ stress and continuous
elasticity (the material data live in :mod:`hfcdem.config.materials`);
``interfaces`` the strengths and failure checks (pure NumPy); ``facets`` the
interface facets and their geometry; ``states`` their failure/contact states;
``forms`` the UFL forms, loads and boundary conditions; ``cdem`` composes them:
the solver and the break state machine.
"""

__all__: list[str] = []

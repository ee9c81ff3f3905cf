"""Results become files: atomic JSON/CSV/VTU writers, field series, pictures.

``files`` writes whole files or nothing (temporary file + rename, rank 0);
``series`` writes fields over time (``fields.bp``, ``interfaces.pvd``);
``plots`` draws PNG pictures; ``sampling`` evaluates fields at points the same
way on any rank count.
"""

__all__: list[str] = []

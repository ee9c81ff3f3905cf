"""Gmsh models built on rank 0 and distributed by DOLFINx, with named tags.

Every hfcdem mesh is a :class:`TaggedMesh`: the DOLFINx mesh, its cell and facet
tags, and the names of the Gmsh physical groups behind those tags.  Tag *names*
are the API (``"rock"``, ``"wellbore_wall"``, ``"symmetry_x"``, ...); the integer
values are an implementation detail.

Meshes are created with shared-facet ghosting so that interior-facet integrals
(the interface springs of the CDEM solid) assemble in parallel.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import dolfinx
import gmsh
import numpy as np
import ufl
from dolfinx.io import gmshio
from mpi4py import MPI

from hfcdem.mesh.partition import create_partitioner


class MeshingError(RuntimeError):
    """Gmsh could not build a scene's geometry or mesh."""


@dataclass(frozen=True)
class TaggedMesh:
    """A distributed mesh with named cell and facet tags."""

    mesh: dolfinx.mesh.Mesh
    cell_tags: dolfinx.mesh.MeshTags
    facet_tags: dolfinx.mesh.MeshTags
    cell_names: Mapping[str, int]
    facet_names: Mapping[str, int]
    seconds: float = field(default=0.0, compare=False)

    @property
    def comm(self) -> MPI.Comm:
        """The mesh's communicator."""
        return self.mesh.comm

    def facet_tag(self, name: str) -> int:
        """Return the integer tag of the facet group ``name``."""
        try:
            return self.facet_names[name]
        except KeyError:
            known = ", ".join(sorted(self.facet_names)) or "none"
            raise KeyError(f"no facet group named {name!r}; this mesh has: {known}") from None

    def facet_groups(self, prefix: str) -> tuple[str, ...]:
        """Names of the facet groups that start with ``prefix`` (``"outer"``: every edge)."""
        return tuple(sorted(n for n in self.facet_names if n.startswith(prefix)))

    def facets(self, name: str) -> np.ndarray:
        """Local indices of the facets in group ``name`` (owned and ghost)."""
        return self.facet_tags.find(self.facet_tag(name))

    def ds(self, name: str | None = None) -> ufl.Measure:
        """Exterior-facet measure over the group ``name`` (all tagged facets if None)."""
        measure = ufl.Measure("ds", domain=self.mesh, subdomain_data=self.facet_tags)
        return measure if name is None else measure(self.facet_tag(name))


def _physical_names(model: Any, dim: int) -> dict[str, int]:
    return {model.getPhysicalName(d, t): t for d, t in model.getPhysicalGroups(dim)}


def mesh_from_gmsh(
    build: Callable[[Any], None],
    comm: MPI.Comm = MPI.COMM_WORLD,
    gdim: int = 3,
    name: str = "scene",
) -> TaggedMesh:
    """Run ``build(gmsh.model)`` on rank 0, mesh it there and distribute the result.

    ``build`` must create the geometry, the physical groups (named; they become
    the tags) and generate the mesh.  Any Gmsh failure is re-raised on every rank
    as :class:`MeshingError` naming the scene.
    """
    t0 = time.perf_counter()
    error: str | None = None
    names: tuple[dict[str, int], dict[str, int]] = ({}, {})
    if comm.rank != 0 and comm.size > 1:
        # while rank 0 runs Gmsh, wait without spinning: a spinning MPI wait takes
        # a core from Gmsh when ranks share cores
        request = comm.Ibarrier()
        while not request.Test():
            time.sleep(0.002)
    if comm.rank == 0:
        gmsh.initialize(interruptible=False)
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(name)
        try:
            build(gmsh.model)
            tdim = gmsh.model.getDimension()
            if tdim != gdim:
                raise MeshingError(f"expected a {gdim}D model, Gmsh built a {tdim}D one")
            names = (_physical_names(gmsh.model, gdim), _physical_names(gmsh.model, gdim - 1))
            if not names[0]:
                raise MeshingError("the model has no named cell group")
        except Exception as exc:
            error = f"meshing scene {name!r} failed: {type(exc).__name__}: {exc}"
            gmsh.finalize()
        if comm.size > 1:
            comm.Ibarrier().Wait()  # wakes the ranks sleeping above
    error = comm.bcast(error, root=0)
    if error is not None:
        raise MeshingError(error)
    cell_names, facet_names = comm.bcast(names, root=0)
    try:
        partitioner = create_partitioner(dolfinx.mesh.GhostMode.shared_facet)
        mesh, cell_tags, facet_tags = gmshio.model_to_mesh(
            gmsh.model, comm, 0, gdim=gdim, partitioner=partitioner
        )
    finally:
        if comm.rank == 0:
            gmsh.finalize()
    mesh.name = name
    cell_tags.name = "cell_tags"
    facet_tags.name = "facet_tags"
    mesh.topology.create_connectivity(gdim - 1, gdim)
    return TaggedMesh(
        mesh=mesh,
        cell_tags=cell_tags,
        facet_tags=facet_tags,
        cell_names=cell_names,
        facet_names=facet_names,
        seconds=comm.allreduce(time.perf_counter() - t0, op=MPI.MAX),
    )


__all__ = ["MeshingError", "TaggedMesh", "mesh_from_gmsh"]

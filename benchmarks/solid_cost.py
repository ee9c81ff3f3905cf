"""What one solid solve costs, full DG against the reduced (vertex-cluster) system.

For the No. 2 scene at each resolution: cells, DG unknowns, the unknowns of a
vertex-continuous space (gdim x vertices), and the seconds of assembly, MUMPS
LDL^T (symbolic + numeric, then numeric alone on the same pattern) and one
solve (a unit pressure on the tunnel wall), with the peak memory of all ranks.
Then the reduced system (hfcdem/solid/reduction.py) with every interface glued
except a band: its unknowns, the seconds to build P, to form P^T K P and to
factorise, and how far its solution of a unit tunnel pressure lies from the
full one (the glued springs' compliance at finite alpha, and Nitsche's error).

    make run CMD="mpirun -n 2 python3 benchmarks/solid_cost.py coarse default"
    make run CMD="python3 benchmarks/solid_cost.py coarse --bands zone 10 wall all"

Bands: ``zone`` frees every interface of the fracturable zone; a number frees the
interfaces whose midpoint lies within that many mm of the tunnel wall; ``wall``
the interfaces touching the wall (its joints); ``all`` glues everything (the
continuous P1 bound).
"""

from __future__ import annotations

import argparse
import resource
import time
from pathlib import Path

import dolfinx
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc
from scipy.spatial import cKDTree

from hfcdem.config.scene import load_scene
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.solid.cdem import CDEMSolid, Loads
from hfcdem.solid.reduction import ReducedSystem, glued_facet_set
from hfcdem.solvers import DIRECT_CHOLESKY, create_ksp
from hfcdem.workflows.run import build_solid

SCENE = Path(__file__).resolve().parents[1] / "meshes/scenes/perforation_no2.toml"
comm = MPI.COMM_WORLD
say = print if comm.rank == 0 else (lambda *a, **k: None)


def memory_mb() -> float:
    """Peak resident memory of all ranks together (MB)."""
    return comm.allreduce(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss, op=MPI.SUM) / 1024


def seconds(t0: float) -> float:
    """Wall seconds since ``t0``, the slowest rank's."""
    return comm.allreduce(time.perf_counter() - t0, op=MPI.MAX)


def factorise(A: PETSc.Mat, prefix: str) -> tuple[PETSc.KSP, float, float]:
    """MUMPS LDL^T of ``A``: the KSP, seconds of symbolic + numeric, seconds of numeric alone."""
    A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
    ksp = create_ksp(A, prefix, DIRECT_CHOLESKY, comm)
    t0 = time.perf_counter()
    ksp.setUp()
    full = seconds(t0)
    # new values (twice scaled back), same pattern: PETSc refactorises numerically only
    A.scale(2.0)
    A.scale(0.5)
    ksp.setOperators(A)
    t0 = time.perf_counter()
    ksp.setUp()
    return ksp, full, seconds(t0)


def wall_groups(solid: CDEMSolid) -> list[str]:
    """Facet groups of the tunnel walls."""
    return sorted(n for n in solid.tmesh.facet_names if n.startswith("perforation"))


def wall_points(solid: CDEMSolid) -> tuple[np.ndarray, np.ndarray]:
    """Coordinates and input ids of the tunnel-wall vertices on all ranks."""
    mesh, fdim = solid.mesh, solid.mesh.topology.dim - 1
    facets = np.concatenate([solid.tmesh.facets(n) for n in wall_groups(solid)])
    # DOLFINx divides by the entity count: a rank without wall facets must not ask
    nodes = (
        np.unique(dolfinx.mesh.entities_to_geometry(mesh, fdim, facets, False))
        if len(facets)
        else np.zeros(0, dtype=np.int32)
    )
    ids = np.asarray(mesh.geometry.input_global_indices)[nodes]
    x = np.concatenate(comm.allgather(mesh.geometry.x[nodes]))
    ids_all = np.concatenate(comm.allgather(ids))
    return x, ids_all


def band(solid: CDEMSolid, name: str) -> np.ndarray:
    """Glued flags of the interfaces for band ``name`` (see the module's docstring)."""
    if name == "zone":
        return np.zeros(solid.num_facets, dtype=bool)
    if name == "all":
        return np.ones(solid.num_facets, dtype=bool)
    x, ids = wall_points(solid)
    if name == "wall":
        touching = np.isin(solid.vertex_ids, ids).sum(axis=1) >= solid.gdim - 1
        return ~touching
    distance = cKDTree(x).query(solid.midpoints)[0] if solid.num_facets else np.zeros(0)
    return distance > float(name) * 1e-3


def relative_difference(u: dolfinx.fem.Function, ref: dolfinx.fem.Function) -> float:
    """Largest DG dof difference over the largest reference dof (all ranks)."""
    diff = comm.allreduce(float(np.abs(u.x.array - ref.x.array).max()), op=MPI.MAX)
    return diff / comm.allreduce(float(np.abs(ref.x.array).max()), op=MPI.MAX)


def full_cost(res: str, solid: CDEMSolid, L: dolfinx.fem.Form) -> dolfinx.fem.Function:
    """Print the full DG row; return the solution of the unit tunnel pressure."""
    cells = solid.mesh.topology.index_map(solid.mesh.topology.dim).size_global
    dg = solid.V.dofmap.index_map.size_global * solid.gdim
    cg = solid.mesh.topology.index_map(0).size_global * solid.gdim
    solid.assemble_stiffness()[1].destroy()  # compiles the form: not counted
    t0 = time.perf_counter()
    a_form, A = solid.assemble_stiffness()
    t_asm = seconds(t0)
    ksp, t_fact, t_num = factorise(A, "bench_full_")
    u = dolfinx.fem.Function(solid.V)
    b = solid.assemble_load(a_form, L)
    t0 = time.perf_counter()
    ksp.solve(b, u.x.petsc_vec)
    t_solve = seconds(t0)
    u.x.scatter_forward()
    for obj in (ksp, A, b):
        obj.destroy()
    say(
        f"| {res} | {cells} | {dg} | {cg} | {t_asm:.2f} | {t_fact:.2f} | {t_num:.2f} "
        f"| {t_solve:.3f} | {memory_mb():.0f} |"
    )
    return u


def reduced_cost(
    res: str, solid: CDEMSolid, L: dolfinx.fem.Form, name: str, ref: dolfinx.fem.Function
) -> None:
    """Print the reduced row of band ``name``."""
    glued = band(solid, name)
    free = comm.allreduce(int(np.count_nonzero(~glued & solid.owned)), op=MPI.SUM)
    t0 = time.perf_counter()
    reduced = ReducedSystem(
        solid.V, solid.bcs, glued_facet_set(solid.interface_facets, glued), prefix="bench_reduced_"
    )
    t_build = seconds(t0)
    a_form, A = solid.assemble_stiffness()
    t0 = time.perf_counter()
    A_red = reduced.clusters.reduce_matrix(A)
    A_red.zeroRowsColumns(reduced.held, diag=1.0)
    t_ptap = seconds(t0)
    ksp, t_fact, t_num = factorise(A_red, "bench_reduced_")
    u = dolfinx.fem.Function(solid.V)
    t0 = time.perf_counter()
    reduced.solve(ksp, solid.assemble_load(a_form, L), u)
    t_solve = seconds(t0)
    for obj in (ksp, A, A_red):
        obj.destroy()
    say(
        f"| {res} | {name} | {free} | {reduced.num_dofs} | {t_build:.2f} | {t_ptap:.2f} "
        f"| {t_fact:.2f} | {t_num:.2f} | {t_solve:.3f} | {relative_difference(u, ref):.2e} "
        f"| {memory_mb():.0f} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("resolutions", nargs="+", help="coarse, default or paper")
    parser.add_argument("--bands", nargs="+", default=["zone", "10", "wall", "all"])
    args = parser.parse_args()
    say(f"{comm.size} rank(s); timings are the slowest rank's; memory: peak of all ranks summed")
    rows: list[tuple[str, CDEMSolid, dolfinx.fem.Form, dolfinx.fem.Function]] = []
    say(
        "\n| resolution | cells | DG unknowns | P1 unknowns | assemble s | MUMPS sym+num s "
        "| num s | solve s | memory MB |\n|---|---|---|---|---|---|---|---|---|"
    )
    for res in args.resolutions:
        scene = load_scene(SCENE, None if res == "default" else res)
        solid = build_solid(scene, create_scene_mesh(scene, comm).tmesh)
        loads = Loads(cavity={name: 1e6 for name in wall_groups(solid)}, in_situ_factor=0.0)
        L = solid.load_form(loads)
        rows.append((res, solid, L, full_cost(res, solid, L)))
    say(
        "\n| resolution | band | free interfaces | reduced unknowns | build P s | PtAP s "
        "| MUMPS sym+num s | num s | solve s | max diff / max u | memory MB |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|"
    )
    for res, solid, L, ref in rows:
        for name in args.bands:
            reduced_cost(res, solid, L, name, ref)


if __name__ == "__main__":
    main()

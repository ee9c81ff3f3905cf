# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
# ---

# %% [markdown]
# # A tour of the hfcdem API
#
# A scene flows one way through hfcdem: a TOML file becomes validated
# dataclasses (`hfcdem.config`), the scene becomes a tagged mesh
# (`hfcdem.mesh`), the mesh becomes a CDEM solid (`hfcdem.solid`), the solid
# meets the fluid (`hfcdem.flow`, `hfcdem.coupling`) and results become files
# (`hfcdem.io`). `hfcdem.run_scene` runs the whole chain; this tour takes the
# steps one at a time on the smallest verified scene, the pressurised crack of
# the perforation paper (Table 1: a 0.2 m crack at 22 MPa in a 1 m steel plate),
# and checks the answer against Sneddon's closed form.
#
# Run it with `python3 demos/api_tour.py -o results/api_tour` (or under
# `mpirun -n 2`).

# %%
from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

from mpi4py import MPI

import hfcdem
from hfcdem import analytic
from hfcdem.workflows.demos import parse_demo_line, run_demo

ROOT = Path(__file__).resolve().parents[1]

# %% [markdown]
# ## 1. A scene file becomes a `Scene`
#
# Every dimensional value carries its unit in the file; inside, all is SI.
# A bad value raises `hfcdem.SceneError` naming the field.


# %%
def read_scene(say: Callable[..., None]) -> hfcdem.Scene:
    """Load the Sneddon plate's scene file and print its crack pressure and rock."""
    scene = hfcdem.load_scene(ROOT / "meshes/scenes/sneddon_plate.toml")
    load = scene.physics.load
    rock = scene.physics.rock
    say(
        f"scene {scene.name}: crack pressure {load.crack_pressure / 1e6:g} MPa, "
        f"E {rock.youngs_modulus / 1e9:g} GPa"
    )
    return scene


# %% [markdown]
# ## 2. The scene becomes a tagged mesh
#
# Gmsh runs on rank 0; the mesh is distributed with its groups by name.


# %%
def mesh_scene(
    scene: hfcdem.Scene, comm: MPI.Comm, say: Callable[..., None]
) -> tuple[hfcdem.TaggedMesh, int]:
    """Mesh ``scene`` on ``comm``; print and return the global cell count with the mesh."""
    mesh = hfcdem.create_scene_mesh(scene, comm).tmesh
    cells = mesh.mesh.topology.index_map(mesh.mesh.topology.dim).size_global
    say(f"mesh: {cells} cells; facet groups {sorted(mesh.facet_names)}")
    return mesh, cells


# %% [markdown]
# ## 3. The mesh becomes a CDEM solid, and one static solve
#
# `build_solid` reads the rock, springs and boundary conditions from the scene.
# The crack is a pre-broken, open interface loaded on both faces.


# %%
def solve_pressurised_crack(
    scene: hfcdem.Scene, mesh: hfcdem.TaggedMesh, say: Callable[..., None]
) -> hfcdem.CDEMSolid:
    """Build the CDEM solid of ``scene`` on ``mesh`` and solve it once under the crack pressure."""
    solid = hfcdem.build_solid(scene, mesh)
    solid.solve(hfcdem.Loads(crack_pressure=scene.physics.load.crack_pressure))
    say(f"solid: {solid.V.dofmap.index_map.size_global * solid.gdim} unknowns")
    return solid


# %% [markdown]
# ## 4. The whole chain in one call, and the results read back
#
# `run_scene` writes `summary.json`, the crack opening and ParaView files into
# the output directory (`force=True`: even over another scene's results);
# `read_results` reads a run directory back, here the face displacement at the
# crack centre.


# %%
def run_and_read_back(scene: hfcdem.Scene, output: str) -> float:
    """Run the whole chain into ``output``; return the crack-centre u_y (m) read back."""
    hfcdem.run_scene(scene, output, force=True)
    results = hfcdem.read_results(output)
    return results.summary["sneddon"]["centre_uy_um"] * 1e-6


# %% [markdown]
# ## 5. Against the closed form
#
# Sneddon's opening of a pressurised crack in an infinite plate (the paper's
# eq. 21); the face displacement u_y is half of it. The finite plate with a
# fixed edge is a little stiffer (README: -3.8 % at the centre).


# %%
def sneddon_centre_uy(scene: hfcdem.Scene) -> float:
    """Sneddon's face displacement u_y (m) at the centre of the scene's crack."""
    load = scene.physics.load
    rock = scene.physics.rock
    half = 0.5 * scene.geometry.crack.length
    return 0.5 * float(
        analytic.sneddon_opening(
            0.0, half, load.crack_pressure, rock.youngs_modulus, rock.poisson_ratio
        )
    )


# %% [markdown]
# ## The tour in one function
#
# `main` takes the output directory (and any PETSc options), runs the five
# steps in order, prints the centre displacement next to Sneddon's and returns
# the cell count and both displacements. Only rank 0 prints.


# %%
def main(argv: list[str] | None = None) -> dict:
    """Walk through the API on the Sneddon plate; return what was measured."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("-o", "--output", default="results/api_tour")
    args, say = parse_demo_line(parser, argv)  # PETSc options too

    scene = read_scene(say)
    mesh, cells = mesh_scene(scene, MPI.COMM_WORLD, say)
    # the solid stays alive through run_scene, so the summary's peak memory counts it
    _solid = solve_pressurised_crack(scene, mesh, say)
    ours = run_and_read_back(scene, args.output)
    exact = sneddon_centre_uy(scene)
    say(f"centre u_y {ours * 1e6:.3f} um; Sneddon {exact * 1e6:.3f} um ({ours / exact - 1:+.2%})")
    return {"cells": cells, "centre_uy_m": ours, "sneddon_centre_uy_m": exact}


# %%
if __name__ == "__main__":
    run_demo(main)

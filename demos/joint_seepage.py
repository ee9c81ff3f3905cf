# ---
# jupyter:
#   jupytext:
#     formats: py:percent
# ---

# %% [markdown]
# # Water permeating the joints around perforation No. 2 (the paper's Fig. 14)
#
# The perforation paper's fluid does not fill the rock at once: every interface
# is a joint, water enters the joints that touch the tunnel wall and
# "gradually permeates" the rock over 1 to 60 s.  Here the tunnel wall of
# perforation No. 2 is held at a water pressure and the joints of the
# fracturable zone fill from dry by saturation filling
# (:mod:`hfcdem.flow.seepage`, ``filling="saturation"``): a joint takes its
# void ``a A`` before it holds pressure, and its relative permeability is
# ``S^2 (3 - 2 S)``.  The solid does not move (the pictures are of the fluid
# only).
#
# The hydraulic aperture ``a`` is the one physical input the paper leaves
# open: its Table 1 gives an initial opening of 5 um and a permeability
# coefficient ``K = 8.33e-11 m^2/(Pa s)``; the cubic law's ``a^2 / (12 mu)``
# equals that ``K`` for ``a = sqrt(12 mu K) = 1.0 um`` with water.  This demo
# takes the permeability coefficient (the flow property) and says so; with
# 5 um the front moves 5 times farther at the same time.
#
# Run (``--resolution coarse`` by default; ``mpirun -n 2`` works the same)::
#
#     python3 demos/joint_seepage.py -o results/joint_seepage
#
# Written: ``saturation.png`` (the Fig. 14 panels), ``seepage.csv`` (fluid
# in the joints and the wet share over time), ``joints.pvd`` (saturation and
# pressure per joint at every picture time, for ParaView).

# %%
from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
from mpi4py import MPI

from hfcdem.config.geometry import Scene
from hfcdem.config.materials import Fluid
from hfcdem.config.scene import load_scene
from hfcdem.config.units import FieldError, parse_quantity
from hfcdem.coupling.condense import cavity_vertices
from hfcdem.flow.seepage import JointSeepage, joint_network, network_positions
from hfcdem.io.files import prepare_output_dir, write_atomic, write_csv, write_interfaces
from hfcdem.io.plots import owned_boundary_triangles, render_facet_series
from hfcdem.io.series import pvd_text
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.mesh.tagged import TaggedMesh
from hfcdem.solid.cdem import CDEMSolid
from hfcdem.solid.interfaces import FacetState
from hfcdem.workflows.demos import parse_demo_line, run_demo
from hfcdem.workflows.run import build_solid, pressurised_groups

ROOT = Path(__file__).resolve().parents[1]
PERMEABILITY_COEFFICIENT = 8.33e-11  # m^2/(Pa s), perforation paper Table 1

# %% [markdown]
# ## The inputs
#
# The scene is No. 2's (``meshes/scenes/perforation_no2.toml``): its mesh,
# rock and fluid, at ``--resolution``.  The wall pressure is a stress with its
# unit (``--pressure``, 60 MPa by default) and must be positive.  The
# aperture is the one of the paper's permeability coefficient,
# ``sqrt(12 mu K)``, unless ``--aperture`` gives a length.  The picture times
# are sorted and must be positive.  All of them are read before anything is
# meshed or written, so a bad one stops the demo with a one-line error.


# %%
def load_no2_scene(resolution: str) -> Scene:
    """Perforation No. 2's scene at ``resolution``: 'coarse', 'default' or 'paper'."""
    return load_scene(
        ROOT / "meshes/scenes/perforation_no2.toml",
        None if resolution == "default" else resolution,
    )


def wall_pressure(text: str) -> float:
    """The tunnel wall's water pressure (Pa) from ``text`` such as '60 MPa'."""
    pressure = parse_quantity(text, "stress", "--pressure")
    if not (math.isfinite(pressure) and pressure > 0.0):
        raise FieldError("--pressure", f"expected a pressure > 0 Pa, got {text!r}")
    return pressure


def joint_aperture(text: str | None, fluid: Fluid) -> float:
    """The joints' hydraulic aperture (m): ``text`` such as '5 um', or the paper's K's."""
    if text is None:
        return math.sqrt(12.0 * fluid.viscosity * PERMEABILITY_COEFFICIENT)
    return parse_quantity(text, "length", "--aperture")


def picture_times(text: str) -> list[float]:
    """The picture times (s), sorted, from comma-separated positive seconds."""
    try:
        times = sorted(float(t) for t in text.split(","))
    except ValueError:
        times = []
    if not times or not (0.0 < times[0] and math.isfinite(times[-1])):
        raise FieldError("--times", f"expected positive seconds such as '1,10,60', got {text!r}")
    return times


# %% [markdown]
# ## The joints, dry
#
# The CDEM solid of the scene is built only for its interfaces: the joints
# are the intact interfaces of the fracturable zone (crack faces are not
# joints), the cavity is the open tunnel wall, the facet groups the
# injection pressure would load.  The network joins the joints to one
# another and, where they touch it, to the wall; the seepage on it starts
# with every joint dry (saturation 0).


# %%
def dry_joints(
    scene: Scene, tmesh: TaggedMesh, aperture: float
) -> tuple[CDEMSolid, tuple[str, ...], np.ndarray, JointSeepage]:
    """Build the solid, the cavity's groups, the joints (local interfaces) and their seepage."""
    solid = build_solid(scene, tmesh)
    cavity = pressurised_groups(tmesh.facet_names, scene.physics.wellbore)
    joints = np.flatnonzero((solid.state == FacetState.INTACT) & ~solid.is_crack)
    net = joint_network(solid, cavity_vertices(solid, cavity, None), joints)
    seep = JointSeepage(net, aperture, scene.physics.fluid, filling="saturation", saturation=0.0)
    return solid, cavity, joints, seep


# %% [markdown]
# ## Implicit steps
#
# The wall holds its pressure from the first step.  The steps are implicit,
# small where the front is fast (early) and growing to a tenth of the time
# reached: the first is a thousandth of the first picture time, each next
# one 1.2 times the last, and none passes the next picture time.  Every
# step adds a row to ``seepage.csv``: the fluid in the joints, the same over
# their void (above 1 once full joints hold pressure, ``V (1 + p / Kw)``),
# the shares of the joints that are wet (S > 0) and full (S = 1), and the
# Newton solves the step took.


# %%
def step_to(
    seep: JointSeepage,
    target: float,
    clock: tuple[float, float],
    pressure: float,
    void: float,
    rows: list[dict],
) -> tuple[float, float]:
    """Step from ``clock = (t, dt)`` to ``target``; return the time reached and the next step.

    The wall is at ``pressure``; every step appends its row to ``rows``, the
    fluid over the joints' ``void`` (m^3) included.
    """
    t, dt = clock
    while t < target * (1 - 1e-12):
        dt = min(dt, target - t)
        seep.step(dt, pressure)
        t += dt
        sat = seep.saturation
        rows.append(
            {
                "time_s": t,
                "fluid_in_joints_m3": float(seep.content.sum()),
                "fluid_over_void": float(seep.content.sum()) / void,
                "wet_share_of_joints": float(np.mean(sat > 0.0)),
                "full_share_of_joints": float(np.mean(sat >= 1.0)),
                "newton_solves": seep.newton_iterations,
            }
        )
        dt = min(1.2 * dt, 0.1 * t)
    return t, dt


# %% [markdown]
# ## A frame at every picture time
#
# At each picture time the demo prints the wet and full shares beside the
# front of a single dry joint filled from the wall, ``sqrt(a^2 p t / 6 mu)``
# (cubic-law flow with the pressure falling linearly to the front), and
# writes the saturation and pressure of every joint into
# ``joints/frame_NNNN.vtu`` (each rank passes its owned joints, rank 0
# writes).


# %%
def write_frame(
    out: Path, index: int, points: np.ndarray, fields: dict[str, np.ndarray], comm: MPI.Comm
) -> str:
    """Write frame ``index`` of the joints at ``points``; return its name under ``out``."""
    name = f"joints/frame_{index:04d}.vtu"
    (out / "joints").mkdir(exist_ok=True)
    write_interfaces(out / name, points, fields, comm)
    return name


def fill_joints(
    seep: JointSeepage,
    aperture: float,
    pressure: float,
    times: list[float],
    out: Path,
    points: np.ndarray,
    position: np.ndarray,
    comm: MPI.Comm,
    say: Callable[..., None],
) -> tuple[list[dict], list[tuple[float, str]], list[np.ndarray], list[str]]:
    """Fill the joints to every picture time; return the rows, frames, panels and titles.

    ``points`` are the vertex coordinates of this rank's owned joints and
    ``position`` their places in the network.
    """
    rows, frames, panels, titles = [], [], [], []
    clock, void = (0.0, 1e-3 * times[0]), float(aperture * seep.net.area.sum())
    for target in times:
        clock = step_to(seep, target, clock, pressure, void, rows)
        t = clock[0]
        sat, p = seep.saturation, seep.pressure
        front = float(np.sqrt(aperture**2 * pressure * t / (6.0 * seep.fluid.viscosity)))
        say(
            f"t = {t:6.3g} s: {rows[-1]['wet_share_of_joints']:.1%} of the joints wet, "
            f"{rows[-1]['full_share_of_joints']:.1%} full; 1D front sqrt(a^2 p t / 6 mu) "
            f"= {front * 1e3:.0f} mm"
        )
        fields = {"saturation": sat[position], "pressure": p[position]}
        frames.append((t, write_frame(out, len(frames), points, fields, comm)))
        panels.append(sat[position])
        titles.append(f"t = {t:.3g} s")
    return rows, frames, panels, titles


# %% [markdown]
# ## The tables
#
# ``joints.pvd`` lists the frames with their times, so ParaView plays them
# as one series; ``seepage.csv`` holds a row per implicit step.


# %%
def write_tables(
    out: Path, frames: list[tuple[float, str]], rows: list[dict], comm: MPI.Comm
) -> None:
    """Write the frame series ``joints.pvd`` and the step table ``seepage.csv`` into ``out``."""
    if comm.rank == 0:
        write_atomic(out / "joints.pvd", pvd_text(frames))
    header = list(rows[0])
    write_csv(out / "seepage.csv", header, [[r[k] for k in header] for r in rows], comm)


# %% [markdown]
# ## The picture
#
# A slice, as the paper's cloud images: the joints within one wall element
# of the symmetry plane z = 0 (through the tunnel axis), seen along z, one
# panel per picture time, with the tunnel wall drawn in.


# %%
def draw_saturation(
    path: Path,
    scene: Scene,
    walls: np.ndarray,
    points: np.ndarray,
    panels: list[np.ndarray],
    titles: list[str],
    comm: MPI.Comm,
) -> None:
    """Draw the saturation ``panels`` of the joints ``points`` near z = 0 into ``path``."""
    layer = points[:, :, 2].mean(axis=1) < 1.5 * scene.geometry.mesh.size
    render_facet_series(
        path,
        points[layer],
        [v[layer] for v in panels],
        titles,
        walls,
        "saturation",
        0.0,
        comm,
        view_axis=2,
    )


# %% [markdown]
# ## The run
#
# Read the inputs, mesh the scene, build the dry joints, fill them to every
# picture time and write the tables and the picture (``--no-pictures``
# skips it).  The return value is what the test checks: the number of
# joints, the aperture and the rows of ``seepage.csv``.


# %%
def main(argv: list[str] | None = None) -> dict:
    """Fill the joints around No. 2 from dry; return the table of the picture times."""
    parser = argparse.ArgumentParser(description=__doc__ or "joint seepage around No. 2")
    parser.add_argument("-o", "--output", default="results/joint_seepage")
    parser.add_argument("--resolution", default="coarse", help="'coarse', 'default' or 'paper'")
    parser.add_argument("--pressure", default="60 MPa", help="tunnel wall pressure")
    parser.add_argument("--aperture", default=None, help="joint hydraulic aperture, e.g. '5 um'")
    parser.add_argument(
        "--times", default="0.05,0.2,1,5", help="picture times (s), comma separated"
    )
    parser.add_argument("--no-pictures", action="store_true", help="skip saturation.png")
    args, say = parse_demo_line(parser, argv)  # PETSc options too
    comm = MPI.COMM_WORLD

    scene = load_no2_scene(args.resolution)
    pressure = wall_pressure(args.pressure)
    aperture = joint_aperture(args.aperture, scene.physics.fluid)
    times = picture_times(args.times)
    out = prepare_output_dir(args.output, comm)
    tmesh = create_scene_mesh(scene, comm).tmesh
    solid, cavity, joints, seep = dry_joints(scene, tmesh, aperture)
    net = seep.net
    say(
        f"{net.size} joints of a = {aperture * 1e6:.3g} um around {', '.join(cavity)}, "
        f"{len(seep.cavity_facets)} joined to the wall; wall at {pressure / 1e6:.4g} MPa"
    )
    owned = joints[solid.owned[joints]]
    position = network_positions(solid, net, owned)
    points = solid.vertex_coords[owned]
    rows, frames, panels, titles = fill_joints(
        seep, aperture, pressure, times, out, points, position, comm, say
    )
    write_tables(out, frames, rows, comm)
    if not args.no_pictures:
        walls = owned_boundary_triangles(tmesh, cavity)
        draw_saturation(out / "saturation.png", scene, walls, points, panels, titles, comm)
    seep.destroy()
    say(f"written: {out / 'saturation.png'}, {out / 'seepage.csv'}, {out / 'joints.pvd'}")
    return {"joints": net.size, "aperture_m": aperture, "rows": rows}


# %%
if __name__ == "__main__":
    run_demo(main)

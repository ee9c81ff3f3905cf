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
import sys
from pathlib import Path

import numpy as np
from mpi4py import MPI

from hfcdem.cli import parse_with_petsc_options
from hfcdem.config.scene import load_scene
from hfcdem.config.units import parse_quantity
from hfcdem.coupling.condense import cavity_vertices
from hfcdem.flow.seepage import JointSeepage, joint_network, network_positions
from hfcdem.io.files import prepare_output_dir, write_atomic, write_csv, write_interfaces
from hfcdem.io.plots import owned_boundary_triangles, render_facet_series
from hfcdem.io.series import pvd_text
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.solid.interfaces import FacetState
from hfcdem.workflows.run import build_solid, pressurised_groups

ROOT = Path(__file__).resolve().parents[1]
PERMEABILITY_COEFFICIENT = 8.33e-11  # m^2/(Pa s), perforation paper Table 1


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
    args = parse_with_petsc_options(parser, argv)
    comm = MPI.COMM_WORLD
    say = print if comm.rank == 0 else (lambda *a, **k: None)

    # %% [markdown]
    # The scene: No. 2's mesh, rock and fluid; the joints are the interfaces of
    # the fracturable zone, the cavity the open tunnel wall.

    # %%
    resolution = None if args.resolution == "default" else args.resolution
    scene = load_scene(ROOT / "meshes/scenes/perforation_no2.toml", resolution)
    fluid = scene.physics.fluid
    pressure = parse_quantity(args.pressure, "stress", "--pressure")
    if not (math.isfinite(pressure) and pressure > 0.0):
        raise ValueError(f"--pressure must be > 0 Pa, got {args.pressure!r}")
    if args.aperture is None:
        aperture = math.sqrt(12.0 * fluid.viscosity * PERMEABILITY_COEFFICIENT)
    else:
        aperture = parse_quantity(args.aperture, "length", "--aperture")
    times = sorted(float(t) for t in args.times.split(","))
    if not times or times[0] <= 0.0:
        raise ValueError(f"--times must be positive seconds, got {args.times!r}")
    out = prepare_output_dir(args.output, comm)
    tmesh = create_scene_mesh(scene, comm).tmesh
    solid = build_solid(scene, tmesh)
    cavity = pressurised_groups(tmesh.facet_names, scene.physics.wellbore)
    joints = np.flatnonzero((solid.state == FacetState.INTACT) & ~solid.is_crack)
    net = joint_network(solid, cavity_vertices(solid, cavity, None), joints)
    seep = JointSeepage(net, aperture, fluid, filling="saturation", saturation=0.0)
    say(
        f"{net.size} joints of a = {aperture * 1e6:.3g} um around {', '.join(cavity)}, "
        f"{len(seep.cavity_facets)} joined to the wall; wall at {pressure / 1e6:.4g} MPa"
    )

    # %% [markdown]
    # Implicit steps, small where the front is fast (early), growing to a
    # tenth of the time reached.

    # %%
    owned = joints[solid.owned[joints]]
    position = network_positions(solid, net, owned)
    points = solid.vertex_coords[owned]
    rows, frames, panels, titles = [], [], [], []
    t, dt, void = 0.0, 1e-3 * times[0], float(aperture * net.area.sum())
    for target in times:
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
        sat, p = seep.saturation, seep.pressure
        front = float(np.sqrt(aperture**2 * pressure * t / (6.0 * fluid.viscosity)))
        say(
            f"t = {t:6.3g} s: {rows[-1]['wet_share_of_joints']:.1%} of the joints wet, "
            f"{rows[-1]['full_share_of_joints']:.1%} full; 1D front sqrt(a^2 p t / 6 mu) "
            f"= {front * 1e3:.0f} mm"
        )
        name = f"joints/frame_{len(frames):04d}.vtu"
        (out / "joints").mkdir(exist_ok=True)
        write_interfaces(
            out / name, points, {"saturation": sat[position], "pressure": p[position]}, comm
        )
        frames.append((t, name))
        panels.append(sat[position])
        titles.append(f"t = {t:.3g} s")
    if comm.rank == 0:
        write_atomic(out / "joints.pvd", pvd_text(frames))
    header = list(rows[0])
    write_csv(out / "seepage.csv", header, [[r[k] for k in header] for r in rows], comm)
    if not args.no_pictures:
        # a slice, as the paper's cloud images: the joints within one wall element of
        # the symmetry plane z = 0 (through the tunnel axis), seen along z
        layer = points[:, :, 2].mean(axis=1) < 1.5 * scene.geometry.mesh.size
        walls = owned_boundary_triangles(tmesh, cavity)
        render_facet_series(
            out / "saturation.png",
            points[layer],
            [v[layer] for v in panels],
            titles,
            walls,
            "saturation",
            0.0,
            comm,
            view_axis=2,
        )
    seep.destroy()
    say(f"written: {out / 'saturation.png'}, {out / 'seepage.csv'}, {out / 'joints.pvd'}")
    return {"joints": net.size, "aperture_m": aperture, "rows": rows}


if __name__ == "__main__":
    try:
        main()
    except (ValueError, KeyError) as err:
        if MPI.COMM_WORLD.rank == 0:
            print(f"error: {err}", file=sys.stderr)
        sys.exit(2)

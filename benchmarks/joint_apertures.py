"""Does No. 2's joint network take the same fluid on two meshes? Apertures plain or held.

Builds the joints of Perforation No. 2's fracturable zone (dry, water) at each
resolution named, holds the tunnel wall at a fixed pressure and takes implicit
steps of saturation filling (:class:`hfcdem.flow.seepage.JointSeepage`), once
with one aperture on every facet and once with the apertures held at a
reference cell size (:mod:`hfcdem.flow.apertures`).  Prints, per mesh and
rule: joints, their cell sizes, their void, the fluid taken and the share of
the void wet (saturation above 1/2) at a few times.  The fluid is water
(2.2 GPa) unless ``--bulk-modulus`` says otherwise.

    make run CMD="python3 benchmarks/joint_apertures.py --resolutions coarse default"
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from hfcdem.config.materials import JointAperture
from hfcdem.config.scene import load_scene
from hfcdem.coupling.condense import cavity_vertices
from hfcdem.flow.apertures import network_apertures, network_cell_sizes
from hfcdem.flow.seepage import JointSeepage, joint_network
from hfcdem.mesh.build import create_scene_mesh
from hfcdem.solid.interfaces import FacetState
from hfcdem.workflows.run import build_solid, pressurised_groups

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--resolutions", nargs="+", default=["coarse", "default"])
    ap.add_argument("--aperture", type=float, default=1e-6, help="m")
    ap.add_argument("--reference-size", type=float, default=5e-3, help="m")
    ap.add_argument("--pressure", type=float, default=30e6, help="Pa at the tunnel wall")
    ap.add_argument("--bulk-modulus", type=float, default=2.2e9, help="Pa (water's)")
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--dt", type=float, default=0.05, help="s")
    args = ap.parse_args()
    rows = []
    for res in args.resolutions:
        scene = load_scene(ROOT / "meshes/scenes/perforation_no2.toml", res)
        tmesh = create_scene_mesh(scene).tmesh
        solid = build_solid(scene, tmesh)
        cavity = pressurised_groups(tmesh.facet_names, scene.physics.wellbore)
        joints = np.flatnonzero((solid.state == FacetState.INTACT) & ~solid.is_crack)
        net = joint_network(solid, cavity_vertices(solid, cavity, None), joints)
        h = network_cell_sizes(solid, net, joints)
        fluid = replace(scene.physics.fluid, bulk_modulus=args.bulk_modulus)
        print(
            f"{res}: {net.size} joints, {net.area.sum():.4g} m^2, cell size {h.min() * 1e3:.3g}"
            f"-{h.max() * 1e3:.3g} mm (area-weighted mean "
            f"{(h * net.area).sum() / net.area.sum() * 1e3:.3g} mm)",
            flush=True,
        )
        for rule, ref in (("plain", None), ("held", args.reference_size)):
            hyd, void = network_apertures(solid, net, joints, JointAperture(args.aperture, ref))
            seep = JointSeepage(
                net, hyd, fluid, filling="saturation", saturation=0.0,
                void_aperture=void,
            )  # fmt: skip
            taken, t0 = [], time.perf_counter()
            for k in range(1, args.steps + 1):
                seep.step(args.dt, args.pressure)
                if k % max(1, args.steps // 4) == 0:
                    wet = float(seep.void @ (seep.saturation > 0.5)) / float(seep.void.sum())
                    held = seep.content.sum()
                    taken.append(f"{k * args.dt:.2f} s: {held:.4g} m^3, {wet:.1%}")
            seep.destroy()
            rows.append((res, rule, float(seep.void.sum()), taken, time.perf_counter() - t0))
    print("\n| mesh | apertures | void m^3 | fluid taken, share of the void wet | s |")
    print("|---|---|---|---|---|")
    for res, rule, void_total, taken, seconds in rows:
        print(f"| {res} | {rule} | {void_total:.4g} | {'; '.join(taken)} | {seconds:.1f} |")


if __name__ == "__main__":
    main()

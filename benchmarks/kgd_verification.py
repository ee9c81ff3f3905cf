"""KGD verification table: the coupled solver against the self-similar solutions.

Seed 000 section 4.2 (its Figs. 8-10): a plane-strain hydraulic fracture driven
by water at Q0 = 4e-3 m^3/s per metre into rock with E = 25 GPa, nu = 0.25, zero
toughness and no leak-off, with and without a 5 MPa background stress; compared
at t = 10 s with the zero-toughness solution (design.md).  Then the mesh is
fixed and the time step varied, and the toughness-dominated growth exponent is
measured.  Run inside the image::

    make run CMD="python3 benchmarks/kgd_verification.py"

Prints one row per run: errors in half-length, net inlet pressure and inlet
opening, the worst mass-balance figures over all steps, and the wall time.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from mpi4py import MPI

from hfcdem.analytic import kgd_viscosity
from hfcdem.config.materials import ElasticMaterial, Fluid, Injection, InSituStress, InterfaceModel
from hfcdem.config.parts import Crack, MeshSizing, Plate
from hfcdem.config.plates import KGDStrip
from hfcdem.coupling.hydrofrac import FlowSettings, HydraulicFracture
from hfcdem.mesh.build import mesh_geometry
from hfcdem.solid.cdem import CDEMSolid

ROCK = ElasticMaterial(25e9, 0.25)
Q0 = 4e-3


def run(
    dx: float,
    dt: float,
    stress: float,
    strength: float = 0.0,
    fidelity: str = "viscous",
    t_end: float = 10.0,
) -> tuple[HydraulicFracture, float, list[tuple[float, float]]]:
    """One KGD run on a half model; returns the solver, its wall time and l(t)."""
    t0 = time.perf_counter()
    # half model 200 m wide: one open facet at the inlet, a 32 m path of dx facets
    sizing = MeshSizing(dx, 40.0, grading=0.3, path_size=dx, size_integration="exact")
    tm = mesh_geometry(KGDStrip(Plate(400.0, 400.0), Crack(2 * dx, 64.0), sizing, symmetry=("x",)))
    solid = CDEMSolid(
        tm,
        ROCK,
        InSituStress(stress, stress, stress),
        InterfaceModel(alpha=1e3, tensile_strength=strength, cohesion=1e10, break_rule="all"),
        zone="fracture_path",
        rollers={"symmetry_x": 0},
        fixed=tm.facet_groups("outer"),
    )
    hf = HydraulicFracture(
        solid,
        Fluid(viscosity=1e-3),
        Injection.constant_rate(Q0 / 2),
        FlowSettings(
            injection_point=(0.0, 0.0),
            filling="no_lag",
            fidelity=fidelity,
            dt_initial=dt,
            dt_max=dt,
            initial_pressure=stress,
        ),
    )
    growth = []
    while hf.t < t_end * (1 - 1e-12):
        hf.dt = min(hf.dt, t_end - hf.t)
        rec = hf.step()
        growth.append((rec.time, hf.wet_extent((0.0, 0.0), (1.0, 0.0))))
    return hf, time.perf_counter() - t0, growth


def row(label: str, hf: HydraulicFracture, wall: float, stress: float) -> str:
    ref = kgd_viscosity(hf.t, Q0, ROCK.youngs_modulus, ROCK.poisson_ratio, 1e-3)
    length = hf.wet_extent((0.0, 0.0), (1.0, 0.0))
    err = [
        100 * (length / ref.half_length - 1),
        100 * ((hf.p_cavity - stress) / ref.net_pressure - 1),
        100 * (hf.opening_at_cavity() / ref.inlet_opening - 1),
    ]
    mass = max(r.mass_error for r in hf.history)
    mismatch = max(r.volume_mismatch for r in hf.history)
    return (
        f"| {label} | {length:.2f} | {err[0]:+.1f} % | {err[1]:+.1f} % | {err[2]:+.1f} % | "
        f"{mass:.0e} | {mismatch:.0e} | {len(hf.history)} | {wall:.1f} s |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="coarse meshes only")
    args = parser.parse_args()
    rank0 = MPI.COMM_WORLD.rank == 0
    sizes = [4.0, 2.0, 1.0] if args.quick else [4.0, 2.0, 1.0, 0.5, 0.25]
    ref = kgd_viscosity(10.0, Q0, ROCK.youngs_modulus, ROCK.poisson_ratio, 1e-3)
    if rank0:
        print(
            f"KGD at t = 10 s: l = {ref.half_length:.3f} m, p_net = {ref.net_pressure / 1e6:.4f} "
            f"MPa, w(0) = {ref.inlet_opening * 1e3:.4f} mm; ranks {MPI.COMM_WORLD.size}"
        )
        print("| run | l (m) | l | p_net(0) | w(0) | mass error | volume mismatch | steps | wall |")
        print("|---|---|---|---|---|---|---|---|---|")
    for stress in (0.0, 5e6):
        for dx in sizes:
            hf, wall, _ = run(dx, 0.5, stress)
            if rank0:
                print(
                    row(f"dx {dx} m, dt 0.5 s, sigma0 {stress / 1e6:g} MPa", hf, wall, stress),
                    flush=True,
                )
    for dt in (2.0, 1.0, 0.5, 0.25):
        hf, wall, _ = run(0.5 if not args.quick else 1.0, dt, 0.0)
        if rank0:
            print(
                row(f"dt {dt} s, dx {0.5 if not args.quick else 1.0} m", hf, wall, 0.0), flush=True
            )
    # toughness dominated: strength-based toughness, uniform pressure, growth exponent
    hf, wall, growth = run(0.5, 0.5, 0.0, strength=10e6, fidelity="uniform", t_end=20.0)
    t, length = np.array(growth).T
    sel = (length > 8.0) & (length < 24.0)
    exponent = np.polyfit(np.log(t[sel]), np.log(length[sel]), 1)[0]
    if rank0:
        print(
            f"toughness dominated (T0 10 MPa, dx 0.5 m, uniform pressure): l ~ t^{exponent:.4f} "
            f"({100 * (exponent / (2 / 3) - 1):+.1f} % from 2/3), {wall:.1f} s"
        )


if __name__ == "__main__":
    main()

"""The cases of the reproduction report: what each runs and what it is compared with.

A :class:`Case` names a scene or study file of the checkout, how it runs in
each tier (``quick``: the whole report in minutes on 2 cores; ``full``: every
case, at the resolutions the project can afford) and a function that turns
its results into :class:`Comparison` rows: the paper's value (or a closed
form), ours, the target and whether it is met.  A paper's number that rests on
the paper's own choices (an assumed profile, a number read off a figure) says
so in the row's note.  Papers' values live in :mod:`hfcdem.references`.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hfcdem import references
from hfcdem.reproduce.compare import (
    DEGREE_FIGURE,
    STRESS_FIGURE,
    CaseResult,
    Comparison,
    all_tensile,
    borehole_limit,
    four_charges,
    griffith,
    kgd,
    lab_specimen,
    paper_trend,
    peak_against,
    shape_study,
    sneddon,
    trend,
)
from hfcdem.reproduce.kgd_series import (
    kgd_series,
    longer_step_runs_further,
    stress_worsens_coarse,
)
from hfcdem.reproduce.rubin import rubin
from hfcdem.reproduce.saturation import SATURATION_FIGURE, SEEPAGE_RUNG, saturation_in_time

#: what the shear-share cases' mesh does to their answer (benchmarks/README, 2026-12-05)
_SHARE_MESHES = (
    "coarse (a/5 at the wall); at point strength the share grows with the mesh: 15 / 21 / "
    "41 % at a/5 / a/10 / a/20 (2 cm3/s per m)"
)

TIERS = ("quick", "full")
FIDELITIES = ("scene", "uniform", "viscous", "seepage")

PAPERS = {
    "perforation": "CDEM perforation paper (seed cdem-perforation-breakdown): breakdown "
    "from 3D perforation tunnels",
    "hfdda": "Implicit DDA paper (seed hfdda-implicit-dda-hydraulic-fracture): "
    "Griffith, KGD, Rubin's PMMA experiment",
    "pfc2d": "PFC2D paper (seed pfc2d-fluid-driven-fracture): borehole breakdown, "
    "stress ratio, rate and viscosity",
    "dem-lbm": "DEM-LBM paper (seed dem-lbm-influential-factors): rate, viscosity, stress, "
    "heterogeneity and permeability",
}


@dataclass(frozen=True)
class Tier:
    """How a case runs in one tier.

    ``resolution``: the scene's named mesh resolution (None: its default mesh);
    ``values``: the swept values of a study (None: the study file's);
    ``fixed``: scene fields set in every run; ``estimate_s``: the wall time
    on one rank of the project's machine, for the time-left estimate before
    the case has run (1.4 times the 2-rank wall times of the reports of
    2026-12-06, docs/reproduction).
    """

    resolution: str | None = None
    values: tuple[Any, ...] | None = None
    fixed: Mapping[str, Any] = field(default_factory=dict)
    estimate_s: float = 60.0


@dataclass(frozen=True)
class Case:
    """A case of the report.

    ``kind``: ``scene``, ``study`` (a sweep), ``convergence`` or ``missing``
    (not modelled yet: listed, not run).  ``source``: the scene or study file,
    from the checkout's root.  ``discretisation``: what is known of the
    discretisation error at the tiers' resolutions, with its source, when the
    case does not estimate it itself.  ``figures``: files of the case's
    output shown in the report.
    """

    name: str
    paper: str
    title: str
    kind: str
    source: str | None
    tiers: Mapping[str, Tier]
    compare: Callable[[CaseResult], list[Comparison]] | None = None
    discretisation: str = ""
    note: str = ""
    figures: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.paper not in PAPERS:
            raise ValueError(f"case {self.name}: unknown paper {self.paper!r}")
        if self.kind not in ("scene", "study", "convergence", "missing"):
            raise ValueError(f"case {self.name}: unknown kind {self.kind!r}")
        for tier in self.tiers:
            if tier not in TIERS:
                raise ValueError(f"case {self.name}: unknown tier {tier!r}")


# -- the cases --------------------------------------------------------------------

# a/10, a/20, a/40 at the wall.  Not a/80: there the excavation alone overstresses 91
# interfaces at the outer edge of the 4 structured wall rings (1.5 mm from the wall; DG1
# traction at their vertices, 5.6 MPa of tension against T0 = 5) and the cascade breaks
# the whole zone before any pressure (12,769 failures); at a/40 one such interface.
_BOREHOLE_H = ("3 mm", "1.5 mm", "0.75 mm")

CASES: tuple[Case, ...] = (
    Case(
        "sneddon",
        "perforation",
        "Sneddon plate (sec. 3.1, Table 1, 11 points)",
        "scene",
        "meshes/scenes/sneddon_plate.toml",
        {"quick": Tier("coarse", estimate_s=2), "full": Tier(None, estimate_s=2)},
        sneddon,
        discretisation="DG2; README 'What is verified': -0.82 % (a/10) to -0.13 % (a/160) "
        "on a 50a plate; here the 1 m plate's own stiffness dominates",
        figures=("crack_opening.png",),
    ),
    Case(
        "kgd",
        "hfdda",
        "KGD, zero toughness (sec. 4.2, Figs. 8-10)",
        "scene",
        "meshes/scenes/kgd_strip.toml",
        {"quick": Tier("coarse", estimate_s=4), "full": Tier(None, estimate_s=7)},
        kgd,
        discretisation="benchmarks/kgd_verification.py: dx 0.5 m on a 400 m plate: "
        "l -0.6 %, p +2.8 %, w -0.1 %",
        figures=("pressure.png",),
    ),
    Case(
        "kgd_mesh",
        "hfdda",
        "KGD mesh series, no background stress (sec. 4.2, Fig. 8)",
        "study",
        "studies/kgd_mesh.toml",
        {"quick": Tier(estimate_s=18), "full": Tier(estimate_s=14)},
        kgd_series("dx", None, "Fig. 8"),
        discretisation="the series is the mesh study: dx = 4 -> 0.5 m along the path",
        figures=("series.png",),
    ),
    Case(
        "kgd_mesh_stress",
        "hfdda",
        "KGD mesh series, 5 MPa background stress (sec. 4.2, Fig. 9)",
        "study",
        "studies/kgd_mesh_stress.toml",
        {"quick": Tier(estimate_s=15), "full": Tier(estimate_s=13)},
        kgd_series("dx", stress_worsens_coarse, "Fig. 9"),
        discretisation="the series is the mesh study: dx = 4 -> 0.5 m along the path",
        figures=("series.png",),
    ),
    Case(
        "kgd_time_step",
        "hfdda",
        "KGD time-step series at dx = 0.5 m (sec. 4.2, Fig. 10)",
        "study",
        "studies/kgd_time_step.toml",
        {"quick": Tier(estimate_s=37), "full": Tier(estimate_s=34)},
        kgd_series("dt", longer_step_runs_further, "Fig. 10"),
        discretisation="the series is the time-step study: dt = 2 -> 0.25 s",
        figures=("series.png",),
    ),
    Case(
        "griffith",
        "hfdda",
        "Griffith crack with background stress (sec. 4.1, Table 1, eq. 17)",
        "scene",
        "meshes/scenes/griffith_plate.toml",
        {"quick": Tier("coarse", estimate_s=1), "full": Tier(None, estimate_s=1)},
        griffith,
        discretisation="DG2; centre opening -4.12 / -3.78 / -3.55 % at h = 1 / 0.5 / "
        "0.25 m (L/10 to L/40) on the 100 m plate: the plate's fixed edges dominate",
        figures=("crack_opening.png",),
    ),
    Case(
        "rubin",
        "hfdda",
        "Rubin's PMMA experiment (sec. 4.3, Figs. 11-15)",
        "scene",
        "meshes/scenes/rubin_pmma.toml",
        {"quick": Tier("coarse", estimate_s=7), "full": Tier(None, estimate_s=7)},
        rubin,
        discretisation="the peak moves with the mesh: 8.17 MPa (coarse, 586 cells), 7.66 "
        "(default, 1,776), 6.99 (4.5 mm, 3,536), 6.29 (3.25 mm, 6,650); within 1 % of its "
        "short-step limit on each; D wet at 34-37 s (benchmarks/rubin_convergence.py)",
        note="paper prints only figures (Figs. 12-13: pressures at the borehole and gauges "
        "A, B, D, width at C, lengths either side): those rows are ours alone; the judged "
        "rows check what the text states. The soft outer frame is left out (one material "
        "per scene): free edges fixed at the corners (scene file)",
        figures=("gauges.png",),
    ),
    Case(
        "hubbert_willis",
        "pfc2d",
        "Borehole breakdown, non-penetrating limit (fast ramp)",
        "convergence",
        "studies/hubbert_willis_limit.toml",
        {
            "quick": Tier(values=_BOREHOLE_H, estimate_s=28),
            "full": Tier(values=_BOREHOLE_H, estimate_s=25),
        },
        borehole_limit(wet=False),
        figures=("convergence.png",),
    ),
    Case(
        "haimson_fairhurst",
        "pfc2d",
        "Borehole breakdown, penetrating limit (slow ramp)",
        "convergence",
        "studies/haimson_fairhurst_limit.toml",
        {
            "quick": Tier(values=_BOREHOLE_H, estimate_s=27),
            "full": Tier(values=_BOREHOLE_H, estimate_s=23),
        },
        borehole_limit(wet=True),
        figures=("convergence.png",),
    ),
    Case(
        "stress_ratio",
        "pfc2d",
        "Breakdown against Sh (SH 20 MPa), seepage ramp 1 MPa/s",
        "study",
        "studies/borehole_seepage_stress_ratio.toml",
        {"quick": Tier("coarse", estimate_s=15), "full": Tier(None, estimate_s=12)},
        trend(
            "breakdown against Sh",
            paper_trend(references.PFC2D_STRESS_RATIO, "Sh", 1e-6, "MPa", "sec. 4.1, 1e-5 m3/s"),
            True,
            1e-6,
            "MPa",
        ),
        discretisation="a/5 (coarse) / a/10: the dry limit is -31 % / -23 % of its "
        "converged value (benchmarks/README.md, penetration_rate.py); the trend at a/10: "
        "+258 % (6.39 -> 22.87 MPa)",
        figures=("study.png",),
    ),
    Case(
        "rate",
        "pfc2d",
        "Breakdown against pressurisation rate (borehole, seepage; the paper pumps at a rate)",
        "study",
        "studies/borehole_seepage_rate.toml",
        {
            "quick": Tier("coarse", ("0.1 MPa/s", "3 MPa/s", "100 MPa/s"), estimate_s=8),
            "full": Tier(None, estimate_s=15),
        },
        trend(
            "breakdown against rate",
            paper_trend(references.PFC2D_RATE, "rate", 1.0, "m3/s", "sec. 4.2")
            + "; DEM-LBM: rises (no values printed)",
            True,
            1e-6,
            "MPa/s",
        ),
        discretisation="the transition collapses on A t_h / P_dry at a/5-a/40 "
        "(docs/images/penetration_rate.png)",
        figures=("study.png",),
    ),
    Case(
        "viscosity",
        "pfc2d",
        "Breakdown against viscosity (borehole, seepage)",
        "study",
        "studies/borehole_seepage_viscosity.toml",
        {
            "quick": Tier("coarse", ("1 mPa.s", "1 Pa.s", "10 Pa.s"), estimate_s=10),
            "full": Tier(None, estimate_s=15),
        },
        trend(
            "breakdown against viscosity",
            paper_trend(references.PFC2D_VISCOSITY, "viscosity", 1.0, "Pa s", "sec. 4.3")
            + "; DEM-LBM: rises (no values printed)",
            True,
            1.0,
            "Pa s",
        ),
        discretisation="a/5 (coarse); at a/10 the same way, smaller: +13 % (9.12 -> 10.34 "
        "MPa, monotone; at a/5 the 10 Pa s case sits at the dry limit)",
        figures=("study.png",),
    ),
    Case(
        "permeability",
        "dem-lbm",
        "Breakdown against joint aperture (permeability)",
        "study",
        "studies/borehole_seepage_aperture.toml",
        {
            "quick": Tier("coarse", ("1 um", "5 um", "20 um"), estimate_s=9),
            "full": Tier(None, estimate_s=12),
        },
        trend(
            "breakdown against permeability",
            "falls as permeability rises (sec. 3.5; no values printed)",
            False,
            1e6,
            "um",
        ),
        discretisation="a/5 (coarse); at a/10 the same way: -22 % (11.80 -> 9.17 MPa, monotone)",
        figures=("study.png",),
    ),
    Case(
        "weibull",
        "dem-lbm",
        "Breakdown against Weibull modulus m (heterogeneity)",
        "study",
        "studies/borehole_seepage_weibull.toml",
        {"full": Tier(None, estimate_s=9)},
        trend(
            "breakdown against Weibull m",
            "rises as the rock gets more homogeneous, larger m (sec. 3.4; no values printed)",
            True,
            1.0,
            "",
        ),
        discretisation="a/5 (coarse); at a/10 the same way, smaller: +4.9 % (9.25 -> 9.70 "
        "MPa; one step of -0.2 % against it)",
        figures=("study.png",),
    ),
    Case(
        "shear_rate",
        "dem-lbm",
        "Shear share of the failures against the pumping rate (pumped borehole)",
        "study",
        "studies/borehole_pumping_shear_rate.toml",
        {"full": Tier(None, estimate_s=200)},  # listed, not judged: not in the quick tier
        trend(
            "shear share of the failures against rate",
            "rises with the injection rate; all tensile at the lowest (sec. 3.1, Fig. 4)",
            True,
            1e6,
            "cm3/s per m",
            shear_share=True,
        ),
        discretisation=_SHARE_MESHES,
        note="the DEM-LBM set-up where it bears on the failure mode: no in-situ stress, "
        "shear strength 2.1 times the tensile one (its B_t / B_n), no friction",
        figures=("study.png",),
    ),
    Case(
        "shear_viscosity",
        "dem-lbm",
        "Shear share of the failures against the fluid viscosity (pumped borehole)",
        "study",
        "studies/borehole_pumping_shear_viscosity.toml",
        {"full": Tier(None, estimate_s=170)},  # listed, not judged: not in the quick tier
        trend(
            "shear share of the failures against viscosity",
            "rises with the viscosity; all tensile at the lowest (sec. 3.2, Fig. 8)",
            True,
            1.0,
            "Pa s",
            shear_share=True,
        ),
        discretisation=_SHARE_MESHES,
        note="as shear_rate, at 2 cm3/s per m",
        figures=("study.png",),
    ),
    Case(
        "shear_weibull",
        "dem-lbm",
        "Shear share of the failures against Weibull modulus m (pumped borehole)",
        "study",
        "studies/borehole_pumping_shear_weibull.toml",
        {"full": Tier(None, estimate_s=200)},  # listed, not judged: not in the quick tier
        trend(
            "shear share of the failures against Weibull m",
            "falls sharply as the rock gets more homogeneous, larger m; 41 % (32 of 78) at "
            "m = 2 (sec. 3.4, Fig. 18)",
            False,
            1.0,
            "",
            shear_share=True,
        ),
        discretisation=_SHARE_MESHES,
        note="as shear_rate, at 2 cm3/s per m; one realisation per m",
        figures=("study.png",),
    ),
    Case(
        "shear_permeability",
        "dem-lbm",
        "Shear share of the failures against the joints' permeability (pumped borehole)",
        "study",
        "studies/borehole_pumping_shear_permeability.toml",
        {"quick": Tier(None, estimate_s=240), "full": Tier(None, estimate_s=240)},
        all_tensile(
            "shear share of the failures against permeability",
            "all tensile, insignificant shear strain, at every permeability (sec. 3.5, "
            "Figs. 20-21)",
            1e6,
            "um",
        ),
        discretisation=_SHARE_MESHES,
        note="as shear_rate, at 2 cm3/s per m; the joints' aperture sets their cubic-law "
        "permeability",
        figures=("study.png",),
    ),
    Case(
        "lab_specimen",
        "perforation",
        "Lab specimen, azimuth 30/45/60 deg (sec. 3.2)",
        "study",
        "studies/lab_azimuth.toml",
        {"quick": Tier("coarse", estimate_s=210), "full": Tier("coarse", estimate_s=200)},
        lab_specimen,
        discretisation="coarse (2 mm at the perforations); at the default mesh (1 mm) 60 deg "
        "peaks at 10.07 MPa (+1.6 %), again cut short by the validity limit (2.5 s), with "
        "3,693 failures against 98 and the fracture 2.7 mm past the tips against 9.9 mm "
        "(benchmarks/README, 2026-12-05)",
        note="dry joints, as the scene files say (a calibration choice, see the README)",
        figures=("study.png",),
    ),
    Case(
        "no2",
        "perforation",
        "Perforation No. 2, the main scene (sec. 4, Fig. 15)",
        "scene",
        "meshes/scenes/perforation_no2.toml",
        {"quick": Tier("coarse", estimate_s=48), "full": Tier("coarse", estimate_s=48)},
        peak_against(
            "breakdown (peak pressure)",
            references.CHARGES["no2"],
            "the paper's CDEM (Fig. 15)",
            0.05,
            "calibrated film, start and duration (scene file)",
            stress=True,
        ),
        discretisation="the first crack is not converged in the mesh: at h = 10.2 / 3.6 / 2.7 / "
        "2.1 mm at the tunnel wall it comes at 61.64 / 58.05 / 55.82 / 51.03 MPa, from the two "
        "finer meshes on as a shear at the tunnel's tip (strength at a point meets the stress "
        "singularity of the tunnel's edges); over a strength length of 6 mm it comes at "
        "62.03 / 60.48 / 60.16 / 59.84 MPa with the root, middle and far end within 2 % of "
        "their strength (benchmarks/first_crack_mesh.py, 2026-12-06); coarse -> default moves "
        "the root's highest failure ratio then from 0.87 to 0.91, "
        "the largest sigma_xx of the root's third from -70.3 to -68.0 MPa, no cell in "
        "tension at either; over the whole 120 s the default mesh has no breakdown: its "
        "pressure levels off at 61-63 MPa and ends at 63.04 MPa, still rising, 1.7 % below "
        "the coarse 64.11 MPa peak (benchmarks/README.md, 2026-12-04)",
        figures=("pressure.png", "fracture.png", STRESS_FIGURE),
    ),
    Case(
        "no2_seepage",
        "perforation",
        "Perforation No. 2 with the joints filling in time (sec. 4.4, Figs. 14 and 15)",
        "scene",
        "meshes/scenes/perforation_no2.toml",
        {"full": Tier("coarse", fixed=SEEPAGE_RUNG, estimate_s=750)},
        saturation_in_time,
        discretisation="large: the joints' void follows the mesh (1.085 / 2.071 / 3.217 m^2 "
        "of joints in the zone at the coarse / default / paper mesh, docs/seepage.md); at the "
        "default mesh (with solver.break_landing = 'step', one run to 75.7 s) the pressure "
        "dips to 7.0 MPa instead of 17.5 and trails the coarse one by 10-17 MPa from 5 s on "
        "(54.6 against 64.8 MPa at 75 s; benchmarks/README.md, 2026-12-05)",
        note="the fidelity ladder's seepage rung (benchmarks/fidelity_ladder.py)",
        figures=(SATURATION_FIGURE, "pressure.png", STRESS_FIGURE),
    ),
    Case(
        "four_charges",
        "perforation",
        "The four charges (sec. 4.4, Fig. 15)",
        "study",
        "studies/four_charges.toml",
        {"full": Tier("coarse", estimate_s=260)},
        four_charges,
        discretisation="peaks as No. 2; the first cracks are not converged in the mesh: "
        "coarse -> default moves them by -4.3 / -5.8 / -11.3 / -14.7 % (No. 1-4), and No. 4's "
        "comes at 62.12 / 52.99 / 46.51 MPa at h = 9.9 / 3.2 / 2.4 mm, a shear at the tunnel's "
        "tip on the finer two; its part of the tunnel changes with the mesh "
        "(benchmarks/first_crack_mesh.py, 2026-12-06)",
        figures=("study.png", DEGREE_FIGURE, STRESS_FIGURE),
    ),
    Case(
        "shape_study",
        "perforation",
        "The shape study (sec. 5, Tables 7-8, Fig. 21)",
        "study",
        "studies/shape_study.toml",
        {"full": Tier("coarse", estimate_s=640)},
        shape_study,
        discretisation="peaks as No. 2; the first cracks move by -4.7 to -11.7 % from the "
        "coarse to the default mesh, and their spread over the nine shapes and four charges "
        "grows from 2.7 to 5.1 MPa, so the first crack's dependence on shape is not resolved "
        "(benchmarks/first_crack_mesh.py, 2026-12-06)",
        figures=("study.png", DEGREE_FIGURE),
    ),
    Case(
        "field_cluster",
        "perforation",
        "Field cluster, Changqing (sec. 3.3)",
        "scene",
        "meshes/scenes/field_cluster.toml",
        {"full": Tier("coarse", estimate_s=570)},
        peak_against(
            "breakdown (peak pressure)",
            references.FIELD_MEASURED,
            "measured in the field",
            0.10,
            f"the paper's CDEM: {references.FIELD_PAPER_SIMULATED} MPa",
        ),
        discretisation="the peak's not measured (coarse, 19k cells); the first crack is not "
        "converged at a point: coarse -> default (53k cells) moves it from 30.37 to 23.20 MPa "
        "(-23.6 %), a shear at the far end on both; over a strength length of 6 mm 36.80 -> "
        "36.47 MPa (-0.9 %), tensile, the root and middle within 1 % of each other "
        "(benchmarks/first_crack_mesh.py, 2026-12-07)",
        figures=("pressure.png", "fracture.png"),
    ),
)


def select_cases(tier: str, only: Sequence[str] | None = None) -> list[Case]:
    """Return the cases of ``tier`` (all tiers' cases named in ``only``, in registry order).

    Raises ValueError naming the unknown tier or case names.
    """
    if tier not in TIERS:
        raise ValueError(f"tier: expected one of {', '.join(TIERS)}, got {tier!r}")
    names = {c.name for c in CASES}
    if only:
        unknown = [n for n in only if n not in names]
        if unknown:
            raise ValueError(
                f"--only: unknown case(s) {', '.join(unknown)}; the cases are "
                + ", ".join(c.name for c in CASES)
            )
        return [c for c in CASES if c.name in only and tier in c.tiers]
    return [c for c in CASES if tier in c.tiers]


def case_resolutions(case: Case, root: Path) -> frozenset[str] | None:
    """Return the mesh resolutions the case's scene names, with ``default``.

    A study's or convergence study's are those of its scene file, its
    ``geometry.catalogue`` entry's included.  ``root``: the checkout (where
    ``case.source`` is).  None when the files cannot be read: the run says why.
    """
    from hfcdem.config.catalogue import PRESETS, lookup_preset

    if case.source is None:
        return frozenset()
    try:
        path = root / case.source
        data = tomllib.loads(path.read_text())
        if case.kind != "scene":
            data = tomllib.loads((path.parent / str(data["scene"])).read_text())
        geometry = data.get("geometry", {})
        names = set(_named(geometry))
        if geometry.get("catalogue") in PRESETS:
            names |= set(_named(lookup_preset(geometry["catalogue"])))
    except (OSError, KeyError, AttributeError, tomllib.TOMLDecodeError):
        return None
    return frozenset({"default", *names})


def _named(geometry: Mapping[str, Any]) -> Mapping[str, Any]:
    """Return the ``mesh.resolutions`` table of a geometry table (empty when it has none)."""
    named = geometry.get("mesh", {}).get("resolutions", {})
    return named if isinstance(named, Mapping) else {}


__all__ = [
    "CASES",
    "FIDELITIES",
    "PAPERS",
    "TIERS",
    "Case",
    "CaseResult",
    "Comparison",
    "Tier",
    "case_resolutions",
    "select_cases",
]

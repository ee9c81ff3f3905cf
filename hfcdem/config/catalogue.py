"""Named perforation profiles and scene presets from the seed papers.

Profiles are cross-section diameters ``d1..dn`` at cumulative stations from the
wellbore wall, given as segment lengths ``l1..l(n-1)`` (seed
cdem-perforation-breakdown.txt, section 4-5):

========  =================================================  ==========================
name      what                                               source
========  =================================================  ==========================
no2       39 g DP3 HMX, 230 mm                               Table 7 row 1, Table 8 row 1
no1       25 g DP3 HMX, 235 mm                               Table 5 length; ASSUMED shape
no3       89-type deep-penetrating charge, 200 mm            Table 5 length; ASSUMED shape
no4       95-type deep-penetrating charge, 195 mm            Table 5 length; ASSUMED shape
1-1       cylinder of No. 2's entry diameter 33.44 mm         Table 7
1-2       cylinder of No. 2's far-end diameter 50 mm          Table 7
1-3       cylinder of No. 2's volume and length              computed (see below)
1-3-paper cylinder of the printed 36.34 mm                   Table 7 as printed
2-1, 2-2  far-well section diameters +10 / -10 mm            Table 7
3-1, 3-2  near-well section diameters +10 / -10 mm           Table 7
4-1, 4-2  every segment +10 / -10 mm (280 / 180 mm long)     Table 8
lab       2 mm x 30 mm cylinder (lab specimen)               Table 2
cluster   20 mm x 400 mm cylinder (field cluster)            section 3.3
========  =================================================  ==========================

Notes on the paper's numbers:

* The paper prints the sections of No. 1, 3 and 4 only in a figure.  The
  profiles here are ASSUMED: No. 2's profile truncated (No. 3 at 200 mm, No. 4
  at 195 mm, interpolating linearly) or extended at its last slope (No. 1 at
  235 mm).  The paper says the four tunnels narrow then widen with similar
  near-well sections, so the near-well part (0-150 mm) is No. 2's.  They are
  flagged ``assumed`` and the mesh report says so; give ``diameters`` and
  ``lengths`` in a scene to replace them.
* Model 1-3 is "the cylinder of Perforation No. 2's volume and length".  By
  conical frustums through Table 7's sections that cylinder has d = 34.86 mm,
  not the 36.34 mm printed (the paper took the volume from CAD).  ``1-3`` uses
  the computed value, ``1-3-paper`` the printed one; the mesh report gives both.
* Section 5.2 of the paper quotes 68.75 MPa for Model 4-1 and 56.97 MPa for
  4-2 while arguing that the longer tunnel breaks down at a lower pressure: the
  two pressures are swapped in the text (4-1, 280 mm, is the one at 56.97 MPa).
  This does not change the geometry here.
"""

from __future__ import annotations

import copy
from typing import Any

from hfcdem.analytic import equal_volume_cylinder_diameter

MM = 1e-3

_NO2_D = (33.44, 33.33, 28.80, 23.50, 48.77, 50.00)
_NO2_L = (50.0, 50.0, 50.0, 50.0, 30.0)


def _stations(lengths: tuple[float, ...]) -> tuple[float, ...]:
    out = [0.0]
    for segment in lengths:
        out.append(out[-1] + segment)
    return tuple(out)


def _no2_diameter_at(station: float) -> float:
    """No. 2's diameter (mm) at ``station`` (mm): linear between sections and past the tip."""
    s = _stations(_NO2_L)
    for i in range(len(s) - 1):
        if station <= s[i + 1] or i == len(s) - 2:
            t = (station - s[i]) / (s[i + 1] - s[i])
            return _NO2_D[i] + t * (_NO2_D[i + 1] - _NO2_D[i])
    raise AssertionError("unreachable")


# D(1-3) from the frustums of Table 7 row 1 (34.86 mm); the paper prints 36.34 mm
D13_COMPUTED_MM = equal_volume_cylinder_diameter(_NO2_D, _stations(_NO2_L))
D13_PAPER_MM = 36.34

_ASSUMED = (
    "ASSUMED profile: the paper gives only the length (Table 5); sections are No. 2's "
    "(Table 7-8 row 1) {how} to {length:g} mm"
)


def _assumed(length: float, how: str) -> dict[str, Any]:
    lengths = [50.0] * int(length // 50.0)
    if length - sum(lengths) > 1e-9:
        lengths.append(length - sum(lengths))
    stations = _stations(tuple(lengths))
    return {
        "diameters_mm": tuple(round(_no2_diameter_at(s), 4) for s in stations),
        "lengths_mm": tuple(lengths),
        "assumed": True,
        "source": _ASSUMED.format(how=how, length=length),
    }


def _table7(diameters: tuple[float, ...], row: str) -> dict[str, Any]:
    return {
        "diameters_mm": diameters,
        "lengths_mm": _NO2_L,
        "assumed": False,
        "source": f"Table 7 row {row} (diameters), Table 8 row 1 (lengths)",
    }


def _cylinder(diameter: float, lengths: tuple[float, ...], source: str) -> dict[str, Any]:
    return {
        "diameters_mm": (diameter,) * (len(lengths) + 1),
        "lengths_mm": lengths,
        "assumed": False,
        "source": source,
    }


PROFILES: dict[str, dict[str, Any]] = {
    "no2": {
        "diameters_mm": _NO2_D,
        "lengths_mm": _NO2_L,
        "assumed": False,
        "source": "Perforation No. 2 (39 g DP3 HMX): Table 7 row 1, Table 8 row 1",
    },
    "no1": _assumed(235.0, "extended at its last slope"),
    "no3": _assumed(200.0, "truncated"),
    "no4": _assumed(195.0, "truncated"),
    "1-1": _table7((33.44,) * 6, "1-1"),
    "1-2": _table7((50.00,) * 6, "1-2"),
    "1-3": _cylinder(
        round(D13_COMPUTED_MM, 4),
        _NO2_L,
        f"equal-volume cylinder of No. 2 by frustums: d = {D13_COMPUTED_MM:.2f} mm "
        f"(the paper prints {D13_PAPER_MM} mm)",
    ),
    "1-3-paper": _cylinder(D13_PAPER_MM, _NO2_L, "Table 7 row 1-3 as printed (36.34 mm)"),
    "2-1": _table7((33.44, 33.33, 28.80, 33.50, 58.77, 60.00), "2-1"),
    "2-2": _table7((33.44, 33.33, 28.80, 13.50, 38.77, 40.00), "2-2"),
    "3-1": _table7((43.44, 43.33, 38.80, 23.50, 48.77, 50.00), "3-1"),
    "3-2": _table7((23.44, 23.33, 18.80, 23.50, 48.77, 50.00), "3-2"),
    "4-1": {
        "diameters_mm": _NO2_D,
        "lengths_mm": (60.0, 60.0, 60.0, 60.0, 40.0),
        "assumed": False,
        "source": "Table 8 row 4-1 (lengths), Table 7 row 1 (diameters)",
    },
    "4-2": {
        "diameters_mm": _NO2_D,
        "lengths_mm": (40.0, 40.0, 40.0, 40.0, 20.0),
        "assumed": False,
        "source": "Table 8 row 4-2 (lengths), Table 7 row 1 (diameters)",
    },
    "lab": _cylinder(2.0, (30.0,), "lab specimen perforation, Table 2: 2 mm x 30 mm"),
    "cluster": _cylinder(20.0, (400.0,), "field cluster perforation, section 3.3: 20 mm x 400 mm"),
}


def profile_names() -> tuple[str, ...]:
    """Names of the catalogue's perforation profiles."""
    return tuple(PROFILES)


def lookup_profile(name: str) -> dict[str, Any]:
    """Return the catalogue profile ``name`` (diameters and lengths in mm); KeyError if unknown."""
    return copy.deepcopy(PROFILES[name])


# ---------------------------------------------------------------------------
# Scene presets: geometry tables as a scene file writes them (units as text)
# ---------------------------------------------------------------------------

# Section 4.2: a 2 m cube, a horizontal wellbore of radius 70 mm through its
# centre (along y = Sh), one perforation along SH (x).  The half model z >= 0
# cuts through the plane of the wellbore and perforation axes; the expected
# fracture plane (normal to Sh) crosses it at right angles.
_SINGLE: dict[str, Any] = {
    "kind": "perforated_block",
    "block": {"size": "2 m"},
    "wellbore": {"diameter": "140 mm", "axis": "y"},
    "perforations": [{"profile": "no2", "azimuth": "0 deg"}],
    "symmetry": ["z"],
    "fracturable": {"shape": "tunnel", "perforation": 1, "radius": "100 mm"},
    "mesh": {
        "size": "6 mm",
        "size_far": "250 mm",
        "grading": 0.3,
        "circle_elements": 32,
        "algorithm": "hxt",
        "resolutions": {
            "coarse": {
                "size": "12 mm",
                "size_far": "700 mm",
                "grading": 0.6,
                "circle_elements": 10,
                "wellbore_size": "60 mm",
                "algorithm": "delaunay",
            },
            "paper": {"size": "1.7 mm", "size_far": "200 mm", "grading": 0.2},
        },
    },
}

_LAB: dict[str, Any] = {
    "kind": "perforated_block",
    "block": {"size": "300 mm"},
    "wellbore": {"diameter": "20 mm", "axis": "z"},
    "cluster": {
        "count": 2,
        "spacing": "0 mm",
        "phasing": "180 deg",
        "azimuth": "60 deg",
        "profile": "lab",
    },
    "symmetry": "auto",
    "fracturable": {"shape": "sphere", "radius": "80 mm"},
    "mesh": {
        "size": "1 mm",
        "size_far": "30 mm",
        "grading": 0.3,
        "circle_elements": 12,
        "algorithm": "hxt",
        "resolutions": {
            "coarse": {
                "size": "2 mm",
                "size_far": "100 mm",
                "grading": 0.6,
                "circle_elements": 6,
                "wellbore_size": "8 mm",
                "algorithm": "delaunay",
            },
            "fine": {"size": "0.5 mm", "size_far": "20 mm", "circle_elements": 16},
        },
    },
}

# Section 3.3: 6 perforations, 60 deg phasing, 200 mm apart along the wellbore.
# "The middle two along SH": two neighbours are 60 deg apart, so they sit at
# -30 and +30 deg about SH (phases -150, -90, ..., 150 deg).
_CLUSTER: dict[str, Any] = {
    "kind": "perforated_block",
    "block": {"size": "2 m"},
    "wellbore": {"diameter": "140 mm", "axis": "y"},
    "cluster": {
        "count": 6,
        "spacing": "200 mm",
        "phasing": "60 deg",
        "first_phase": "-150 deg",
        "profile": "cluster",
    },
    "symmetry": "none",
    "fracturable": {"shape": "sphere", "radius": "600 mm"},
    "mesh": {
        "size": "8 mm",
        "size_far": "500 mm",
        "grading": 0.5,
        "circle_elements": 8,
        "wellbore_size": "30 mm",
        "resolutions": {
            "coarse": {
                "size": "15 mm",
                "size_far": "700 mm",
                "grading": 0.8,
                "circle_elements": 6,
                "wellbore_size": "80 mm",
            },
            "paper": {
                "size": "6 mm",
                "size_far": "300 mm",
                "circle_elements": 12,
                "algorithm": "hxt",
            },
        },
    },
}

_CRACK_PLATE: dict[str, Any] = {
    "kind": "crack_plate",
    "plate": {"width": "1 m", "height": "1 m"},
    "crack": {"length": "0.2 m"},
    "symmetry": "none",
    "mesh": {
        "size": "5 mm",
        "size_far": "50 mm",
        "grading": 0.3,
        "resolutions": {"coarse": {"size": "20 mm", "size_far": "100 mm"}},
    },
}

# The same plate as the Sneddon verification scene: the half x >= 0 (the plate and the
# pressure are symmetric about x = 0), so the coarse mesh can be twice as fine.
_SNEDDON_PLATE: dict[str, Any] = {
    **_CRACK_PLATE,
    "symmetry": ["x"],
    "mesh": {
        "size": "5 mm",
        "size_far": "50 mm",
        "grading": 0.3,
        "resolutions": {"coarse": {"size": "10 mm", "size_far": "100 mm"}},
    },
}

# Seed hfdda sec. 4.1 (Griffith with a background stress): a 20 m crack in the paper's
# 100 m outer domain, its half x >= 0; h = L/20 at the crack (the paper's blocks are 1 m,
# the coarse mesh's).
_GRIFFITH_PLATE: dict[str, Any] = {
    "kind": "crack_plate",
    "plate": {"width": "100 m", "height": "100 m"},
    "crack": {"length": "20 m"},
    "symmetry": ["x"],
    "mesh": {
        "size": "0.5 m",
        "size_far": "5 m",
        "grading": 0.3,
        "resolutions": {"coarse": {"size": "1 m", "size_far": "10 m"}},
    },
}

# Seed hfdda sec. 4.2: 160 m x 160 m, injection at the origin, the fracture
# may run 24 m each way; 1 m of each wing is opened at the start.  The crack and
# the path are split into facets of exactly the wall size (path_size), as in the
# KGD verification (benchmarks/kgd_verification.py): the half-length moves in
# whole facets.
_KGD: dict[str, Any] = {
    "kind": "kgd_strip",
    "plate": {"width": "160 m", "height": "160 m"},
    "crack": {"length": "2 m", "path_length": "48 m"},
    "symmetry": ["x"],
    "fracturable": {"shape": "slab", "axis": "y", "thickness": "4 m"},
    "mesh": {
        "size": "0.5 m",
        "size_far": "16 m",
        "grading": 0.25,
        "path_size": "0.5 m",
        "resolutions": {"coarse": {"size": "1 m", "size_far": "32 m", "path_size": "1 m"}},
    },
}

# Seed hfdda sec. 4.3 (Rubin's PMMA experiment): the 305 mm x 96 mm inner area, a 30 mm
# initial crack 0.1 cm wide (an open slot) and a path at 51 deg from each crack end;
# triangles of at most 30 mm2 (just over 1800).  meshes/scenes/rubin_pmma.toml says why
# the edges are free but for fixed corners and where the paths stop.
_RUBIN: dict[str, Any] = {
    "kind": "angled_path_plate",
    "plate": {"width": "305 mm", "height": "96 mm"},
    "crack": {
        "length": "30 mm",
        "width": "1 mm",
        "path_length": "50 mm",
        "path_angle": "51 deg",
        "wings": "point",
    },
    "support": {"corners": "8 mm"},
    "symmetry": "none",
    "mesh": {
        "size": "6.5 mm",
        "size_far": "6.5 mm",
        "path_size": "5 mm",
        "resolutions": {"coarse": {"size": "12 mm", "size_far": "12 mm", "path_size": "7.5 mm"}},
    },
}

# Seed pfc2d sec. 3.2 / seed 001: 1000 mm square, 60 mm borehole at the centre.  The
# whole plate: a breakdown crack along SH (y = 0) must be interior facets, and a
# quarter model makes y = 0 a roller.  Four structured rings of the wall size put
# radial facets at every angle step, including along SH; the default mesh is the
# one of tests/test_hydrofrac.py and benchmarks/wall_joint_verification.py (a/10).
_BOREHOLE: dict[str, Any] = {
    "kind": "borehole_plate",
    "plate": {"width": "1000 mm", "height": "1000 mm"},
    "wellbore": {"diameter": "60 mm"},
    "symmetry": "none",
    "mesh": {
        "size": "3 mm",
        "size_far": "100 mm",
        "grading": 0.25,
        "circle_elements": 6,  # no cap on the wall size from the circle: size is the knob
        "wall_rings": 4,
        "size_integration": "exact",
        "resolutions": {"coarse": {"size": "6 mm"}},
    },
}


def _single(profile: str) -> dict[str, Any]:
    preset = copy.deepcopy(_SINGLE)
    preset["perforations"][0]["profile"] = profile
    return preset


PRESETS: dict[str, dict[str, Any]] = {
    "single_perforation": _single("no2"),
    **{f"perforation_{p}": _single(p) for p in ("no1", "no2", "no3", "no4")},
    **{
        f"shape_{p}": _single(p)
        for p in ("1-1", "1-2", "1-3", "2-1", "2-2", "3-1", "3-2", "4-1", "4-2")
    },
    "lab_specimen": _LAB,
    "field_cluster": _CLUSTER,
    "crack_plate": _CRACK_PLATE,
    "sneddon_plate": _SNEDDON_PLATE,
    "griffith_plate": _GRIFFITH_PLATE,
    "kgd_strip": _KGD,
    "borehole_plate": _BOREHOLE,
    "rubin_pmma": _RUBIN,
}


def preset_names() -> tuple[str, ...]:
    """Names of the scene presets a scene file may start from (``geometry.catalogue``)."""
    return tuple(PRESETS)


def lookup_preset(name: str) -> dict[str, Any]:
    """Return a deep copy of the geometry table of preset ``name``; KeyError if unknown."""
    return copy.deepcopy(PRESETS[name])


__all__ = [
    "D13_COMPUTED_MM",
    "D13_PAPER_MM",
    "MM",
    "PRESETS",
    "PROFILES",
    "lookup_preset",
    "lookup_profile",
    "preset_names",
    "profile_names",
]

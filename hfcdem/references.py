"""Published figures the demos compare against (seed cdem-perforation-breakdown).

Breakdown pressures in MPa.  Section 5.2 of the paper quotes 68.75 MPa for
Model 4-1 and 56.97 MPa for 4-2 while arguing that the longer tunnel breaks down
lower; the values are swapped here (4-1, 280 mm long, at 56.97 MPa), as
:mod:`hfcdem.config.catalogue` explains.
"""

from __future__ import annotations

# sec. 3.2, Fig. 9: lab specimen of Jiang et al., azimuth (deg) -> MPa
LAB_MEASURED = {30: 10.39, 45: 10.55, 60: 15.55}
LAB_PAPER_SIMULATED = {30: 10.46, 45: 10.65, 60: 15.64}

# sec. 3.3: field cluster (Changqing oilfield)
FIELD_MEASURED = 43.0
FIELD_PAPER_SIMULATED = 44.26
FIELD_FIRST_CRACK_S = 7.0  # at the perforation root

# sec. 4.4, Fig. 15: the four charges
CHARGES = {"no1": 68.02, "no2": 64.01, "no3": 68.56, "no4": 65.37}
CHARGE_NAMES = {
    "no1": "25 g DP3 HMX",
    "no2": "39 g DP3 HMX",
    "no3": "89-type deep-penetrating",
    "no4": "95-type deep-penetrating",
}

# sec. 5.2, Fig. 21: the shape study (profile name -> MPa)
SHAPES = {
    "no2": 64.01,
    "1-1": 66.83,
    "1-2": 53.86,
    "1-3": 65.35,
    "2-1": 56.67,
    "2-2": 65.67,
    "3-1": 58.35,
    "3-2": 66.66,
    "4-1": 56.97,
    "4-2": 68.75,
}
SHAPE_FRACTURE_DEGREE = {"1-2": 0.31e-3, "4-1": 0.56e-3}

# the orderings the paper draws from these numbers: (lower, higher) pairs
SHAPE_ORDERINGS = (
    ("1-2", "no2", "the large cylinder breaks below No. 2"),
    ("no2", "1-1", "No. 2 breaks below the small cylinder"),
    ("no2", "1-3", "No. 2 breaks below the equal-volume cylinder"),
    ("2-1", "2-2", "a wider far-well section lowers breakdown"),
    ("3-1", "3-2", "a wider near-well section lowers breakdown"),
    ("4-1", "4-2", "a longer tunnel lowers breakdown"),
)


__all__ = [
    "CHARGES",
    "CHARGE_NAMES",
    "FIELD_FIRST_CRACK_S",
    "FIELD_MEASURED",
    "FIELD_PAPER_SIMULATED",
    "LAB_MEASURED",
    "LAB_PAPER_SIMULATED",
    "SHAPES",
    "SHAPE_FRACTURE_DEGREE",
    "SHAPE_ORDERINGS",
]

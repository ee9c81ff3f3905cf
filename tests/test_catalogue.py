"""The perforation profiles and scene presets carry the paper's numbers."""

import numpy as np
import pytest

from hfcdem.analytic import equal_volume_cylinder_diameter, frustum_volume
from hfcdem.config import catalogue

NO2_D = (33.44, 33.33, 28.80, 23.50, 48.77, 50.00)
NO2_L = (50.0, 50.0, 50.0, 50.0, 30.0)


def test_no2_is_table7_and_table8_row1():
    no2 = catalogue.lookup_profile("no2")
    assert no2["diameters_mm"] == NO2_D
    assert no2["lengths_mm"] == NO2_L
    assert sum(no2["lengths_mm"]) == 230.0
    assert not no2["assumed"]


def test_equal_volume_cylinder_is_computed_not_copied():
    stations = np.concatenate([[0.0], np.cumsum(NO2_L)])
    assert catalogue.D13_COMPUTED_MM == pytest.approx(34.86, abs=0.005)
    assert catalogue.D13_PAPER_MM == 36.34
    d13 = catalogue.lookup_profile("1-3")["diameters_mm"]
    assert d13 == (round(catalogue.D13_COMPUTED_MM, 4),) * 6
    # same volume as No. 2 within the rounding of the diameter
    assert frustum_volume(d13, stations) == pytest.approx(frustum_volume(NO2_D, stations), 1e-5)
    assert equal_volume_cylinder_diameter(NO2_D, stations) == pytest.approx(d13[0], abs=1e-4)
    assert catalogue.lookup_profile("1-3-paper")["diameters_mm"] == (36.34,) * 6


@pytest.mark.parametrize(
    ("name", "diameters"),
    [
        ("1-1", (33.44,) * 6),
        ("1-2", (50.00,) * 6),
        ("2-1", (33.44, 33.33, 28.80, 33.50, 58.77, 60.00)),
        ("2-2", (33.44, 33.33, 28.80, 13.50, 38.77, 40.00)),
        ("3-1", (43.44, 43.33, 38.80, 23.50, 48.77, 50.00)),
        ("3-2", (23.44, 23.33, 18.80, 23.50, 48.77, 50.00)),
    ],
)
def test_table7_variants(name, diameters):
    p = catalogue.lookup_profile(name)
    assert p["diameters_mm"] == diameters
    assert p["lengths_mm"] == NO2_L
    assert not p["assumed"]


@pytest.mark.parametrize(
    ("name", "segment", "last", "total"), [("4-1", 60, 40, 280), ("4-2", 40, 20, 180)]
)
def test_table8_length_variants(name, segment, last, total):
    p = catalogue.lookup_profile(name)
    assert p["lengths_mm"] == (segment,) * 4 + (last,)
    assert sum(p["lengths_mm"]) == total
    assert p["diameters_mm"] == NO2_D


@pytest.mark.parametrize(("name", "length"), [("no1", 235.0), ("no3", 200.0), ("no4", 195.0)])
def test_assumed_profiles_have_table5_lengths_and_say_so(name, length):
    p = catalogue.lookup_profile(name)
    assert p["assumed"]
    assert "ASSUMED" in p["source"]
    assert sum(p["lengths_mm"]) == pytest.approx(length)
    d = np.asarray(p["diameters_mm"])
    # narrowing then widening, with No. 2's near-well section
    throat = int(np.argmin(d))
    assert 0 < throat < len(d) - 1
    assert np.all(np.diff(d[: throat + 1]) < 0) and np.all(np.diff(d[throat:]) > 0)
    assert tuple(d[:4]) == NO2_D[:4]


def test_lab_and_cluster_cylinders():
    assert catalogue.lookup_profile("lab") == {
        "diameters_mm": (2.0, 2.0),
        "lengths_mm": (30.0,),
        "assumed": False,
        "source": catalogue.PROFILES["lab"]["source"],
    }
    assert catalogue.lookup_profile("cluster")["diameters_mm"] == (20.0, 20.0)
    assert catalogue.lookup_profile("cluster")["lengths_mm"] == (400.0,)


def test_presets_and_notes():
    names = catalogue.preset_names()
    for required in (
        "perforation_no1",
        "perforation_no2",
        "perforation_no3",
        "perforation_no4",
        "shape_1-3",
        "shape_4-2",
        "lab_specimen",
        "field_cluster",
        "single_perforation",
        "crack_plate",
        "kgd_strip",
        "borehole_plate",
    ):
        assert required in names
    preset = catalogue.lookup_preset("perforation_no2")
    preset["block"]["size"] = "1 m"  # a copy: the catalogue is unchanged
    assert catalogue.PRESETS["perforation_no2"]["block"]["size"] == "2 m"
    # the 4-1/4-2 swap of the paper's text is documented
    assert "swapped" in (catalogue.__doc__ or "")
    with pytest.raises(KeyError):
        catalogue.lookup_profile("no5")

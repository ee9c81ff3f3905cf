"""Static scenes ([load] instead of [injection]): the Sneddon plate through `hfcdem run`."""

import json

import numpy as np
import pytest
from mpi4py import MPI

from hfcdem.cli import main
from hfcdem.config.scene import load_scene, parse_scene
from hfcdem.config.tables import SceneError
from hfcdem.workflows.run import run_scene

SNEDDON = "meshes/scenes/sneddon_plate.toml"


def _plate(width_m: float, alpha: float | None = None):
    overrides = {
        "geometry.plate.width": f"{width_m} m",
        "geometry.plate.height": f"{width_m} m",
        "geometry.mesh.size_far": f"{100 * width_m} mm",
    }
    if alpha is not None:
        overrides["rock.spring_factor"] = alpha
    return load_scene(SNEDDON, "coarse", overrides=overrides)


def test_sneddon_scene_is_stiffer_than_the_infinite_plate(shared_tmp_path):
    out = shared_tmp_path / "sneddon"
    summary = run_scene(_plate(1.0), out)
    ref = summary["sneddon"]
    # the 1 m plate with a fixed edge is stiffer than Sneddon's infinite one (-4 % here)
    assert -0.06 < ref["centre_relative_error"] < -0.02
    assert ref["sneddon_centre_uy_um"] == pytest.approx(19.643, rel=1e-4)
    assert summary["max_crack_opening_m"] == pytest.approx(2e-6 * ref["centre_uy_um"], rel=0.01)
    # the tips are far past the 3 MPa strength: reported, not broken
    assert summary["overstressed_interfaces"] > 0
    assert summary["max_spring_tension_MPa"] > 3.0
    for name in ("summary.json", "crack_opening.csv", "crack_opening.png", "interfaces.pvd"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "fields.bp").is_dir()
    profile = np.loadtxt(out / "crack_opening.csv", delimiter=",", skiprows=1)
    assert np.all(profile[:, 1] > 0.0)  # every crack facet open under pressure
    assert np.all(np.diff(profile[:, 0]) >= 0.0)


def test_sneddon_gap_closes_on_a_large_plate_with_stiff_springs(shared_tmp_path):
    summary = run_scene(_plate(10.0, alpha=1000), shared_tmp_path / "large")
    # the paper's sec. 3.1 claim, made sharp: what is left is discretisation (-0.3 %)
    assert abs(summary["sneddon"]["centre_relative_error"]) < 0.01


def test_cli_runs_the_sneddon_scene(shared_tmp_path, capsys):
    out = shared_tmp_path / "cli"
    code = main(["run", SNEDDON, "--resolution", "coarse", "-o", str(out)])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["kind"] == "static"
    assert summary["ranks"] == MPI.COMM_WORLD.size
    if MPI.COMM_WORLD.rank == 0:
        printed = capsys.readouterr().out
        assert "Sneddon" in printed and "springs past their strength" in printed


def test_load_and_injection_together_are_refused():
    with pytest.raises(SceneError, match=r"load.*not both"):
        load_scene(SNEDDON, overrides={"injection.rate": "1e-7 m3/s"})


@pytest.mark.parametrize(
    ("key", "value", "field"),
    [
        ("load.crack_pressure", 22, "load.crack_pressure"),  # no unit
        ("load.crack_pressure", "2 GPa", "load.crack_pressure"),
        ("load.fracture", True, "load.fracture"),  # unknown key
    ],
)
def test_bad_load_names_the_field(key, value, field):
    with pytest.raises(SceneError, match=field):
        load_scene(SNEDDON, overrides={key: value})


def test_a_static_scene_without_a_crack_is_refused(shared_tmp_path):
    scene = parse_scene(
        {
            "geometry": {"catalogue": "borehole_plate"},
            "rock": {
                "youngs_modulus": "20 GPa",
                "poisson_ratio": 0.25,
                "tensile_strength": "3 MPa",
                "cohesion": "10 MPa",
            },
            "stress": {"sh_max": "0 MPa", "sh_min": "0 MPa", "sv": "0 MPa"},
            "load": {"crack_pressure": "1 MPa"},
        },
        resolution="coarse",
    )
    with pytest.raises(SceneError, match="no pre-existing crack"):
        run_scene(scene, shared_tmp_path / "nocrack")


def test_a_crack_pressed_shut_is_said_and_compared_to_nothing(shared_tmp_path):
    scene = load_scene(SNEDDON, "coarse", overrides={"load.crack_pressure": "0 MPa"})
    said = []
    summary = run_scene(scene, shared_tmp_path / "shut", say=said.append)
    ref = summary["sneddon"]
    assert ref["net_pressure_MPa"] == 0.0
    assert ref["centre_relative_error"] is None and ref["max_relative_error_inner"] is None
    text = " ".join(said)
    assert "the faces are pressed shut" in text and "nan" not in text
    # written as plain JSON: no NaN
    json.loads((shared_tmp_path / "shut" / "summary.json").read_text(), parse_constant=_refuse)


def _refuse(name):
    raise ValueError(f"{name} in summary.json")

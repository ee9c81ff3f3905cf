"""The report's Fig. 14 case: how fast the zone fills, the picture, the rows.

A run directory is written by hand: a history of the share of joints holding
pressure and two interface frames, one wet triangle near the tunnel wall and
one dry triangle far from it, around No. 2's tunnel (the scene is loaded, not
meshed).
"""

import math
from pathlib import Path

import meshio
import numpy as np
import pytest

from hfcdem import references
from hfcdem.config.scene import load_scene
from hfcdem.reproduce.cases import CASES
from hfcdem.reproduce.compare import CaseResult
from hfcdem.reproduce.saturation import (
    SATURATION_FIGURE,
    SEEPAGE_RUNG,
    TO_SEEPAGE,
    filling_times,
    plot_saturation,
    saturation_in_time,
)

SCENE = Path(__file__).resolve().parents[1] / "meshes/scenes/perforation_no2.toml"
SHARES = ((0.5, 0.2), (1.5, 0.6), (3.0, 0.95), (4.0, 1.0), (5.0, 1.0))


def _history(path: Path, shares=SHARES) -> None:
    lines = ["time_s,cavity_pressure_Pa,joints_holding_pressure"]
    lines += [f"{t},3e7,{w}" for t, w in shares]
    path.write_text("\n".join(lines) + "\n")


def test_filling_times_are_the_first_to_reach_each_share(tmp_path):
    _history(tmp_path / "history.csv")
    assert filling_times(tmp_path / "history.csv") == {0.5: 1.5, 0.9: 3.0, 1.0: 4.0}
    _history(tmp_path / "history.csv", SHARES[:2])
    assert filling_times(tmp_path / "history.csv") == {0.5: 1.5, 0.9: None, 1.0: None}


def _run_dir(root: Path, scene) -> Path:
    """Two frames (0 s dry, 1 s with the triangle near the wall wet) around the first tunnel."""
    from hfcdem.mesh.frames import tunnel_frame

    tunnel = tunnel_frame(scene.geometry, 0)
    near = tunnel.start + 0.05 * tunnel.d + 0.03 * tunnel.w  # station 50 mm, 30 mm off the axis
    far = tunnel.start + 0.15 * tunnel.d + 0.08 * tunnel.t  # station 150 mm, 80 mm off
    points = np.array([p + e for p in (near, far) for e in (0.0, 1e-3 * tunnel.d, 1e-3 * tunnel.t)])
    cells = [("triangle", np.array([[0, 1, 2], [3, 4, 5]]))]
    (root / "joints").mkdir(parents=True)
    listed = []
    for k, (t, wet) in enumerate(((0.0, 0.0), (1.0, 1.0))):
        name = f"joints/frame_{k:04d}.vtu"
        data = {"saturation": [np.array([wet, 0.0])], "state": [np.zeros(2)]}
        meshio.write(root / name, meshio.Mesh(points, cells, cell_data=data))
        listed.append(f'<DataSet timestep="{t}" group="" part="0" file="{name}"/>')
    (root / "joints.pvd").write_text("<Collection>\n" + "\n".join(listed) + "\n</Collection>\n")
    _history(root / "history.csv")
    return root


def test_every_scene_that_bounds_its_steps_turns_into_a_seepage_run():
    """The seepage conversion drops the scenes' pressure bound, which seepage refuses."""
    scenes = SCENE.parent
    for name in ("perforation_no2", "shape_1-2", "field_cluster"):
        bounded = load_scene(scenes / f"{name}.toml", "coarse")
        assert bounded.physics.solver.max_pressure_change == pytest.approx(0.02), name
        seeping = load_scene(scenes / f"{name}.toml", "coarse", overrides=TO_SEEPAGE)
        assert seeping.physics.wall_joints == "seepage", name
        assert seeping.physics.solver.max_pressure_change == math.inf, name


def test_rows_and_picture_of_the_joints_filling(tmp_path):
    scene = load_scene(SCENE, "coarse", overrides=SEEPAGE_RUNG)
    assert scene.physics.wall_joints == "seepage" and scene.physics.wall_film is None
    assert scene.physics.fluid.bulk_modulus == pytest.approx(2.2e9)
    assert scene.physics.output_interval == pytest.approx(1.0)
    run = _run_dir(tmp_path / "run", scene)
    summary = {"peak_pressure_MPa": 70.11, "breakdown_pressure_MPa": None}
    peak, filling = saturation_in_time(CaseResult(run, (scene,), summary=summary))
    assert peak.reference == references.CHARGES["no2"] and peak.met is False  # +9.5 %
    assert filling.ours == 3.0 and filling.met is None  # listed, not judged
    assert filling.ours_text == "50 % by 1.5 s, 90 % by 3 s, 100 % by 4 s"
    assert (run / SATURATION_FIGURE).stat().st_size > 10_000
    # without frames there is no picture, and no error
    assert not plot_saturation(tmp_path, scene, tmp_path / "none.png")
    assert not (tmp_path / "none.png").exists()


def test_the_case_runs_the_seepage_rung_in_the_full_tier():
    (case,) = [c for c in CASES if c.name == "no2_seepage"]
    assert case.tiers.keys() == {"full"} and case.tiers["full"].fixed == SEEPAGE_RUNG
    assert SATURATION_FIGURE in case.figures

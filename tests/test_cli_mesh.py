"""``hfcdem mesh``: scene files to .msh, XDMF with tags, PNG and mesh_report.json."""

import json
import shutil
from pathlib import Path

import pytest
from dolfinx.io import XDMFFile
from mpi4py import MPI

from hfcdem.cli import main

SCENES = Path(__file__).resolve().parents[1] / "meshes" / "scenes"


def _report(path: Path) -> dict:
    return json.loads((path / "mesh_report.json").read_text())


def test_mesh_writes_msh_xdmf_png_and_report(shared_tmp_path, capsys):
    out = shared_tmp_path / "no2"
    code = main(
        ["mesh", str(SCENES / "perforation_no2.toml"), "-o", str(out), "--resolution", "coarse"]
    )
    assert code == 0
    for name in ("perforation_no2.msh", "perforation_no2.xdmf", "perforation_no2.h5"):
        assert (out / name).stat().st_size > 0
    assert (out / "perforation_no2.png").stat().st_size > 10_000
    report = _report(out)
    comm = MPI.COMM_WORLD
    assert report["ranks"] == comm.size
    assert report["scene"] == "perforation_no2" and report["resolution"] == "coarse"
    assert report["cells"] > 1000 and report["vertices"] > 100
    assert report["seconds_to_mesh"] > 0.0
    assert 0.0 < report["element_quality"]["min"] <= report["element_quality"]["median"] <= 1.0
    assert 0.0 < report["cell_diameter_m"]["min"] < report["cell_diameter_m"]["max"]
    assert report["equal_volume_cylinder_1_3_mm"]["paper"] == 36.34
    assert report["equal_volume_cylinder_1_3_mm"]["computed_from_table7_frustums"] == pytest.approx(
        34.86, abs=0.005
    )
    (perf,) = report["perforations"]
    assert perf["profile"] == "no2" and perf["assumed"] is False
    assert perf["diameters_mm"] == [33.44, 33.33, 28.8, 23.5, 48.77, 50.0]
    for key in ("measured", "expected", "rel_error"):
        assert key in perf["volume"] and key in report["areas"]["wellbore_wall"]
    assert set(report["tags"]["facets"]) >= {"wellbore_wall", "perforation_1_wall", "symmetry_z"}
    if comm.rank == 0:
        assert "perforation_no2: " in capsys.readouterr().out
    # the XDMF file holds the mesh and both tag sets (what ParaView opens)
    with XDMFFile(comm, out / "perforation_no2.xdmf", "r") as xdmf:
        mesh = xdmf.read_mesh(name="perforation_no2")
        mesh.topology.create_connectivity(2, 3)
        cells = xdmf.read_meshtags(mesh, name="cell_tags")
        facets = xdmf.read_meshtags(mesh, name="facet_tags")
    assert mesh.topology.index_map(3).size_global == report["cells"]
    n_cells = comm.allreduce(
        int((cells.indices < mesh.topology.index_map(3).size_local).sum()), op=MPI.SUM
    )
    assert n_cells == report["cells"]
    wall = report["tags"]["facets"]["perforation_1_wall"]
    assert comm.allreduce(len(facets.find(wall)), op=MPI.SUM) > 0


def test_assumed_profiles_are_reported(shared_tmp_path, capsys):
    out = shared_tmp_path / "no4"
    args = ["mesh", str(SCENES / "perforation_no4.toml"), "-o", str(out)]
    assert main([*args, "--resolution", "coarse", "--no-picture"]) == 0
    report = _report(out)
    assert report["assumed_profiles"] == ["no4"]
    assert report["notes"] and "ASSUMED" in report["notes"][0]
    assert report["perforations"][0]["length_mm"] == pytest.approx(195.0)
    assert not (out / "perforation_no4.png").exists()
    if MPI.COMM_WORLD.rank == 0:
        assert "note: ASSUMED profile no4" in capsys.readouterr().out


def test_size_override_and_all(shared_tmp_path):
    scene_dir = shared_tmp_path / "scenes"
    if MPI.COMM_WORLD.rank == 0:
        scene_dir.mkdir()
        for name in ("crack_plate", "borehole_plate"):
            shutil.copy(SCENES / f"{name}.toml", scene_dir)
    MPI.COMM_WORLD.barrier()
    out = shared_tmp_path / "all"
    args = ["mesh", "--all", "--scene-dir", str(scene_dir), "-o", str(out), "--size", "25 mm"]
    assert main([*args, "--no-picture"]) == 0
    for name in ("crack_plate", "borehole_plate"):
        report = _report(out / name)
        assert report["sizing_m"]["size"] == pytest.approx(0.025)
        assert "size 25 mm" in report["resolution"]
        assert report["kind"] == name
    assert (out / "crack_plate" / "crack_plate.msh").exists()


def test_2d_picture(shared_tmp_path):
    out = shared_tmp_path / "kgd"
    assert (
        main(["mesh", str(SCENES / "kgd_strip.toml"), "-o", str(out), "--resolution", "coarse"])
        == 0
    )
    assert (out / "kgd_strip.png").stat().st_size > 10_000
    report = _report(out)
    assert report["units"] == {"volumes": "m2", "areas": "m"}
    assert report["areas"]["fracture_path"]["measured"] == pytest.approx(23.0)


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--size", "25"], "--size: expected a length such as '70 mm', got '25' (no unit)"),
        (["--resolution", "ultra"], "no resolution named 'ultra'"),
    ],
)
def test_bad_arguments_fail_with_the_field_named(shared_tmp_path, capsys, argv, message):
    code = main(["mesh", str(SCENES / "crack_plate.toml"), "-o", str(shared_tmp_path), *argv])
    assert code == 2
    if MPI.COMM_WORLD.rank == 0:
        assert message in capsys.readouterr().err


def test_bad_scene_file_fails_before_meshing(shared_tmp_path, capsys):
    bad = shared_tmp_path / "bad.toml"
    if MPI.COMM_WORLD.rank == 0:
        bad.write_text(
            '[geometry]\ncatalogue = "perforation_no2"\n'
            '[[geometry.perforations]]\nprofile = "no2"\n'
            'lengths = ["50 mm", "-1 mm", "50 mm", "50 mm", "30 mm"]\n'
        )
    MPI.COMM_WORLD.barrier()
    assert main(["mesh", str(bad), "-o", str(shared_tmp_path / "out")]) == 2
    if MPI.COMM_WORLD.rank == 0:
        err = capsys.readouterr().err
        assert (
            "bad.toml: geometry.perforations[0].lengths[1]: a segment length must be positive"
            in err
        )
    assert not (shared_tmp_path / "out").exists()
    assert main(["mesh", "-o", str(shared_tmp_path / "none")]) == 2

"""Scene files: validated frozen dataclasses in SI, errors that name the field, before Gmsh."""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from hfcdem.config import catalogue
from hfcdem.config.geometry import PerforatedBlock
from hfcdem.config.parts import MeshSizing, Profile, TunnelZone, tunnel_extension
from hfcdem.config.plates import BoreholeSquare, CrackPlate, KGDStrip
from hfcdem.config.scene import load_scene, parse_geometry, parse_scene
from hfcdem.config.tables import SceneError

SCENES = Path(__file__).resolve().parents[1] / "meshes" / "scenes"
SCENE_FILES = sorted(SCENES.glob("*.toml"))


def scene(geometry, **top):
    return parse_scene({"name": "t", "geometry": geometry, **top})


def no2(**over):
    return scene({"catalogue": "perforation_no2", **over})


def test_every_catalogue_entry_has_a_scene_file():
    stems = {p.stem for p in SCENE_FILES}
    for name in catalogue.preset_names():
        if name == "lab_specimen":
            assert {"lab_specimen_30deg", "lab_specimen_45deg", "lab_specimen_60deg"} <= stems
        else:
            assert name in stems


@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: p.stem)
def test_scene_files_parse_and_agree_with_the_catalogue(path):
    s = load_scene(path)
    assert s.name == path.stem
    assert s.source == str(path)
    assert s.description
    preset = s.catalogue
    assert preset in catalogue.PRESETS
    ref = parse_geometry({"catalogue": preset})[0]
    if preset == "lab_specimen":
        azimuth = math.radians(float(path.stem.split("_")[-1].removesuffix("deg")))
        d = s.geometry.perforations[0].direction
        assert d == pytest.approx((math.cos(azimuth), math.sin(azimuth), 0.0), abs=1e-12)
        ref = dataclasses.replace(ref, perforations=s.geometry.perforations)
    if path.stem == "single_perforation":
        assert s.geometry.perforations[0].profile.name == "custom"
        ref = dataclasses.replace(ref, perforations=s.geometry.perforations)
    assert s.geometry == ref
    for res in ("coarse",):
        load_scene(path, resolution=res)


def test_no2_scene_in_si_with_the_paper_conventions():
    s = load_scene(SCENES / "perforation_no2.toml")
    g = s.geometry
    assert isinstance(g, PerforatedBlock)
    assert g.block.size == (2.0, 2.0, 2.0)
    assert g.wellbore.diameter == pytest.approx(0.140)  # radius 70 mm
    assert g.wellbore.axis == "y"
    (perf,) = g.perforations
    assert perf.direction == (1.0, 0.0, 0.0)  # along SH
    assert perf.profile.diameters == pytest.approx(tuple(d * 1e-3 for d in catalogue._NO2_D))
    assert perf.profile.stations == pytest.approx((0, 0.05, 0.10, 0.15, 0.20, 0.23))
    assert perf.profile.length == pytest.approx(0.23)
    assert g.symmetry == ("z",)
    assert g.relation(0, "z") == "cut" and g.kept_fraction(0) == 0.5
    assert isinstance(g.fracturable, TunnelZone)
    assert s.assumed_profiles == ()
    with pytest.raises(dataclasses.FrozenInstanceError):
        g.symmetry = ()  # type: ignore[misc]


def test_assumed_profiles_are_flagged_until_both_are_replaced():
    assert load_scene(SCENES / "perforation_no1.toml").assumed_profiles == ("no1",)
    s = scene(
        {
            "catalogue": "perforation_no3",
            "perforations": [{"profile": "no3", "lengths": ["50 mm"] * 4}],
        }
    )
    assert s.geometry.perforations[0].profile.assumed  # diameters still assumed
    assert s.geometry.perforations[0].profile.name == "no3 (modified)"
    full = {"profile": "no3", "diameters": ["30 mm"] * 3, "lengths": ["100 mm"] * 2}
    s = scene({"catalogue": "perforation_no3", "perforations": [full]})
    assert not s.geometry.perforations[0].profile.assumed


def test_resolutions_and_size_override():
    assert no2().geometry.mesh.size == pytest.approx(6e-3)
    s = load_scene(SCENES / "perforation_no2.toml", resolution="paper")
    assert s.geometry.mesh.size == pytest.approx(1.7e-3) and s.resolution == "paper"
    assert s.geometry.mesh.algorithm == "hxt"
    s = load_scene(SCENES / "perforation_no2.toml", resolution="coarse", size=0.01)
    assert s.geometry.mesh.size == pytest.approx(0.01)
    assert s.geometry.mesh.circle_elements == 10
    with pytest.raises(SceneError, match=r"geometry.mesh.resolutions: no resolution named 'ultra'"):
        parse_scene({"geometry": {"catalogue": "perforation_no2"}}, resolution="ultra")


def test_lab_specimen_symmetry_follows_the_azimuth():
    lab = {"catalogue": "lab_specimen"}
    g = scene(lab).geometry
    assert g.symmetry == ("z",)  # azimuth 60 deg: only the plane through both perforations
    assert [g.relation(k, "z") for k in (0, 1)] == ["cut", "cut"]
    g = scene({**lab, "cluster": {"azimuth": "0 deg"}}).geometry
    assert g.symmetry == ("x", "y", "z")  # along SH: an eighth model keeps perforation 1
    assert g.kept_fraction(0) == 0.25 and g.kept_fraction(1) == 0.0
    d1, d2 = (np.asarray(p.direction) for p in scene(lab).geometry.perforations)
    assert d2 == pytest.approx(-d1)


def test_field_cluster_layout():
    g = scene({"catalogue": "field_cluster"}).geometry
    assert len(g.perforations) == 6
    assert [p.entry for p in g.perforations] == pytest.approx([-0.5, -0.3, -0.1, 0.1, 0.3, 0.5])
    phases = [math.degrees(math.atan2(-p.direction[2], p.direction[0])) for p in g.perforations]
    assert phases == pytest.approx([-150, -90, -30, 30, 90, 150])
    assert all(p.profile.length == pytest.approx(0.4) for p in g.perforations)
    assert g.symmetry == ()
    assert g.symmetric_axes() == ()


def test_plates():
    crack = scene({"catalogue": "crack_plate"}).geometry
    assert isinstance(crack, CrackPlate) and crack.crack.length == pytest.approx(0.2)
    assert crack.plate.width == 1.0 and crack.symmetry == ()
    kgd = scene({"catalogue": "kgd_strip"}).geometry
    assert isinstance(kgd, KGDStrip) and kgd.symmetry == ("x",)
    assert kgd.crack.path_length == pytest.approx(48.0)
    hole = scene({"catalogue": "borehole_plate"}).geometry
    assert isinstance(hole, BoreholeSquare) and hole.symmetry == ()
    assert hole.wellbore.diameter == pytest.approx(0.06)
    # the verified set-ups: structured wall rings, exact facets along the KGD path
    assert hole.mesh.wall_rings == 4 and hole.ring_radius == pytest.approx(0.03 + 4 * 0.003)
    assert kgd.mesh.path_size == pytest.approx(0.5) and kgd.path_start == pytest.approx(0.5)
    plain = scene({"catalogue": "crack_plate"}).geometry.mesh
    assert (plain.wall_rings, plain.path_size, plain.size_integration) == (0, None, "fast")


def test_tunnel_starts_inside_the_wellbore():
    profile = Profile.from_lengths([0.03344, 0.03333, 0.0288], [0.05, 0.05])
    delta, r = tunnel_extension(profile, 0.07)
    assert 0.0 < delta < 0.07
    # the start circle lies inside the wellbore
    assert math.hypot(0.07 - delta, r) < 0.07


def _geometry(catalogue_name="perforation_no2", **over):
    return {"catalogue": catalogue_name, **over}


def _perf(**kw):
    return {"perforations": [{"profile": "no2", **kw}]}


BAD = [
    # (geometry table, top-level extras, expected text in the error)
    (_geometry(**_perf(profile=None)), {}, "geometry.perforations[0]: give a profile"),
    (
        _geometry(perforations=[{"lengths": ["50 mm"]}]),
        {},
        "geometry.perforations[0].diameters: missing",
    ),
    (
        _geometry(**_perf(diameters=["33 mm", "-5 mm", "30 mm", "25 mm", "40 mm", "50 mm"])),
        {},
        "geometry.perforations[0].diameters[1]: a perforation diameter must be positive",
    ),
    (
        _geometry(**_perf(diameters=["33440 m"] * 6)),
        {},
        "geometry.perforations[0].diameters[0]: 33440 m is outside the plausible range",
    ),
    (
        _geometry(**_perf(lengths=["50 mm", "50 mm", "0 mm", "50 mm", "30 mm"])),
        {},
        "geometry.perforations[0].lengths[2]: a segment length must be positive",
    ),
    (
        _geometry(**_perf(lengths=["50 mm", "50 mm", "50 mm"])),
        {},
        "geometry.perforations[0].lengths: expected 5 segment lengths for 6 diameters, got 3",
    ),
    (
        _geometry(**_perf(lengths=["200 mm"] * 5)),
        {},
        "geometry.perforations[0]: the tunnel leaves the block",
    ),
    (
        _geometry(
            perforations=[{"profile": "no2"}, {"profile": "no2", "entry": "20 mm"}],
            symmetry="none",
            fracturable={"shape": "sphere", "radius": "0.5 m"},
        ),
        {},
        "geometry.perforations[1]: intersects perforation 1",
    ),
    (
        _geometry(wellbore={"diameter": "1.5 m"}),
        {},
        "geometry.wellbore.diameter: 1.5 m is too large for the block",
    ),
    (
        _geometry(wellbore={"diameter": 70}),
        {},
        "geometry.wellbore.diameter: expected a length such as '70 mm', got 70",
    ),
    (_geometry(wellbore={"diameter": "70"}), {}, "got '70' (no unit)"),
    (_geometry(wellbore={"radius": "70 mm"}), {}, "geometry.wellbore.radius: unknown key"),
    (_geometry(mesh={"size": "0 mm"}), {}, "geometry.mesh.size: an element size must be positive"),
    (_geometry(mesh={"size": "0.02 mm"}), {}, "geometry.mesh.size: 0.02 mm would give about"),
    (
        _geometry(mesh={"size": "30 mm"}),
        {},
        "geometry.mesh.size: 30 mm is coarser than the thinnest",
    ),
    (
        _geometry(mesh={"size_far": "1 mm"}),
        {},
        "geometry.mesh.size_far: 1 mm must be at least size",
    ),
    (_geometry(mesh={"grading": "0.3"}), {}, "geometry.mesh.grading: expected a number (no unit)"),
    (
        _geometry(**_perf(azimuth="30 deg")),
        {},
        "geometry.perforations[0].direction: must be perpendicular",
    ),
    (
        _geometry(**_perf(direction=[0, 0, 0])),
        {},
        "geometry.perforations[0].direction: must not be the zero vector",
    ),
    (
        _geometry(symmetry=["y", "x"]),
        {},
        "geometry.symmetry: x = 0 is not a symmetry plane of this scene",
    ),
    (_geometry(symmetry=["w"]), {}, "geometry.symmetry[0]: expected one of 'x', 'y', 'z'"),
    (
        _geometry(fracturable={"shape": "tunnel", "radius": "10 mm"}),
        {},
        "geometry.fracturable.radius: 10 mm lies inside",
    ),
    (_geometry(fracturable={"shape": "cube"}), {}, "geometry.fracturable.shape: expected one of"),
    (_geometry("field_cluster", symmetry=["y"]), {}, "perforation 1 has no mirror image"),
    (_geometry("crack_plate", symmetry=["y"]), {}, "geometry.symmetry: y = 0 is not allowed"),
    (
        _geometry("crack_plate", crack={"length": "0.9 m"}),
        {},
        "geometry.crack.length: must be at most 0.8",
    ),
    (
        _geometry("crack_plate", block={"size": "1 m"}),
        {},
        "geometry.block: not used by a crack_plate",
    ),
    (
        _geometry("kgd_strip", crack={"path_length": "1 m"}),
        {},
        "geometry.crack.path_length: 1 m must be at least",
    ),
    (
        _geometry("borehole_plate", mesh={"wall_rings": -1}),
        {},
        "geometry.mesh.wall_rings: expected an integer in [0, 200], got -1",
    ),
    (
        _geometry("borehole_plate", mesh={"wall_rings": 2.5}),
        {},
        "geometry.mesh.wall_rings: expected an integer",
    ),
    (
        _geometry("borehole_plate", mesh={"wall_rings": 200}),
        {},
        "geometry.mesh.wall_rings: 200 rings of 3 mm reach 630 mm",
    ),
    (
        _geometry("borehole_plate", fracturable={"shape": "sphere", "radius": "200 mm"}),
        {},
        "geometry.mesh.wall_rings: structured wall rings cannot be combined",
    ),
    (
        _geometry("borehole_plate", mesh={"path_size": "3 mm"}),
        {},
        "geometry.mesh.path_size: not used by a borehole_plate",
    ),
    (
        _geometry("crack_plate", mesh={"wall_rings": 2}),
        {},
        "geometry.mesh.wall_rings: not used by a crack_plate",
    ),
    (
        _geometry("kgd_strip", mesh={"path_size": "0.3 m"}),
        {},
        "geometry.mesh.path_size: 300 mm must divide each wing of crack.length",
    ),
    (
        _geometry("kgd_strip", crack={"path_length": "47.2 m"}),
        {},
        "geometry.mesh.path_size: 500 mm must divide each wing of crack.path_length",
    ),
    (
        _geometry("borehole_plate", mesh={"size_integration": "slow"}),
        {},
        "geometry.mesh.size_integration: expected one of 'fast', 'exact'",
    ),
    (
        _geometry(mesh={"size_integration": "exact"}),
        {},
        "geometry.mesh.size_integration: not used by a perforated_block",
    ),
    ({"catalogue": "perforation_no9"}, {}, "geometry.catalogue: unknown entry 'perforation_no9'"),
    ({"kind": "sphere_pack"}, {}, "geometry.kind: expected one of"),
    (_geometry(), {"rocks": {}}, "rocks: unknown key"),
    (_geometry(), {"name": "no 2"}, "name: expected letters"),
]


@pytest.mark.parametrize(("geometry", "top", "message"), BAD, ids=[m for *_, m in BAD])
def test_bad_input_names_the_field(geometry, top, message):
    geometry = {k: v for k, v in geometry.items() if v is not None}
    if "perforations" in geometry:
        geometry["perforations"] = [
            {k: v for k, v in p.items() if v is not None} for p in geometry["perforations"]
        ]
    with pytest.raises(SceneError) as err:
        parse_scene({"name": "t", "geometry": geometry, **top})
    assert message in str(err.value)


def test_output_section_alone_is_ignored_in_a_geometry_scene():
    s = parse_scene({"geometry": {"catalogue": "crack_plate"}, "output": {}})
    assert s.ignored_sections == ("output",)
    assert s.physics is None


def test_load_scene_reports_the_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[geometry]\ncatalogue = "perforation_no2"\n'
        '[geometry.wellbore]\ndiameter = "14 cm"\naxis = "q"\n'
    )
    with pytest.raises(SceneError, match=r"bad.toml: geometry.wellbore.axis: expected one of"):
        load_scene(bad)
    broken = tmp_path / "broken.toml"
    broken.write_text("[geometry\n")
    with pytest.raises(SceneError, match=r"broken\.toml is not valid TOML"):
        load_scene(broken)
    with pytest.raises(SceneError, match="cannot read scene file"):
        load_scene(tmp_path / "missing.toml")


def test_dataclasses_validate_on_construction():
    with pytest.raises(SceneError, match="stations must increase"):
        Profile((0.01, 0.01, 0.01), (0.0, 0.02, 0.02))
    with pytest.raises(SceneError, match="needs at least two sections"):
        Profile((0.01,), (0.0,))
    with pytest.raises(SceneError, match="circle_elements"):
        MeshSizing(0.01, 0.1, circle_elements=3)
    sizing = MeshSizing(0.006, 0.25, circle_elements=32)
    assert sizing.wall_size(0.0235) == pytest.approx(math.pi * 0.0235 / 32)
    assert sizing.wall_size(0.5) == 0.006


def test_a_mesh_field_set_explicitly_wins_over_a_named_resolution():
    from hfcdem.config.scene import apply_overrides
    from hfcdem.workflows.study import load_study

    sneddon = "meshes/scenes/sneddon_plate.toml"
    assert load_scene(sneddon, "coarse").geometry.mesh.size_far == pytest.approx(0.1)
    # once the coarse table's 100 mm replaced it silently
    set_far = load_scene(sneddon, "coarse", overrides={"geometry.mesh.size_far": "1 m"})
    assert set_far.geometry.mesh.size_far == pytest.approx(1.0)
    assert set_far.geometry.mesh.size == pytest.approx(0.01)  # the rest is still coarse
    graded = load_scene(sneddon, "coarse", overrides={"geometry.mesh.grading": 0.4})
    assert graded.geometry.mesh.grading == pytest.approx(0.4)
    with pytest.raises(SceneError, match="no resolution named 'ultra'"):
        load_scene(sneddon, "ultra", overrides={"geometry.mesh.size": "1 mm"})
    # a resolution of the catalogue entry's, not the scene's
    doc = {"geometry": {"catalogue": "borehole_plate"}}
    apply_overrides(doc, {"geometry.mesh.size": "4 mm"}, "coarse")
    geometry, _, chosen = parse_geometry(doc["geometry"], resolution="coarse")
    assert chosen == "coarse" and geometry.mesh.size == pytest.approx(0.004)
    # a study's fixed fields too (sneddon_alpha's 1 m far size at coarse)
    study = load_study("studies/sneddon_alpha.toml", "coarse")
    assert study.case_scene(0).geometry.mesh.size_far == pytest.approx(1.0)

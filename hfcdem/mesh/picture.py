"""A PNG of a scene's mesh, read back from its Gmsh ``.msh`` file (rank 0, off-screen).

Left: the whole model, cavity walls coloured, block faces with their element
edges.  Right: a close-up of the element layer along a cut through the first
tunnel and the wellbore axis (3D), or of the mesh around the crack or
borehole (2D).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from hfcdem.config.geometry import PerforatedBlock, Scene
from hfcdem.config.parts import axis_vector
from hfcdem.io.plots import ensure_display

_WALL_PREFIXES = ("wellbore_wall", "perforation_")
_LINE_TAGS = {"crack": "red", "fracture_path": "orange", "wellbore_wall": "red"}


def _read(msh: Path) -> tuple[np.ndarray, dict[str, list[tuple[np.ndarray, np.ndarray]]], dict]:
    import meshio

    m = meshio.read(msh)
    names = {int(v[0]): k for k, v in m.field_data.items()}
    blocks: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
    for block, tags in zip(m.cells, m.cell_data["gmsh:physical"], strict=True):
        blocks.setdefault(block.type, []).append((block.data, np.asarray(tags)))
    return m.points, blocks, names


def _cells(blocks: dict, kind: str) -> tuple[np.ndarray, np.ndarray]:
    parts = blocks.get(kind, [])
    if not parts:
        return np.zeros((0, 0), dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate([c for c, _ in parts]), np.concatenate([t for _, t in parts])


def _poly(points: np.ndarray, cells: np.ndarray) -> Any:
    import pyvista

    faces = np.hstack([np.full((len(cells), 1), cells.shape[1]), cells]).ravel()
    if cells.shape[1] == 2:
        return pyvista.PolyData(points, lines=faces)
    return pyvista.PolyData(points, faces=faces)


def render_mesh(msh: str | Path, png: str | Path, scene: Scene) -> None:
    """Render the mesh in ``msh`` to ``png`` (call on one rank only)."""
    ensure_display()
    import pyvista

    pyvista.OFF_SCREEN = True
    points, blocks, names = _read(Path(msh))
    plotter = pyvista.Plotter(off_screen=True, shape=(1, 2), window_size=(1600, 800))
    if scene.geometry.dim == 3:
        _render_3d(plotter, points, blocks, names, scene)
    else:
        _render_2d(plotter, points, blocks, names, scene)
    plotter.screenshot(str(png))
    plotter.close()


def _render_3d(plotter: Any, points: np.ndarray, blocks: dict, names: dict, scene: Scene) -> None:
    import pyvista

    geom = scene.geometry
    assert isinstance(geom, PerforatedBlock)
    tris, tri_tags = _cells(blocks, "triangle")
    tets, _ = _cells(blocks, "tetra")
    is_wall = np.array([names.get(int(t), "").startswith(_WALL_PREFIXES) for t in tri_tags])
    walls = _poly(points, tris[is_wall])
    walls.cell_data["wall"] = np.array(
        [sorted(set(tri_tags[is_wall])).index(t) for t in tri_tags[is_wall]]
    )
    faces = _poly(points, tris[~is_wall])

    plotter.subplot(0, 0)
    plotter.add_text(f"{scene.name}: {len(tets)} tetrahedra", font_size=11)
    plotter.add_mesh(faces, color="lightgrey", show_edges=True, edge_color="dimgrey", opacity=0.5)
    plotter.add_mesh(walls, scalars="wall", cmap="tab10", show_scalar_bar=False)
    plotter.view_isometric()

    # a cut through the first tunnel and the wellbore axis: keep the cells on one side
    w = axis_vector(geom.wellbore.axis)
    if geom.perforations:
        d = np.asarray(geom.perforations[0].direction)
        focus = (
            geom.perforations[0].start(geom.wellbore)
            + 0.5 * geom.perforations[0].profile.length * d
        )
        span = geom.wellbore.radius + geom.perforations[0].profile.length
    else:
        d = np.roll(w, 1)
        focus = np.zeros(3)
        span = 4.0 * geom.wellbore.radius
    normal = np.cross(d, w)
    for axis in geom.symmetry:  # on a mirror plane, look at the kept side's face
        e = axis_vector(axis)
        if abs(normal @ e) > 0.999:
            normal = e
    grid = pyvista.UnstructuredGrid({pyvista.CellType.TETRA: tets}, points)
    centres = points[tets].mean(axis=1)
    near = np.flatnonzero(
        (centres @ normal >= 0.0) & (np.linalg.norm(centres - focus, axis=1) <= 1.5 * span)
    )
    layer = grid.extract_cells(near)
    plotter.subplot(0, 1)
    plotter.add_text("elements along a cut through tunnel 1 and the wellbore axis", font_size=10)
    plotter.add_mesh(layer, color="wheat", show_edges=True, edge_color="black", line_width=0.5)
    plotter.add_mesh(walls, scalars="wall", cmap="tab10", show_scalar_bar=False)
    for axis in geom.symmetry:  # centre the close-up on the kept side of the planes
        e = axis_vector(axis)
        if abs(e @ normal) < 0.5 and abs(e @ focus) < 1e-12:
            focus = focus + 0.35 * span * e
    plotter.camera.focal_point = tuple(focus)
    plotter.camera.position = tuple(focus - 3.0 * span * normal)
    plotter.camera.up = tuple(w)
    plotter.reset_camera_clipping_range()


def _render_2d(plotter: Any, points: np.ndarray, blocks: dict, names: dict, scene: Scene) -> None:
    tris, tri_tags = _cells(blocks, "triangle")
    lines, line_tags = _cells(blocks, "line")
    surface = _poly(points, tris)
    labels = sorted(set(tri_tags.tolist()))
    surface.cell_data["group"] = np.array([labels.index(t) for t in tri_tags])
    line_names = np.array([names.get(int(t), "") for t in line_tags])
    features = [
        (_poly(points, lines[line_names == name]), color)
        for name, color in _LINE_TAGS.items()
        if np.any(line_names == name)
    ]
    geom = scene.geometry
    if hasattr(geom, "crack"):
        zoom = float(getattr(geom.crack, "path_length", None) or geom.crack.length)
    else:
        zoom = 4.0 * float(geom.wellbore.diameter)
    for col, title in ((0, f"{scene.name}: {len(tris)} triangles"), (1, "near the crack/borehole")):
        plotter.subplot(0, col)
        plotter.add_text(title, font_size=11)
        plotter.add_mesh(
            surface, scalars="group", cmap="Pastel1", show_edges=True, show_scalar_bar=False
        )
        for feature, color in features:
            plotter.add_mesh(feature, color=color, line_width=4)
        plotter.view_xy()
        if col == 1:
            cx = 0.25 * zoom if "x" in geom.symmetry else 0.0
            cy = 0.25 * zoom if "y" in geom.symmetry else 0.0
            plotter.camera.focal_point = (cx, cy, 0.0)
            plotter.camera.position = (cx, cy, 2.5 * zoom)
            plotter.camera.up = (0.0, 1.0, 0.0)
            plotter.reset_camera_clipping_range()


__all__ = [
    "render_mesh",
]

"""Pictures people look at: line plots (matplotlib) and field renderings (PyVista).

Rendering happens on rank 0 only; distributed fields are gathered there first.
"""

from __future__ import annotations

import atexit
import os
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import dolfinx
import dolfinx.plot
import numpy as np
from mpi4py import MPI


def ensure_display() -> None:
    """Give VTK an X display: start a private Xvfb when none is set.

    ``-displayfd`` lets Xvfb pick a free display number, so concurrent runs on one
    machine do not collide.
    """
    if os.environ.get("DISPLAY"):
        return
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        raise RuntimeError(
            "no X display and no Xvfb to render pictures; install xvfb or pass --no-pictures"
        )
    read_fd, write_fd = os.pipe()
    proc = subprocess.Popen(
        [xvfb, "-displayfd", str(write_fd), "-screen", "0", "1280x1024x24", "-nolisten", "tcp"],
        pass_fds=(write_fd,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write_fd)
    with os.fdopen(read_fd) as fh:
        display = fh.readline().strip()
    if not display:
        proc.kill()
        raise RuntimeError("Xvfb did not start; pictures cannot be rendered")
    os.environ["DISPLAY"] = f":{display}"
    atexit.register(proc.terminate)


def _gather_grid(
    f: dolfinx.fem.Function,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
    """Gather the VTK topology, cell types, points and values of ``f`` on rank 0.

    ``f`` is a Lagrange function (point data) or a DG0 function (cell data).
    """
    V = f.function_space
    mesh = V.mesh
    comm = mesh.comm
    tdim = mesh.topology.dim
    owned = np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
    bs = V.dofmap.index_map_bs
    if V.element.basix_element.discontinuous and V.element.basix_element.degree == 0:
        topology, types, points = dolfinx.plot.vtk_mesh(mesh, tdim, owned)
        dofs = np.array([V.dofmap.cell_dofs(int(c))[0] for c in owned], dtype=np.int64)
        values = f.x.array.reshape(-1, bs)[dofs]
    else:
        topology, types, points = dolfinx.plot.vtk_mesh(V)
        values = f.x.array.reshape(-1, bs)[: len(points)]
        # keep only owned cells to avoid drawing ghosts twice
        cells_per = topology.reshape(-1, topology[0] + 1)[: len(owned)]
        topology = cells_per.ravel()
        types = types[: len(owned)]
    parts = comm.gather((topology, types, points, values), root=0)
    if comm.rank != 0:
        return None
    assert parts is not None
    topo_all, types_all, pts_all, vals_all = [], [], [], []
    offset = 0
    for topo, typ, pts, vals in parts:
        cells = topo.reshape(len(typ), -1).copy()
        cells[:, 1:] += offset
        topo_all.append(cells.ravel())
        types_all.append(typ)
        pts_all.append(pts)
        vals_all.append(vals)
        offset += len(pts)
    return (
        np.concatenate(topo_all),
        np.concatenate(types_all),
        np.concatenate(pts_all),
        np.concatenate(vals_all),
    )


def render_field(
    f: dolfinx.fem.Function,
    path: str | os.PathLike[str],
    title: str,
    scale: float = 1.0,
    unit: str = "",
    warp_by: dolfinx.fem.Function | None = None,
    warp_factor: float = 0.0,
    cmap: str = "coolwarm",
    crop: tuple[float, float, float, float] | None = None,
) -> None:
    """Render a scalar field to PNG with PyVista, off-screen (collective call).

    ``crop = (xmin, xmax, ymin, ymax)`` keeps only cells whose centres lie inside.
    """
    grid_data = _gather_grid(f)
    warp_data = _gather_grid(warp_by) if warp_by is not None else None
    if grid_data is None:
        return
    ensure_display()
    import pyvista

    pyvista.OFF_SCREEN = True
    topology, types, points, values = grid_data
    grid = pyvista.UnstructuredGrid(topology, types, points)
    label = f"{title} [{unit}]" if unit else title
    data = values[:, 0] * scale
    if len(data) == grid.n_cells:
        grid.cell_data[label] = data
    else:
        grid.point_data[label] = data
    if warp_data is not None and warp_factor:
        disp = np.zeros((len(points), 3))
        disp[:, : warp_data[3].shape[1]] = warp_data[3]
        grid.points = np.asarray(grid.points) + warp_factor * disp
    if crop is not None:
        centres = grid.cell_centers().points
        inside = (
            (centres[:, 0] >= crop[0])
            & (centres[:, 0] <= crop[1])
            & (centres[:, 1] >= crop[2])
            & (centres[:, 1] <= crop[3])
        )
        grid = grid.extract_cells(np.flatnonzero(inside))
    plotter = pyvista.Plotter(off_screen=True, window_size=(1000, 800))
    plotter.add_mesh(
        grid, scalars=label, cmap=cmap, show_edges=False, scalar_bar_args={"title": label}
    )
    plotter.add_mesh(grid.extract_all_edges(), color="black", opacity=0.15, line_width=1)
    if np.allclose(points[:, 2], 0.0):
        plotter.view_xy()
    else:
        plotter.view_isometric()
    plotter.add_text(title, font_size=12)
    plotter.screenshot(str(path))
    plotter.close()


def plot_lines(
    path: str | os.PathLike[str],
    curves: Sequence[tuple[np.ndarray, np.ndarray, str, str]],
    xlabel: str,
    ylabel: str,
    title: str,
    comm: MPI.Comm = MPI.COMM_WORLD,
    xscale: str = "linear",
) -> None:
    """Plot ``(x, y, label, style)`` curves to PNG from rank 0 (``xscale`` e.g. ``"log"``)."""
    if comm.rank == 0:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(7, 4.5))
        for x, y, label, style in curves:
            ax.plot(x, y, style, label=label)
        ax.set_xscale(xscale)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(title)
        ax.grid(alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(Path(path), dpi=120)
        plt.close(fig)
    comm.barrier()


def plot_interface_states(
    path: str | os.PathLike[str],
    segments: np.ndarray,
    states: np.ndarray,
    title: str,
    extent: float,
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> None:
    """Draw 2D interfaces coloured by failure state (0 intact, 1 tensile, 2 shear)."""
    parts = comm.gather((segments[:, :, :2], states), root=0)
    if comm.rank != 0:
        comm.barrier()
        return
    assert parts is not None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    segs = np.concatenate([p for p, _ in parts])
    st = np.concatenate([s for _, s in parts])
    fig, ax = plt.subplots(figsize=(6.5, 6.5))
    styles = {
        0: ("0.8", 0.4, "intact"),
        1: ("tab:red", 2.0, "tensile"),
        2: ("tab:blue", 2.0, "shear"),
    }
    for code, (color, width, label) in styles.items():
        mask = st == code
        if np.any(mask):
            ax.add_collection(
                LineCollection(
                    segs[mask], colors=color, linewidths=width, label=f"{label} ({mask.sum()})"
                )
            )
    ax.set_xlim(-extent, extent)
    ax.set_ylim(-extent, extent)
    ax.set_aspect("equal")
    ax.set_xlabel("x (along SH) [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title)
    ax.legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(Path(path), dpi=120)
    plt.close(fig)
    comm.barrier()


def owned_boundary_triangles(tmesh: Any, names: Sequence[str]) -> np.ndarray:
    """Vertex coordinates (F, nv, 3) of this rank's owned facets of groups ``names``."""
    mesh = tmesh.mesh
    fdim = mesh.topology.dim - 1
    size = mesh.topology.index_map(fdim).size_local
    facets = [tmesh.facets(n) for n in names]
    local = np.unique(np.concatenate(facets)) if facets else np.zeros(0, np.int32)
    local = local[local < size].astype(np.int32)
    if not len(local):  # entities_to_geometry divides by the count
        return np.zeros((0, fdim + 1, 3))
    nodes = dolfinx.mesh.entities_to_geometry(mesh, fdim, local, False)
    return mesh.geometry.x[nodes]


def _offscreen_pyvista() -> Any:
    """Return PyVista set to render off screen (an X display started if needed)."""
    ensure_display()
    import pyvista

    pyvista.OFF_SCREEN = True
    return pyvista


def _triangles(pyvista: Any, tris: np.ndarray) -> Any:
    """Return a PolyData of triangles (T, 3, 3), each with its own three points."""
    pts = tris.reshape(-1, 3)
    faces = np.column_stack([np.full(len(tris), 3), np.arange(len(pts)).reshape(-1, 3)])
    return pyvista.PolyData(pts, faces.ravel())


def render_fracture_pattern(
    path: str | os.PathLike[str],
    points: np.ndarray,
    states: np.ndarray,
    walls: np.ndarray,
    title: str,
    view_axis: int = 1,
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> None:
    """Draw broken interfaces by failure state around the cavity walls (collective).

    ``points`` (F, 3, 3) and ``states`` (1 tensile, 2 shear, 0 intact: skipped)
    are this rank's owned interface facets; ``walls`` (W, 3, 3) its cavity wall
    triangles.  Two views: isometric, and along axis ``view_axis`` (the wellbore).
    """
    broken = states > 0
    parts = comm.gather((points[broken], states[broken], walls), root=0)
    if comm.rank != 0:
        comm.barrier()
        return
    assert parts is not None
    pyvista = _offscreen_pyvista()

    def surface(tris: np.ndarray) -> Any:
        return _triangles(pyvista, tris)

    tris = np.concatenate([p for p, _, _ in parts]) if parts else np.zeros((0, 3, 3))
    codes = np.concatenate([s for _, s, _ in parts]) if parts else np.zeros(0)
    wall = np.concatenate([w for _, _, w in parts])
    plotter = pyvista.Plotter(off_screen=True, shape=(1, 2), window_size=(1600, 800))
    for col in range(2):
        plotter.subplot(0, col)
        if len(wall):
            plotter.add_mesh(surface(wall), color="lightgrey", opacity=0.35)
        for code, colour, label in ((1, "red", "tensile"), (2, "royalblue", "shear")):
            mask = codes == code
            if mask.any():
                plotter.add_mesh(
                    surface(tris[mask]),
                    color=colour,
                    show_edges=True,
                    edge_color="black",
                    line_width=0.5,
                    label=f"{label} ({int(mask.sum())})",
                )
        if col == 0:
            plotter.view_isometric()
            plotter.add_text(title, font_size=11)
            if codes.size:
                plotter.add_legend(bcolor="white", face="rectangle")
        else:
            (plotter.view_yz, plotter.view_xz, plotter.view_xy)[view_axis]()
            plotter.add_text(f"along {'xyz'[view_axis]} (the wellbore axis)", font_size=10)
        plotter.show_axes()
    plotter.screenshot(str(path))
    plotter.close()
    comm.barrier()


def render_facet_series(
    path: str | os.PathLike[str],
    points: np.ndarray,
    series: Sequence[np.ndarray],
    titles: Sequence[str],
    walls: np.ndarray,
    label: str,
    threshold: float = 0.0,
    comm: MPI.Comm = MPI.COMM_WORLD,
    view_axis: int | None = None,
) -> None:
    """Draw facet values at several times side by side (collective).

    ``points`` (F, 3, 3): this rank's facet triangles; ``series``: one (F,) array
    per panel; facets at or below ``threshold`` are left out; ``walls`` (W, 3, 3)
    this rank's cavity wall triangles, drawn grey.  One colour scale for all panels;
    the view is isometric, or along axis ``view_axis``.
    """
    parts = comm.gather((points, [np.asarray(v) for v in series], walls), root=0)
    if comm.rank != 0:
        comm.barrier()
        return
    assert parts is not None
    pyvista = _offscreen_pyvista()

    def surface(tris: np.ndarray) -> Any:
        return _triangles(pyvista, tris)

    tris = np.concatenate([p for p, _, _ in parts])
    wall = np.concatenate([w for _, _, w in parts])
    values = [np.concatenate([v[k] for _, v, _ in parts]) for k in range(len(series))]
    top = max((float(v.max()) for v in values if v.size), default=1.0) or 1.0
    plotter = pyvista.Plotter(
        off_screen=True, shape=(1, len(values)), window_size=(480 * len(values), 520)
    )
    for col, (vals, title) in enumerate(zip(values, titles, strict=True)):
        plotter.subplot(0, col)
        if len(wall):
            plotter.add_mesh(surface(wall), color="lightgrey", opacity=0.5)
        shown = vals > threshold
        if shown.any():
            surf = surface(tris[shown])
            surf.cell_data[label] = vals[shown]
            plotter.add_mesh(
                surf,
                scalars=label,
                clim=(0.0, top),
                cmap="viridis",
                opacity=0.6,
                show_scalar_bar=col == len(values) - 1,
            )
        if view_axis is None:
            plotter.view_isometric()
        else:
            (plotter.view_yz, plotter.view_xz, plotter.view_xy)[view_axis]()
        plotter.add_text(title, font_size=11)
    plotter.link_views()
    plotter.screenshot(str(path))
    plotter.close()
    comm.barrier()


__all__ = [
    "ensure_display",
    "plot_interface_states",
    "plot_lines",
    "render_facet_series",
    "render_field",
    "render_fracture_pattern",
]

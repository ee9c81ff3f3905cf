"""Joint apertures that keep the joint network's equivalent medium when the mesh changes.

Every interface of the fracturable zone is a joint, so a finer mesh has more
joints per unit volume.  With one aperture ``a`` on every facet the network's
void per unit volume and its equivalent conductivity both grow as ``1 / h``
(docs/seepage.md: ``k_eq h`` is the same on four annulus meshes; No. 2's zone
holds twice the void at the default mesh as at the coarse one), so the rock
the fluid seeps into changes with the mesh.  The filling front's speed, which
goes as their ratio (``~ a^2``), does not: a prescribed cavity pressure hardly
notices, a pumped cavity does (its pressure follows what the joints take).

Given the cell size ``h_ref`` at which ``a`` holds, each facet gets

- a hydraulic aperture ``a (h / h_ref)^(1/3)`` (its cubic-law conductivity):
  the equivalent conductivity, ``~ a_h^3 / h``, is that of the reference mesh;
- a void aperture ``a h / h_ref`` (its fluid volume ``a_v A``): the void per
  unit volume, ``~ a_v / h``, is that of the reference mesh;

with ``h`` the mean diameter of the facet's two cells.  At ``h = h_ref`` both
are ``a``.  The ``~`` hides a lattice factor of the mesh's cell shapes; it is
the same for meshes of one generator and quality, not across cell types.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from hfcdem.config.materials import JointAperture
from hfcdem.flow.network import Network
from hfcdem.flow.seepage import network_positions, network_values
from hfcdem.solid.cdem import CDEMSolid


def network_cell_sizes(
    solid: CDEMSolid,
    net: Network,
    facets: Sequence[int] | np.ndarray,
    positions: np.ndarray | None = None,
) -> np.ndarray:
    """Mean diameter of the two cells of every facet of ``net`` (m), the same on every rank.

    ``facets``: the local interfaces ``net`` was built from; ``positions``
    their :func:`~hfcdem.flow.seepage.network_positions` when known (collective).
    """
    facets = np.asarray(facets, dtype=np.int64)
    if positions is None:
        positions = network_positions(solid, net, facets)
    return network_values(solid, net, facets, positions, solid.h)


def network_apertures(
    solid: CDEMSolid,
    net: Network,
    facets: Sequence[int] | np.ndarray,
    aperture: float | JointAperture,
    positions: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Hydraulic and void apertures of every facet of ``net`` (m; collective).

    A plain number is one aperture for every facet, flow and void alike.
    ``positions``: as for :func:`network_cell_sizes`.
    """
    if not isinstance(aperture, JointAperture):
        aperture = JointAperture(float(aperture))
    if aperture.reference_size is None:
        return aperture.scaled(np.zeros(net.size))
    return aperture.scaled(network_cell_sizes(solid, net, facets, positions))


__all__ = ["JointAperture", "network_apertures", "network_cell_sizes"]

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
from mpi4py import MPI

from hfcdem.config.materials import JointAperture
from hfcdem.flow.network import Network
from hfcdem.flow.seepage import network_positions
from hfcdem.solid.cdem import CDEMSolid


def network_cell_sizes(
    solid: CDEMSolid, net: Network, facets: Sequence[int] | np.ndarray
) -> np.ndarray:
    """Mean diameter of the two cells of every facet of ``net`` (m), the same on every rank.

    ``facets``: the local interfaces ``net`` was built from (collective).
    """
    local = np.unique(np.asarray(facets, dtype=np.int64))
    owned = local[solid.owned[local]]
    sizes = np.zeros(net.size)
    sizes[network_positions(solid, net, owned)] = solid.h[owned]
    # each joint is owned by one rank: the sum is its value, exactly
    solid.comm.Allreduce(MPI.IN_PLACE, sizes, op=MPI.SUM)
    return sizes


def network_apertures(
    solid: CDEMSolid,
    net: Network,
    facets: Sequence[int] | np.ndarray,
    aperture: float | JointAperture,
) -> tuple[np.ndarray, np.ndarray]:
    """Hydraulic and void apertures of every facet of ``net`` (m; collective).

    A plain number is one aperture for every facet, flow and void alike.
    """
    if not isinstance(aperture, JointAperture):
        aperture = JointAperture(float(aperture))
    if aperture.reference_size is None:
        return aperture.scaled(np.zeros(net.size))
    return aperture.scaled(network_cell_sizes(solid, net, facets))


__all__ = ["JointAperture", "network_apertures", "network_cell_sizes"]

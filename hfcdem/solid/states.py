"""The state of every interface facet: failure, contact and friction.

``state`` is the failure state (0 intact, 1 tensile, 2 shear, as
:class:`~hfcdem.solid.interfaces.FacetState`); ``contact`` the contact sub-state
of a broken facet (open, stick, slip); ``friction_traction`` the Coulomb traction
of a sliding facet on its ``+`` face; ``released`` the broken facets around a
block cut loose from the rock, held open under the fluid that surrounds it
(:mod:`hfcdem.solid.fragments`); ``shut_at`` the fluid pressure at which a broken
facet last closed (NaN: none), for contact hysteresis.  Owners decide; ghosts copy.
A cascade of breaks that does not settle at a fixed load stops with
:class:`CascadeStopped`; the states and breaks reached so far are kept.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import dolfinx
import numpy as np

from hfcdem.solid.interfaces import FacetState
from hfcdem.solvers import SimulationStopped

# contact sub-states of broken facets
OPEN, STICK, SLIP = 0, 1, 2


class CascadeStopped(SimulationStopped):
    """The interface states did not settle at a fixed load (raised on every rank).

    ``load_factor`` is the load of the cascade, ``broken`` the facets it broke
    (global count), ``iterations`` the re-solves it took; ``first_break`` the
    load factor of the first break of a ramp, if the stop came from one.  The
    solid keeps the states and break events reached so far.
    """

    def __init__(
        self,
        load_factor: float,
        broken: int,
        iterations: int,
        first_break: float | None = None,
    ) -> None:
        self.load_factor = load_factor
        self.broken = broken
        self.iterations = iterations
        self.first_break = first_break
        first = "" if first_break is None else f", first break at {first_break:.6g}"
        super().__init__(
            f"interface states did not settle in {iterations} iterations at load factor "
            f"{load_factor:.6g} ({broken} facets broke in the cascade{first}); "
            "try break_rule='all' or a smaller load step"
        )


def faces_overlap(gap: np.ndarray, pressure: np.ndarray, kn: np.ndarray) -> np.ndarray:
    """Open faces that close: those whose springs would push back harder than the fluid.

    ``gap`` is the mechanical opening past the pre-compression offset (negative:
    the faces overlap), ``pressure`` the fluid pressure on the faces, ``kn`` the
    normal spring stiffness.  A closed face opens when its spring traction holds
    less compression than the fluid pressure
    (:meth:`InterfaceStates.switch_contacts`); an open one closes when its
    springs, were they there, would hold more: ``kn (-gap) > p``.  Closing on
    ``gap < 0`` instead leaves a band ``-p/kn < gap < 0`` where each state sends
    the facet to the other (chatter).
    """
    return np.asarray(gap) < -np.maximum(np.asarray(pressure, dtype=float), 0.0) / kn


@dataclass(eq=False)
class InterfaceStates:
    """Failure state, contact sub-state and friction traction per interface facet."""

    state: np.ndarray  # (F,) int8 FacetState
    contact: np.ndarray  # (F,) int8 OPEN, STICK or SLIP
    friction_traction: np.ndarray  # (F, gdim) Pa, on the + face of sliding facets
    released: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))  # (F,)
    shut_at: np.ndarray = field(default_factory=lambda: np.zeros(0))  # (F,) Pa, NaN: none

    def __post_init__(self) -> None:
        if not len(self.state) == len(self.contact) == len(self.friction_traction):
            raise ValueError("state, contact and friction_traction need one row per facet")
        if len(self.released) == 0:
            self.released = np.zeros(len(self.state), dtype=bool)
        if len(self.released) != len(self.state):
            raise ValueError("released needs one row per facet")
        if len(self.shut_at) == 0:
            self.shut_at = np.full(len(self.state), np.nan)
        if len(self.shut_at) != len(self.state):
            raise ValueError("shut_at needs one row per facet")

    @classmethod
    def initial(cls, is_crack: np.ndarray, gdim: int) -> InterfaceStates:
        """Pre-existing cracks broken and open; every other facet intact and stuck."""
        count = len(is_crack)
        state = np.where(is_crack, FacetState.TENSILE, FacetState.INTACT).astype(np.int8)
        contact = np.full(count, OPEN, dtype=np.int8)
        contact[~is_crack] = STICK
        return cls(state, contact, np.zeros((count, gdim)))

    def copy(self) -> InterfaceStates:
        """Return an independent copy (to restore after a rejected attempt)."""
        return InterfaceStates(
            self.state.copy(),
            self.contact.copy(),
            self.friction_traction.copy(),
            self.released.copy(),
            self.shut_at.copy(),
        )

    def restore(self, saved: InterfaceStates) -> None:
        """Take the values of ``saved`` in place (arrays handed out stay valid)."""
        self.state[:] = saved.state
        self.contact[:] = saved.contact
        self.friction_traction[:] = saved.friction_traction
        self.released[:] = saved.released
        self.shut_at[:] = saved.shut_at

    def break_facets(self, facets: np.ndarray, modes: np.ndarray) -> None:
        """Break ``facets`` in ``modes``: tensile breaks start open, shear breaks closed."""
        self.state[facets] = modes
        self.contact[facets] = np.where(modes == FacetState.TENSILE, OPEN, STICK)

    def release(self, facets: np.ndarray) -> None:
        """Hold broken ``facets`` open for good: a loose block's faces, under fluid."""
        if np.any(self.state[facets] == FacetState.INTACT):
            raise ValueError("only broken facets can be released")
        self.released[facets] = True
        self.contact[facets] = OPEN
        self.friction_traction[facets] = 0.0

    def switch_contacts(
        self,
        broken: np.ndarray,
        normal_traction: np.ndarray,
        shear_vector: np.ndarray,
        pressure: np.ndarray,
        closing: np.ndarray,
        friction: float,
        hysteresis: bool = False,
    ) -> np.ndarray:
        """Open, close, stick or slip the ``broken`` facets (pure NumPy).

        Returns the facets the hysteresis keeps shut that would open without it.

        ``normal_traction`` and ``shear_vector`` are the tractions at the current
        states, ``pressure`` the fluid pressure per facet, ``closing`` the open
        facets whose faces interpenetrate (:func:`faces_overlap`).

        ``hysteresis``: a facet that closed at a fluid pressure is opened by the
        fluid again only once the pressure on it has passed that one (springs in
        tension open it as without).  A broken facet whose springs hold less
        compression than the fluid, opened together with its neighbours, can be
        pressed shut by their blocks; without hysteresis it opens again at the
        next check under the same pressure, and is shut again (contact chatter,
        one refactorisation each way at fine meshes).  A crack that closed as the
        pressure fell reopens as the pressure passes its closing value, as
        without.  Every closing records its pressure in ``shut_at``; an opening
        clears it, and so does a break of a facet of either of its cells
        (:meth:`~hfcdem.solid.cdem.CDEMSolid.break_facets`): the break unloads
        its springs, so its closing pressure no longer says what holds it shut.
        """
        old = self.contact.copy()
        # closed facets open when their normal traction exceeds the fluid pressure
        closed = broken & (self.contact != OPEN)
        opening = closed & (normal_traction > -pressure)
        held = np.zeros(len(opening), dtype=bool)
        if hysteresis:
            with np.errstate(invalid="ignore"):  # NaN (never shut) compares False
                held = opening & (pressure <= self.shut_at) & (normal_traction <= 0.0)
            opening &= ~held
        self.contact[opening] = OPEN
        self.shut_at[opening] = np.nan
        # open facets close when the faces interpenetrate
        shutting = broken & (old == OPEN) & closing
        self.contact[shutting] = STICK
        self.shut_at[shutting] = pressure[shutting]
        # stick/slip by Coulomb on closed facets
        closed = broken & (self.contact != OPEN)
        limit = friction * np.maximum(-normal_traction, 0.0)
        mag = np.linalg.norm(shear_vector, axis=1)
        sliding = closed & (mag > limit * (1.0 + 1e-9))
        self.contact[closed & ~sliding & (old != SLIP)] = STICK
        self.contact[sliding] = SLIP
        with np.errstate(invalid="ignore", divide="ignore"):
            direction = np.where(mag[:, None] > 0.0, shear_vector / mag[:, None], 0.0)
        self.friction_traction = np.where(
            (self.contact == SLIP)[:, None], direction * limit[:, None], 0.0
        )
        return held

    def sync_ghosts(self, imap: dolfinx.common.IndexMap, facets: np.ndarray) -> None:
        """Copy the owners' state, contact, release and shut pressure to the ghosts (collective)."""
        vec = dolfinx.la.vector(imap, 4, dtype=np.float64)
        arr = vec.array.reshape(-1, 4)
        arr[:] = -1.0
        arr[facets, 0] = self.state
        arr[facets, 1] = self.contact
        arr[facets, 2] = self.released
        arr[facets, 3] = self.shut_at
        vec.scatter_forward()
        self.state[:] = arr[facets, 0].astype(np.int8)
        self.contact[:] = arr[facets, 1].astype(np.int8)
        self.released[:] = arr[facets, 2] > 0.5
        self.shut_at[:] = arr[facets, 3]


__all__ = ["OPEN", "SLIP", "STICK", "CascadeStopped", "InterfaceStates", "faces_overlap"]

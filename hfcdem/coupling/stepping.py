"""The time-step controller of the coupled run, separate from the problem it steps.

The problem attempts a step of the size the controller gives and reports what
happened: a failed solve (halve), a pressure that moved too far (halve), an
overshoot of the next interface break (shorten to land on it, the failure ratio
interpolated linearly in time), or an accepted step (grow when it was easy).
The size stays within ``[dt_min, dt_max]``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

#: the shortest step a cut towards a break asks for, as a fraction of the step cut
_LEAST_CUT = 0.05


@dataclass
class StepController:
    """Adaptive step size and the location of interface events in time."""

    dt: float  # the next step to attempt (s)
    dt_min: float
    dt_max: float
    growth: float = 1.5  # factor after an easy step
    break_tolerance: float = 0.01  # overshoot of the failure ratio allowed at a break
    max_pressure_change: float = math.inf  # relative change of the cavity pressure per step
    easy_iterations: int = 6  # Newton iterations of a step that may grow the next
    max_event_cuts: int = 6  # shortenings towards one break before it is taken as it comes
    last_ratio: float = 0.0  # worst failure ratio of eligible facets, last accepted step
    step_ratio: float = 0.0  # the same, of the attempt under way
    event_cuts: int = 0
    pressure_cuts: int = 0  # attempts halved by max_pressure_change (a run's cost of it)

    def __post_init__(self) -> None:
        if not (self.dt_min > 0.0 and self.dt_max > 0.0):
            raise ValueError("dt_min and dt_max must be positive times in s")
        if not 1.0 <= self.growth:
            raise ValueError(f"growth must be at least 1, got {self.growth!r}")

    def limit(self, remaining: float) -> None:
        """Do not step past the end of the run, ``remaining`` seconds away."""
        self.dt = min(self.dt, remaining)

    def halve(self, dt: float) -> bool:
        """Try half of a failed ``dt`` next; return False when that is below ``dt_min``."""
        self.dt = dt * 0.5
        return self.dt >= self.dt_min

    def retry_with(self, dt: float) -> None:
        """Try ``dt`` next (a shortened attempt)."""
        self.dt = dt

    def _may_cut(self, dt: float) -> bool:
        return dt > 4.0 * self.dt_min

    def pressure_cut(self, dt: float, p_old: float, p_new: float) -> float | None:
        """Half ``dt`` if the cavity pressure moved too far (at least 1 MPa wide), else None."""
        if not self._may_cut(dt):
            return None
        if abs(p_new - p_old) > self.max_pressure_change * max(abs(p_old), 1e6):
            self.pressure_cuts += 1
            return 0.5 * dt
        return None

    def overshoot(self, dt: float, worst: float, switched: bool = False) -> float | None:
        """Return a shorter step that lands on the next break, or None (``worst`` is kept).

        ``worst`` is the attempt's worst failure ratio; a step that overshoots 1 by
        more than ``break_tolerance`` is shortened.  The ratio may jump (fluid
        reaching a facet), so after a few cuts the break is taken as it comes.
        ``switched``: the attempt switched contacts before ``worst``.  A switch can
        make the ratio jump past 1 within a step; a jump that the line from the last
        ratio puts in the step's first 5 % is the switch's, not the load's (a loose
        block: the same jump at any step), and is taken as it comes.
        """
        r0 = self.last_ratio
        if (
            math.isfinite(worst)  # zero strength gives an infinite ratio
            and worst > 1.0 + self.break_tolerance
            and r0 < 1.0
            and self._may_cut(dt)
            and self.event_cuts < self.max_event_cuts
        ):
            frac = (1.0 - r0) / (worst - r0)
            if not (switched and frac < _LEAST_CUT):
                self.event_cuts += 1
                return max(dt * min(max(frac, _LEAST_CUT), 0.9), self.dt_min)
        self.step_ratio = worst
        return None

    def landed(self, worst: float) -> bool:
        """Tell whether the attempt reached the next break (record it; break next step)."""
        return self.last_ratio < 1.0 <= worst and math.isfinite(worst)

    def broke(self) -> None:
        """Interfaces broke: the next break is located afresh."""
        self.event_cuts = 0

    def accepted(self, dt: float, changed: bool, newton_iterations: int) -> None:
        """Take an accepted ``dt``; grow the next if nothing changed and Newton was easy."""
        self.last_ratio = self.step_ratio if not changed else 1.0
        if not changed and newton_iterations <= self.easy_iterations:
            self.dt = min(dt * self.growth, self.dt_max)


__all__ = ["StepController"]

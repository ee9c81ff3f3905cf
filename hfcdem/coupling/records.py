"""What a coupled run reports: one :class:`StepRecord` per accepted step, or a stop."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

# the coupled run stops with the same exception as the solid's cascade (one base)
from hfcdem.io.progress import duration_words
from hfcdem.solvers import SimulationStopped


@dataclass
class StepRecord:
    """One accepted time step (SI units, global values)."""

    time: float
    dt: float
    injection_pressure: float
    injected_volume: float
    cavity_fluid: float
    fracture_fluid: float
    fracture_volume: float
    leaked_volume: float
    mass_error: float  # |injected - fluid held - leaked| / max(injected, initial fluid)
    volume_mismatch: float  # |fluid held - compressed void volume|, same scale (solver)
    wet_facets: int
    tensile: int
    shear: int
    fracture_degree: float
    newton_iterations: int
    rebuilds: int
    wall_time: float
    # broken facets contact hysteresis held shut at the step's last contact check;
    # histories written before this column read back as 0
    held_shut: int = 0

    def as_row(self) -> dict[str, float]:
        """Return the record as a flat dict (the columns of history.csv)."""
        return dict(self.__dict__)

    def progress_line(self, left_s: float) -> str:
        """One line of progress, with ``left_s``, the wall time left (s; nan: not known)."""
        return (
            f"t {self.time:9.4g} s  p {self.injection_pressure / 1e6:9.4f} MPa  "
            f"broken {self.tensile + self.shear:5d}  wet {self.wet_facets:5d}  "
            f"dt {self.dt:8.3g} s  wall {self.wall_time:7.1f} s  eta {duration_words(left_s):>6}"
        )

    @classmethod
    def from_row(cls, row: dict[str, float]) -> StepRecord:
        """Return the record of a row of history.csv (counts back to integers)."""
        kinds = {f.name: f.type for f in fields(cls)}
        values: dict[str, Any] = {
            k: int(v) if kinds[k] in (int, "int") else float(v) for k, v in row.items()
        }
        return cls(**values)


__all__ = ["SimulationStopped", "StepRecord"]

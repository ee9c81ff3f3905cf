"""The solid meets the fluid: hydraulic fracturing stepped in time.

``hydrofrac`` couples :class:`~hfcdem.solid.cdem.CDEMSolid` with the flow
network: the solid condensed onto the pressure unknowns, implicit Euler steps,
interface events repeated to convergence.
"""

__all__: list[str] = []

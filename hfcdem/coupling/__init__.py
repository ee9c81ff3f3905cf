"""The solid meets the fluid: hydraulic fracturing stepped in time.

``hydrofrac`` couples :class:`~hfcdem.solid.cdem.CDEMSolid` with the flow
network: implicit Euler steps, interface events repeated to convergence.
``condense`` condenses the solid onto the pressure groups (and measures the
cavity); ``stepping`` is the step-size controller; ``settings`` holds
:class:`FlowSettings`.
"""

__all__: list[str] = []

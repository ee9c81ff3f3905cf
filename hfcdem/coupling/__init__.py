"""The solid meets the fluid: hydraulic fracturing stepped in time.

``hydrofrac`` couples :class:`~hfcdem.solid.cdem.CDEMSolid` with the flow
network: implicit Euler steps, interface events repeated to convergence.
``condense`` condenses the solid onto the pressure groups (and measures the
cavity); ``groups`` builds the network, its pressure groups and wet joints;
``fluidstate`` is the fluid record per facet, ``checkpoint`` its JSON form;
``events`` switches contacts and picks breaks; ``fields`` gives the output
fields; ``records`` the step records; ``stepping`` is the step-size
controller; ``settings`` holds :class:`FlowSettings`; ``breakdown`` finds the
breakdown in a pressure history, one rule for every rung.
"""

__all__: list[str] = []

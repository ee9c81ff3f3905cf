"""hfcdem: hydraulic fracture initiation from perforation tunnels with a CDEM model on DOLFINx."""

__version__ = "0.1.0"

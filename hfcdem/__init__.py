"""hfcdem: hydraulic fracture initiation from perforation tunnels with a CDEM model on DOLFINx.

A scene flows one way through the subpackages::

    config  -> mesh        -> solid        -> flow, coupling       -> io
    (scene)    (TaggedMesh)   (CDEMSolid)     (HydraulicFracture)     (files, pictures)

and ``workflows`` runs the whole chain.  The names below are the public API;
they are imported on first use, so ``import hfcdem`` stays cheap::

    import hfcdem
    scene = hfcdem.load_scene("meshes/scenes/perforation_no2.toml", resolution="coarse")
    summary = hfcdem.run_scene(scene, "results/no2")
    results = hfcdem.read_results("results/no2")
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

# public name -> module that defines it
_API = {
    # config: scene files become validated dataclasses
    "load_scene": "hfcdem.config.scene",
    "parse_scene": "hfcdem.config.scene",
    "Scene": "hfcdem.config.geometry",
    "SceneError": "hfcdem.config.tables",
    "FieldError": "hfcdem.config.units",
    "Physics": "hfcdem.config.physics",
    # mesh: a scene becomes a tagged DOLFINx mesh
    "create_scene_mesh": "hfcdem.mesh.build",
    "mesh_scene": "hfcdem.mesh.build",
    "mesh_geometry": "hfcdem.mesh.build",
    "TaggedMesh": "hfcdem.mesh.tagged",
    "MeshingError": "hfcdem.mesh.tagged",
    # solid: blocks and interface springs
    "CDEMSolid": "hfcdem.solid.cdem",
    "CascadeStopped": "hfcdem.solid.states",
    "Loads": "hfcdem.solid.cdem",
    "InterfaceModel": "hfcdem.config.materials",
    "ElasticMaterial": "hfcdem.config.materials",
    "InSituStress": "hfcdem.config.materials",
    # flow and coupling: the fluid in the fractures
    "Fluid": "hfcdem.config.materials",
    "Injection": "hfcdem.config.materials",
    "CarterLeakOff": "hfcdem.flow.fluid",
    "HydraulicFracture": "hfcdem.coupling.hydrofrac",
    "FlowSettings": "hfcdem.coupling.hydrofrac",
    "StepRecord": "hfcdem.coupling.hydrofrac",
    "SimulationStopped": "hfcdem.solvers",
    "ValidityLimit": "hfcdem.solvers",
    # workflows and results
    "build_solid": "hfcdem.workflows.run",
    "build_fracture": "hfcdem.workflows.run",
    "run_scene": "hfcdem.workflows.run",
    "load_study": "hfcdem.workflows.study",
    "run_study": "hfcdem.workflows.study",
    "detect_breakdown": "hfcdem.coupling.breakdown",
    "in_situ_wall_tension": "hfcdem.workflows.wall_stress",
    "read_results": "hfcdem.io.files",
    "Results": "hfcdem.io.files",
    "SolverError": "hfcdem.solvers",
}

__all__ = ["__version__", *sorted(_API)]


def __getattr__(name: str) -> Any:
    if name in _API:
        value = getattr(importlib.import_module(_API[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'hfcdem' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API))

"""The package's layers: a scene flows one way, config -> mesh -> solid -> flow -> coupling -> io.

Read from the source (no imports), so the checks hold whatever is installed.
"""

import ast
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "hfcdem"
# Lower layers first; a module may import its own layer and the ones before it.
LAYERS = [
    "analytic",
    "solvers",
    "references",
    "config",
    "mesh",
    "solid",
    "flow",
    "coupling",
    "io",
    "info",
    "workflows",
    "reproduce",
    "cli",
    "__main__",
]
# Atomic writers and the off-screen plotting switch serve every layer that
# writes a file, the progress cadence every loop that says where it is; they
# import nothing of the solid, flow, coupling or workflows.
SHARED = {"hfcdem.io.files", "hfcdem.io.plots", "hfcdem.io.progress"}


def _module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path, top_level_only: bool = False) -> set[str]:
    tree = ast.parse(path.read_text())
    nodes = tree.body if top_level_only else list(ast.walk(tree))
    found = set()
    for node in nodes:
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("hfcdem"):
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("hfcdem"))
    return found


def _layer(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "hfcdem"


def test_every_module_belongs_to_a_layer():
    layers = {_layer(_module_name(p)) for p in PACKAGE.rglob("*.py")}
    assert layers - {"hfcdem"} == set(LAYERS)


def test_layers_import_only_downstream():
    upward = []
    for path in PACKAGE.rglob("*.py"):
        here = _layer(_module_name(path))
        if here == "hfcdem":
            continue  # the lazy public API names every layer
        for target in _imports(path) - SHARED:
            there = _layer(target)
            if there != "hfcdem" and LAYERS.index(there) > LAYERS.index(here):
                upward.append(f"{path.relative_to(ROOT)} imports {target}")
    assert not upward, "\n".join(sorted(upward))


def test_shared_io_modules_stay_low():
    for name in SHARED:
        path = PACKAGE / Path(*name.split(".")[1:]).with_suffix(".py")
        above = [t for t in _imports(path) if LAYERS.index(_layer(t)) > LAYERS.index("mesh")]
        above = [t for t in above if t not in SHARED and _layer(t) != "io"]
        assert not above, f"{name} imports {above}"


def test_no_import_cycle_between_modules():
    graph: dict[str, set[str]] = defaultdict(set)
    modules = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    for name, path in modules.items():
        graph[name] = {t for t in _imports(path, top_level_only=True) if t in modules} - {name}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                cycle = [*stack[stack.index(nxt) :], nxt]
                raise AssertionError("import cycle: " + " -> ".join(cycle))
            if nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for name in sorted(modules):
        if name not in state:
            visit(name)


def test_every_scene_reads_without_a_solver_installed():
    """config/ validates every shipped scene with DOLFINx, PETSc, UFL and Gmsh unimportable."""
    script = """
import sys
from importlib.abc import MetaPathFinder
from pathlib import Path

class Block(MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {"dolfinx", "petsc4py", "ufl", "basix", "gmsh", "pyvista"}:
            raise ImportError(f"blocked: {name}")
        return None

sys.meta_path.insert(0, Block())
from hfcdem.config.scene import load_scene
scenes = sorted(Path(sys.argv[1]).glob("*.toml"))
for path in scenes:
    load_scene(path)
print(len(scenes))
"""
    scenes = ROOT / "meshes" / "scenes"
    out = subprocess.run(
        [sys.executable, "-c", script, str(scenes)],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
        timeout=120,
    )
    assert out.returncode == 0, out.stderr
    assert int(out.stdout.strip()) == len(list(scenes.glob("*.toml"))) > 10

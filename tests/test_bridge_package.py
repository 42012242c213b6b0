"""Layout of the bridge package: modules import each other without a cycle; registry names resolve."""

import ast
import graphlib
from pathlib import Path

import framework.structures.bridge as bridge
from framework.structures.registry import MEASUREMENTS, STRUCTURES, resolve

PACKAGE_DIR = Path(bridge.__file__).parent
PACKAGE = "framework.structures.bridge"


def _package_imports() -> dict[str, set[str]]:
    """Sibling modules imported by each module (anywhere in it, function bodies included)."""
    graph = {}
    for path in sorted(PACKAGE_DIR.glob("*.py")):
        names = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                raise AssertionError(f"{path.name}: relative import")
            modules = [node.module] if isinstance(node, ast.ImportFrom) else []
            if isinstance(node, ast.Import):
                modules = [alias.name for alias in node.names]
            for module in modules:
                if module and module.startswith(PACKAGE + "."):
                    names.add(module.split(".")[3])
                elif module == PACKAGE:
                    names.add("__init__")
        graph[path.stem] = names
    return graph


def test_package_modules_form_a_dag():
    graph = _package_imports()
    assert set(graph) >= {"geometry", "build", "modes", "fast", "model", "data", "reference"}
    order = list(graphlib.TopologicalSorter(graph).static_order())  # raises CycleError on a cycle
    # the package face imports the model layers; nothing below it imports the face
    assert set(order[: order.index("__init__")]) >= {"geometry", "build", "modes", "fast", "model", "data", "reference"}
    assert all("__init__" not in deps for name, deps in graph.items() if name != "__init__")
    # the model layers below the factory never reach up to it
    for low in ("geometry", "data", "parameters", "build", "modes", "fast"):
        assert not graph[low] & {"model", "reference"}, (low, graph[low])


def test_registry_entries_resolve_to_the_package_functions():
    assert resolve(STRUCTURES["bridge"], "structure") is bridge.model.make_model
    assert resolve(MEASUREMENTS["bridge"], "measured") is bridge.reference.measured


def test_package_exports_every_name_in_all():
    missing = [name for name in bridge.__all__ if not hasattr(bridge, name)]
    assert missing == []
    assert {"make_model", "measured", "pair_by_type", "bridge_parameters", "PARAMETER_NAMES"} <= set(bridge.__all__)

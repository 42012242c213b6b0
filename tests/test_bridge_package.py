"""Layout of the bridge package: modules import each other without a cycle, nothing inside imports
the package face or the descriptor, and the registered descriptor holds the package's functions."""

import ast
import graphlib
from pathlib import Path

import framework.structures.bridge as bridge
from framework.structures.registry import CAMPAIGNS, CATALOGUES, MEASUREMENTS, STRUCTURES, describe

PACKAGE_DIR = Path(bridge.__file__).parent
PACKAGE = "framework.structures.bridge"
#: the model layers: geometry, sections, build, modes, fast path, factory, data
MODEL_LAYERS = {"geometry", "build", "modes", "fast", "model", "data", "reference", "parameters", "section"}


def _package_imports() -> dict[str, set[str]]:
    """Sibling modules imported by each module (anywhere in it, function bodies included);
    ``from framework.structures.bridge import x`` imports module x if there is one, else the face."""
    graph = {}
    for path in sorted(PACKAGE_DIR.glob("*.py")):
        names = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                raise AssertionError(f"{path.name}: relative import")
            if isinstance(node, ast.ImportFrom) and node.module == PACKAGE:
                names |= {a.name if (PACKAGE_DIR / f"{a.name}.py").exists() else "__init__" for a in node.names}
                continue
            if isinstance(node, ast.ImportFrom) and node.module == "framework.structures":
                names |= {"__init__" for a in node.names if a.name == "bridge"}
                continue
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
    assert set(graph) >= MODEL_LAYERS | {"descriptor", "campaign", "effects", "vibration_tests", "choices",
                                         "reproduction"}
    order = list(graphlib.TopologicalSorter(graph).static_order())  # raises CycleError on a cycle
    # the package face imports the model layers; nothing in the package imports the face
    assert set(order[: order.index("__init__")]) >= MODEL_LAYERS
    assert all("__init__" not in deps for name, deps in graph.items() if name != "__init__"), graph
    # the descriptor is the top: it names the features, nothing imports it (the registry does)
    assert all("descriptor" not in deps for deps in graph.values())
    assert graph["descriptor"] >= {"model", "reference", "effects", "choices", "reproduction"}
    # the model layers below the factory never reach up to it, nor to the features built on the model
    features = {"descriptor", "campaign", "effects", "vibration_tests", "choices", "reproduction"}
    for low in ("geometry", "data", "parameters", "build", "modes", "fast"):
        assert not graph[low] & ({"model", "reference"} | features), (low, graph[low])
    assert not graph["model"] & features and not graph["reference"] & features
    # the reproduction rows read tables only
    assert graph["reproduction"] == set()


def test_registry_descriptor_holds_the_package_functions():
    from framework.structures.bridge import campaign, choices, effects, reproduction

    d = describe("bridge")
    assert STRUCTURES["bridge"] is d and MEASUREMENTS["bridge"] is d and CATALOGUES["bridge"] is d
    assert CAMPAIGNS["bridge"] is d
    assert d.make_model is bridge.model.make_model and d.measured is bridge.reference.measured
    assert d.effects is effects.catalogue and d.modelling_choices is choices.modelling_choices
    assert d.reproduction is reproduction.rows and d.tests() is campaign.CAMPAIGN
    assert set(d.identified) == {"bridge_vertical", "bridge_lateral"} and d.geometry is None


def test_package_exports_every_name_in_all():
    missing = [name for name in bridge.__all__ if not hasattr(bridge, name)]
    assert missing == []
    assert {"make_model", "measured", "pair_by_type", "bridge_parameters", "PARAMETER_NAMES"} <= set(bridge.__all__)

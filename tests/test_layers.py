"""The framework's packages form layers: nothing below imports from above, and no two packages
import each other, counting every import (also those inside functions) and every module path
written as a string (``"framework.x.y"`` or ``"framework.x.y:attr"``); no module imports itself
in a cycle either. The README's Architecture section lists the same layers."""

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: bottom to top; a package may import only packages of a lower (or its own) layer
LAYERS: list[tuple[str, ...]] = [
    ("core",),
    ("measured",),
    ("models",),
    ("execution",),
    ("inference",),
    ("updating",),
    ("optimizers",),
    ("damage", "diagnosis", "identification"),
    ("report",),
    ("structures",),
    ("study",),
    ("cli",),
]
LEVEL = {package: i for i, layer in enumerate(LAYERS) for package in layer}
STRING_PATH = re.compile(r"framework(\.\w+)+(:\w+)?")


def _modules() -> dict[str, Path]:
    return {".".join(p.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__"): p
            for p in (ROOT / "framework").rglob("*.py")}


def _import_graph() -> dict[str, set[str]]:
    """module -> the framework modules it names (imports, lazy imports and module-path strings)."""
    files = _modules()
    edges: dict[str, set[str]] = {m: set() for m in files}
    for module, path in files.items():
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")
                    base = ".".join(parts[: len(parts) - node.level + 1] + ([base] if base else []))
                targets = [base] + [f"{base}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Constant) and isinstance(node.value, str) \
                    and STRING_PATH.fullmatch(node.value):
                targets = [node.value.split(":")[0]]
            for target in targets:
                while target and target not in files:
                    target = target.rpartition(".")[0]
                if target and target != module and not module.startswith(target + "."):
                    edges[module].add(target)
    return edges


def _package(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def test_every_package_has_a_layer():
    packages = {_package(m) for m in _modules()} - {None}
    assert packages <= set(LEVEL), f"packages without a layer: {sorted(packages - set(LEVEL))}"


def test_nothing_below_imports_from_above():
    upward = sorted(
        f"{m} -> {t}"
        for m, targets in _import_graph().items()
        for t in targets
        if _package(m) and _package(t) and LEVEL[_package(t)] > LEVEL[_package(m)]
    )
    assert upward == [], "imports that point up a layer:\n" + "\n".join(upward)


def test_no_two_packages_import_each_other():
    edges = _import_graph()
    pairs = {(_package(m), _package(t)) for m, ts in edges.items() for t in ts}
    pairs = {(a, b) for a, b in pairs if a and b and a != b}
    mutual = sorted({tuple(sorted(p)) for p in pairs if p[::-1] in pairs})
    assert mutual == [], f"packages that import each other: {mutual}"


def test_no_import_cycles_between_modules():
    edges = _import_graph()
    files = _modules()
    # a package's __init__ that only re-exports its own modules is not a cycle with them
    edges = {m: {t for t in ts if files[t].name != "__init__.py" or not m.startswith(t + ".")}
             for m, ts in edges.items()}
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m):
        state[m] = 1
        stack.append(m)
        for n in sorted(edges[m]):
            if state.get(n) == 1:
                raise AssertionError("import cycle: " + " -> ".join(stack[stack.index(n):] + [n]))
            if n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(edges):
        if m not in state:
            visit(m)


def _module_path_strings() -> dict[str, list[str]]:
    """module -> the module paths it writes as strings (``"framework.x.y"``, ``"framework.x.y:attr"``)."""
    return {module: [node.value for node in ast.walk(ast.parse(path.read_text()))
                     if isinstance(node, ast.Constant) and isinstance(node.value, str)
                     and STRING_PATH.fullmatch(node.value)]
            for module, path in _modules().items()}


def test_kinds_optimizers_and_analyses_are_registered_as_objects_not_module_paths():
    """No module path written as a string names a run kind, an optimizer or an analysis, nor
    stands in the modules of those three registries."""
    registries = ("framework.study.kinds", "framework.optimizers", "framework.report.analyses")
    found = sorted(f"{module}: {text!r}" for module, texts in _module_path_strings().items() for text in texts
                   if module.startswith(registries) or text.startswith(registries))
    assert found == [], "module paths as strings:\n" + "\n".join(found)


def test_diagnosis_does_not_import_study():
    """A run kind's config schema lives with its kind (framework/study/kinds/), not in diagnosis."""
    up = sorted(f"{m} -> {t}" for m, ts in _import_graph().items() for t in ts
                if _package(m) == "diagnosis" and _package(t) == "study")
    assert up == []

"""One descriptor per structure (issue 24): the registry holds typed descriptors, one line each;
every feature asks a descriptor; a user's model (``module:function`` or ``module:DESCRIPTOR``)
takes the same code paths; adding a structure is its package plus one registry line."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from framework.core.errors import InputError
from framework.models.base import ModalResult
from framework.models.geometry import model_shapes
from framework.models.matrix import MatrixModel
from framework.models.shear_building import make_shear_building, storey_matrices
from framework.structures import registry
from framework.structures.descriptor import StructureDescriptor
from framework.structures.lab_frame.model import make_model as lab_frame_3dof

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "diagnosis"


# ---- the registry -----------------------------------------------------------------------------
def test_registry_is_one_typed_line_per_structure_without_module_paths():
    source = (ROOT / "framework" / "structures" / "registry.py").read_text()
    assert not re.search(r"\"framework(\.\w+)+(:\w+)?\"", source)
    assert all(isinstance(d, StructureDescriptor) for d in registry.BUILTIN)
    assert list(registry.STRUCTURES) == ["lab_frame_3dof", "lab_frame_detailed", "bridge", "beam", "four_story",
                                         "footbridge", "frame_two_bay"]
    # every structure package holds its descriptor(s), and each is registered
    packages = {p.parent.name for p in (ROOT / "framework" / "structures").glob("*/descriptor.py")}
    assert packages == {d.make_model.__module__.split(".")[2] for d in registry.BUILTIN}


def test_families_name_the_data_catalogues_and_tests_of_a_structure():
    three_dof, detailed = registry.STRUCTURES["lab_frame_3dof"], registry.STRUCTURES["lab_frame_detailed"]
    assert three_dof.family == detailed.family == "lab_frame"
    assert registry.MEASUREMENTS["lab_frame"] is three_dof and registry.CATALOGUES["lab_frame"] is detailed
    assert sorted(registry.MEASUREMENTS) == ["beam", "bridge", "footbridge", "four_story", "lab_frame"]
    assert sorted(registry.CATALOGUES) == ["beam", "bridge", "frame_two_bay", "lab_frame"]
    assert sorted(registry.CAMPAIGNS) == ["bridge", "lab_frame"]
    assert sorted(registry.IDENTIFIED_CASES) == ["bridge_lateral", "bridge_vertical", "lab_frame"]
    assert registry.campaign("lab_frame").structure == "lab_frame"
    assert three_dof.features() == ("measured", "reproduction", "tests", "identified")
    assert detailed.features() == ("measured", "effects", "geometry")
    assert registry.STRUCTURES["frame_two_bay"].features() == ("effects",)
    m = registry.builtin_measured("lab_frame", "mass_0.654kg", congruence="model")
    np.testing.assert_allclose(m.frequencies_hz, [3.54, 4.90, 7.21])
    assert registry.STRUCTURES["lab_frame_3dof"].cases == ("base", "mass_0.654kg", "mass_1.379kg")


@pytest.mark.parametrize(("call", "message"), [
    (lambda: registry.make_structure("nowhere"), "neither a built-in name nor 'module:function'"),
    (lambda: registry.builtin_measured("nowhere"), "measured.builtin='nowhere' unknown; known"),
    (lambda: registry.catalogue("four_story"), "'four_story' has no effect catalogue; known"),
    (lambda: registry.campaign("beam"), "'beam' has no simulated tests; known: \\['bridge', 'lab_frame'\\]"),
    (lambda: registry.builtin_measured("identified", "x"), "unknown case 'x'"),
    (lambda: registry.make_structure("lab_frame_3dof", stories=3), "bad options \\['stories'\\]"),
    (lambda: registry.describe("os:system"), "not a structure or data provider of a user module"),
])
def test_unknown_names_and_options_are_one_line_input_errors(call, message):
    with pytest.raises(InputError, match=message):
        call()


# ---- geometry: hooks, never class names or DOF labels -------------------------------------------
class _Plain:
    """A model that is neither the 3-DOF lab frame nor a shear building, with their DOF labels."""

    def __init__(self, dofs, inner):
        self.dofs, self.inner = dofs, inner

    parameters = property(lambda self: self.inner.parameters)

    def modal(self, theta):
        r = self.inner.modal(theta)
        return ModalResult(r.frequencies_hz, r.shapes, self.dofs)


def test_geometry_comes_from_the_model_type_or_a_hook_not_from_dof_labels():
    lab = lab_frame_3dof()
    assert model_shapes(lab, {}).coords.shape == (8, 3)  # ThreeDofFrame.geometry: the rigid slab
    assert not model_shapes(_Plain(("y", "x", "torsion"), lab), {}).has_geometry
    building = make_shear_building([1.0] * 3, [10.0] * 3, measured_floors=(1, 3))
    shapes = model_shapes(building, {})
    assert shapes.length_unit == "storey" and shapes.points == ["floor 1", "floor 3"]
    np.testing.assert_allclose(shapes.node_shapes[[1, 3], 0, :], shapes.dof_shapes)
    plain = MatrixModel([10.0 * E for E in storey_matrices(3)], np.eye(3), building.parameters,
                        {"floor1": 0, "floor3": 2}, n_modes=3, solver="condensation")
    assert not model_shapes(plain, {}).has_geometry  # the same DOF labels, no geometry method
    # a descriptor's hook wins over the model's own method
    calls = []

    def hook(model, theta, shapes):
        calls.append(model)
        return None

    assert not model_shapes(lab, {}, geometry=hook).has_geometry and calls == [lab]
    # the generic reader's code (docstrings aside) names no structure, class or DOF label
    tree = ast.parse((ROOT / "framework" / "models" / "geometry.py").read_text())
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
            body.pop(0)
    assert not re.search(r"lab_frame|floor|Beam|Bridge|ThreeDof|Shear|torsion|structures\.", ast.unparse(tree))


# ---- a user's model: the same descriptor type, the same code paths -----------------------------
def test_user_reference_is_described_by_the_same_type(monkeypatch):
    pytest.importorskip("openseespy.opensees")
    from framework.diagnosis.auto import with_candidates
    from framework.models.opensees import OpenSeesModel
    from framework.study.structure_hooks import geometry_of

    monkeypatch.syspath_prepend(str(EXAMPLE))
    d = registry.describe("my_frame:model")
    assert isinstance(d, StructureDescriptor) and d.name == "my_frame:model" and d.features() == ("effects",)
    model = registry.make_structure("my_frame:model")
    assert isinstance(model, OpenSeesModel)
    assert registry.catalogue("my_frame:model").effects == {}
    assert with_candidates(registry.catalogue("my_frame:model"), "auto").generated  # candidates: auto
    assert set(registry.catalogue("my_frame:catalogue").effects) == {"heavy_equipment"}
    assert isinstance(registry.make_structure("my_frame:catalogue"), OpenSeesModel)  # its model under test
    shapes = model_shapes(model, {}, "my_frame:model", geometry_of("my_frame:model"))  # the shape stage's path
    assert shapes.coords.shape == (8, 3) and shapes.points == ["node11", "node21", "node15", "node25"]


def test_user_descriptor_gets_every_feature_through_a_config(tmp_path, monkeypatch):
    pytest.importorskip("openseespy.opensees")
    import yaml

    from framework.study.config import validate
    from framework.study.runner import run_study

    monkeypatch.syspath_prepend(str(EXAMPLE))
    data = yaml.safe_load((EXAMPLE / "update.yaml").read_text())
    data.update(output=str(tmp_path / "my_frame"), budget={"max_evaluations": 60})
    run_study(validate(data), progress=False, figures=False, shapes=True)
    out = tmp_path / "my_frame"
    choices = pd.read_csv(out / "choices.csv")
    assert list(choices["item"]) == ["members", "mass", "sensors"]
    geometry = pd.read_csv(out / "geometry.csv")
    assert (geometry["kind"] == "node").sum() == 8 and (geometry["kind"] == "element").sum() == 8
    assert set(pd.read_csv(out / "mode_shapes.csv")["state"]) == {"initial", "updated"}
    from my_frame_structure import MY_FRAME

    row = MY_FRAME.reproduction(tmp_path)[0]
    assert row["item"] == "column stiffness ratio" and row["ours"] != "" and row["verdict"]


@pytest.fixture
def my_frame_registered(monkeypatch):
    """The one line that makes my_frame a built-in: its descriptor appended to BUILTIN."""
    monkeypatch.syspath_prepend(str(EXAMPLE))
    from my_frame_structure import MY_FRAME

    monkeypatch.setattr(registry, "BUILTIN", (*registry.BUILTIN, MY_FRAME))
    registry._index()
    yield MY_FRAME
    monkeypatch.undo()
    registry._index()


def test_a_registered_structure_has_every_feature_by_its_name(my_frame_registered):
    pytest.importorskip("openseespy.opensees")
    from framework.study.config import validate
    from framework.study.plan import plan

    d = my_frame_registered
    assert d.features() == ("measured", "effects", "reproduction", "tests", "modelling_choices", "identified")
    assert registry.make_structure("my_frame").name == "my_frame"
    assert registry.builtin_measured("my_frame").dofs == ("x1", "x2", "y1", "y2")
    assert "heavy_equipment" in registry.catalogue("my_frame").effects
    assert registry.reproduction_providers()[-1] is d.reproduction
    assert registry.modelling_choices("my_frame") is d.modelling_choices
    # its simulated tests through the identification kind's config and plan
    cfg = validate({"study": "t", "kind": "identification", "output": "unused",
                    "tests": {"sweep": {"structure": "my_frame", "test": "sweep", "methods": ["n4sid"],
                                        "subspace": {"orders": {"min": 8, "max": 30, "step": 2}, "block_rows": 20,
                                                     "decimate": 4, "mac_min": 0.9, "band_hz": [1.0, 25.0]}}}})
    task = plan(cfg)[0]["task"]
    assert (task["duration_s"], task["f_range_hz"]) == (60.0, [1.0, 25.0])
    tests = registry.campaign("my_frame")
    rec = tests.simulate("sweep", 1, 20.0, 200.0, 0.0, 0.0)
    assert rec.output_labels == ("x1", "x2", "y1", "y2") and rec.input_labels == ("force",)
    truth = tests.true_modes(("x2", "y2"), (1.0, 25.0))
    assert truth.f_hz.size == 4 and truth.shapes.shape == (2, 4)

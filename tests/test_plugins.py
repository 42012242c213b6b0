"""Typed plugins (issue 24): optimizers, analyses and run kinds are registered as typed objects, and
an optimizer's settings are validated once, when the config is read, and reach the optimizer as
that object; a run's identity stays plain data (the run ids of stored results do not change)."""

import dataclasses
import json
import re
from typing import ClassVar

import pytest
import yaml
from pydantic import model_validator

from framework.core.errors import InputError
from framework.optimizers import OPTIMIZERS, Budget, run_optimizer
from framework.optimizers import pso as pso_module
from framework.optimizers.base import Optimizer, Settings
from framework.report.analyses import ANALYSES, Analysis
from framework.study.config import load, validate
from framework.study.kinds import KINDS, get_kind
from framework.study.kinds.base import Kind
from framework.study.plan import canonical, plan
from framework.study.runner import run_study

SMALL = {
    "study": "plugins",
    "structure": {"name": "lab_frame_3dof"},
    "measured": {"builtin": "lab_frame", "case": "base"},
    "budget": {"max_evaluations": 48, "stall_iterations": 50},
    "algorithms": {"pso": {"algorithm": "pso", "settings": {"swarm_size": 8}}},
    "runs": 3,
    "execution": {"progress": False},
}
HYBRID = {"algorithm": "hybrid", "settings": {"global": {"algorithm": "pso", "settings": {"swarm_size": 8},
                                                         "max_evaluations": 40}, "local": {"settings": {"ftol": 1e-8}}}}


def test_registries_hold_typed_objects():
    assert OPTIMIZERS and all(isinstance(o, Optimizer) and o.name == n and issubclass(o.settings, Settings)
                              and callable(o.run) for n, o in OPTIMIZERS.items())
    assert ANALYSES and all(isinstance(a, Analysis) and a.name == n and callable(a.tables) and callable(a.figures)
                            for n, a in ANALYSES.items())
    assert all(isinstance(k, Kind) and k.name == n for n, k in KINDS.items())
    assert set(OPTIMIZERS) == {"pso", "ga", "annealing", "sm", "snt", "nsga2", "hybrid", "multistart"}
    assert ANALYSES["damage_summary"].check_options is not None


class _Counted(pso_module.PSOSettings):
    """PSO settings that count how often they are validated (every construction validates)."""

    made: ClassVar[int] = 0

    @model_validator(mode="after")
    def _count(self):
        type(self).made += 1
        return self


def test_optimizer_settings_are_validated_once_and_reach_the_optimizer_as_that_object(tmp_path, monkeypatch):
    """Once per config, not per plan, run or adapter: three runs (plus the planning for the mode-shape
    tables) construct the settings object once, and every run's optimizer gets that very object."""
    seen = []
    counted = dataclasses.replace(OPTIMIZERS["pso"], settings=_Counted)

    def run(evaluator, seed, budget, settings):
        seen.append(settings)
        return pso_module.run(evaluator, seed, budget, settings)

    monkeypatch.setitem(OPTIMIZERS, "pso", dataclasses.replace(counted, run=run))
    _Counted.made = 0
    path = tmp_path / "study.yaml"
    path.write_text(yaml.safe_dump({**SMALL, "output": str(tmp_path / "out")}))
    cfg = load(path)
    assert _Counted.made == 1
    settings = cfg.algorithms["pso"].settings
    assert isinstance(settings, _Counted) and settings.swarm_size == 8 and settings.factor == 0.75
    tables = run_study(cfg)
    assert len(tables["runs"]) == 3 and set(tables["runs"]["swarm_size"]) == {8}
    assert _Counted.made == 1 and len(seen) == 3 and all(s is settings for s in seen)
    # the settings are written back as given (config.yaml, variants), not with every default
    assert yaml.safe_load((tmp_path / "out" / "config.yaml").read_text())["algorithms"]["pso"]["settings"] == {
        "swarm_size": 8}


def test_a_run_identity_is_plain_data_with_the_settings_as_before():
    """The hashed identity holds the settings as the JSON of the validated object, with every
    default: the same data as the dict the task held before the settings were typed."""
    cfg = validate({**SMALL, "algorithms": {"pso": SMALL["algorithms"]["pso"], "h": HYBRID,
                                            "snt": {"algorithm": "snt", "settings": {"pso": {"swarm_size": 8}}}}})
    kind = get_kind("updating")
    for spec in plan(cfg):
        ident = kind.identity_of(spec["task"])
        assert json.loads(json.dumps(ident)) == ident  # plain JSON data, nothing hashed by str()
        assert canonical(ident) == json.dumps(ident, sort_keys=True, separators=(",", ":"))
        settings = ident["settings"]
        if spec["label"] == "pso":
            assert settings == pso_module.PSOSettings(swarm_size=8).model_dump(mode="json")
        elif spec["label"] == "h":
            assert settings["global"]["settings"] == pso_module.PSOSettings(swarm_size=8).model_dump(mode="json")
            assert "x0" not in settings["local"]["settings"] and settings["local"]["settings"]["ftol"] == 1e-8
        else:  # SNT's PSO settings as given (as the dict they were)
            assert settings["pso"] == {"swarm_size": 8} and settings["n_minima"] == 4


@pytest.mark.parametrize("algorithm, message, field", [
    ({"algorithm": "pso", "settings": {"swarm_size": 1}},
     r"algorithms\.a: settings\.swarm_size: Input should be greater than or equal to 2 \(value 1\) "
     r"for algorithm 'pso'", "swarm_size"),
    ({"algorithm": "hybrid", "settings": {"global": {"algorithm": "pso", "settings": {"swarm_size": 1},
                                                     "max_evaluations": 40}}},
     r"algorithms\.a: settings\.global\.settings \(pso\)\.swarm_size: Input should be greater than or equal to 2 "
     r"\(value 1\) for algorithm 'hybrid'", "swarm_size"),
    ({"algorithm": "snt", "settings": {"pso": {"swarm_sise": 8}}},  # used to fail only when the run started
     r"algorithms\.a: settings\.pso\.swarm_sise: unknown key \(value 8\) for algorithm 'snt'", "swarm_sise"),
    ({"algorithm": "multistart", "settings": {"local": {"x0": [0.5]}}},
     r"algorithms\.a: settings\.local: \['x0'\] are set by the multi-start", "x0"),
])
def test_a_bad_setting_is_one_message_naming_the_field_once(algorithm, message, field):
    with pytest.raises(InputError) as err:
        validate({**SMALL, "algorithms": {"a": algorithm}}, source="s.yaml")
    text = str(err.value)
    assert re.match(rf"s\.yaml: {message}", text) and len(text.splitlines()) == 1, text
    assert text.count(field) == 1, text


def test_settings_given_in_code_are_validated_where_given():
    """Code calls ``run_optimizer`` with keywords (validated there, once per call) or with the
    settings object (used as it is); not both."""
    from framework.structures.registry import builtin_measured, make_structure
    from framework.updating.problem import UpdatingProblem

    problem = UpdatingProblem(make_structure("lab_frame_3dof"), builtin_measured("lab_frame", "base"))
    budget = Budget(max_evaluations=24)
    by_keywords = run_optimizer("pso", problem, 1, budget, swarm_size=8)
    by_object = run_optimizer("pso", problem, 1, budget, settings=pso_module.PSOSettings(swarm_size=8))
    assert by_keywords.objective == by_object.objective and by_object.extra["swarm_size"] == 8
    with pytest.raises(TypeError, match="either as settings= or as keywords"):
        run_optimizer("pso", problem, 1, budget, settings=pso_module.PSOSettings(), swarm_size=8)
    with pytest.raises(InputError, match=r"unknown algorithm 'psoo'; known: \['annealing'"):
        run_optimizer("psoo", problem, 1, budget)

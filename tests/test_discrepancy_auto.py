"""Issue 17: candidates generated from the model, screening, verdicts, noise assumption,
Laplace evidence, and a user's module run through the ``gomu`` command."""

from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

pytest.importorskip("openseespy.opensees")

from framework.core.errors import InputError  # noqa: E402
from framework.diagnosis.auto import Block, _condensed_end, with_candidates  # noqa: E402
from framework.diagnosis.generate import NOISE_LEVELS, HiddenCase, generate  # noqa: E402
from framework.diagnosis.outcomes import agreement, cases, targets  # noqa: E402
from framework.diagnosis.tables import diagnosis_rows  # noqa: E402
from framework.diagnosis.workflow import DiagnoseSettings, diagnose  # noqa: E402
from framework.inference.evidence import laplace_log_evidence_chi2  # noqa: E402
from framework.structures.frame_two_bay import effects as frame_two_bay  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "diagnosis"
FAST = {"n_starts": 1, "max_evaluations": 50, "screen_keep": 2, "screen_points": 0, "refine_starts": 1,
        "rank_always": False}  # fmt: skip


@pytest.fixture(scope="module")
def frame():
    return with_candidates(frame_two_bay.catalogue(), "auto")


def test_generated_candidates_are_named_located_and_null_at_their_initial_value(frame):
    effects = frame.candidate_effects()
    assert set(effects) == {"support_rotational_flexibility", "support_translational_flexibility",
                            "semi_rigid_connections", "nodal_mass_change", "level_mass_change",
                            "member_stiffness_change", "added_brace"}  # fmt: skip
    assert "two_storey_brace" in frame.effects and "two_storey_brace" not in effects  # hand-written, not a candidate
    # locations from the model: 3 supports + all, 9 columns + 6x2 beam elements + groups, 12 bay diagonals
    assert effects["support_rotational_flexibility"].variants == ("node1", "node11", "node21", "all")
    assert {"ele1", "ele21", "columns_storey1", "beams_level3", "columns", "beams"} <= set(
        effects["member_stiffness_change"].variants)
    assert len(effects["added_brace"].variants) == 12 and "n1-n111" in effects["added_brace"].variants
    assert effects["level_mass_change"].variants == ("level1", "level2", "level3")
    base = frame.model({}).modal({}).frequencies_hz
    for name, eff in effects.items():
        p = eff.parameters[0]
        f = frame.model({name: eff.variants[0]}).modal({p.name: p.initial}).frequencies_hz
        assert np.array_equal(f, base), name  # the null value is "no effect", exactly


def test_generated_effects_act_with_their_physical_sign(frame):
    base = frame.model({}).modal({}).frequencies_hz
    # all columns 10 % stiffer = the base parameter column_stiffness_ratio 1.1 (K linear in E)
    f_cols = frame.model({"member_stiffness_change": "columns"}).modal({"stiffness_change": 0.1}).frequencies_hz
    f_ratio = frame.model({}).modal({"column_stiffness_ratio": 1.1}).frequencies_hz
    assert np.allclose(f_cols, f_ratio, rtol=1e-9)
    f = frame.model({"level_mass_change": "level2"}).modal({"level_mass_ratio": 0.3}).frequencies_hz
    assert np.all(f[:2] < base[:2])
    f = frame.model({"added_brace": "n1-n111"}).modal({"brace_stiffness_ratio": 1.0}).frequencies_hz
    assert f[0] > 1.05 * base[0]
    for name in ("support_rotational_flexibility", "semi_rigid_connections"):
        p = frame.effect(name).parameters[0].name
        f = frame.model({name: "all"}).modal({p: 1.0}).frequencies_hz
        assert f[0] < 0.97 * base[0], name


def test_semi_rigid_condensation_spans_rigid_to_pinned():
    # a 2D beam element (EI = L = 1) between nodes 1 and 2: [v1, t1, v2, t2]
    k = np.array([[12, 6, -12, 6], [6, 4, -6, 2], [-12, -6, 12, -6], [6, 2, -6, 4]], float)
    block = Block(((1, 2), (1, 3), (2, 2), (2, 3)), k)
    assert np.abs(_condensed_end(block, 2, (3,), 1e-9).matrix).max() < 1e-6
    pinned = k + _condensed_end(block, 2, (3,), 1e9).matrix
    # a beam pinned at node 2 (propped cantilever): 3EI/L^3 translation, no moment at node 2
    assert pinned[3, 3] == pytest.approx(0.0, abs=1e-6)
    assert pinned[0, 0] == pytest.approx(3.0, rel=1e-6)
    assert np.linalg.eigvalsh(_condensed_end(block, 2, (3,), 1.0).matrix).max() < 1e-9  # softening only


def test_screened_auto_diagnosis_names_effect_and_location_with_every_round_in_the_headline(frame):
    data = generate(frame, HiddenCase({"member_stiffness_change": "ele1"}, seed=1, noise=NOISE_LEVELS["low"]))
    d = diagnose(frame, data, DiagnoseSettings(**(dict(frame.settings) | FAST)))
    assert d.named_effects == ["member_stiffness_change"] and d.after.active["member_stiffness_change"] == "ele1"
    assert d.conclusion.startswith("explained by member_stiffness_change[ele1]") and not d.partial
    assert "round 1:" in d.headline and "round 2:" in d.headline and "consistent with the noise" in d.headline
    rows = diagnosis_rows(d)
    s = rows["summary"][0]
    assert s["named_location"] == "ele1" and s["hidden_location"] == "ele1" and s["noise_source"] == "data"
    screen = pd.DataFrame(rows["screen"])
    member = screen[screen["effect"] == "member_stiffness_change"]
    assert member["calibrated"].sum() == 2 and len(member) == 29
    assert bool(member.loc[member["effect_variant"] == "ele1", "calibrated"].iloc[0])
    cand = pd.DataFrame(rows["candidates"])
    assert {"log_evidence", "two_ln_bayes_vs_none", "flags", "fitted_effect"} <= set(cand)
    fitted = cand.loc[cand["effect"] == "member_stiffness_change", "fitted_effect"].iloc[0]
    truth = data.meta["truth_parameters"]["stiffness_change"]
    assert json.loads(fitted)["stiffness_change"] == pytest.approx(truth, abs=0.2)


def test_out_of_candidate_effect_is_partial_never_explained():
    from framework.structures.registry import catalogue as get_catalogue

    beam = with_candidates(get_catalogue("beam"), ["support_rotational_restraint", "localized_stiffness_loss"])
    data = generate(beam, HiddenCase({"midspan_mass": None}, {"midspan_mass_ratio": 0.3}, seed=1,
                                     noise=NOISE_LEVELS["high"]))  # fmt: skip
    d = diagnose(beam, data, DiagnoseSettings(n_starts=1, max_evaluations=100))
    assert not d.conclusion.startswith("explained")
    if d.named_effects:
        assert d.partial and d.conclusion.startswith("partial:")
        assert "may lie outside the candidates" in d.conclusion and "remaining discrepancy is significant" in d.conclusion


def test_data_without_stds_run_under_a_stated_assumption(frame):
    data = generate(frame, HiddenCase({}, seed=2, noise=NOISE_LEVELS["low"], with_stds=False))
    assert data.frequency_std_hz is None and data.shape_std is None
    d = diagnose(frame, data, DiagnoseSettings(**(dict(frame.settings) | FAST)))
    s = d.summary()
    assert s["noise_source"].startswith("assumed: frequency std = 1.00% of f")
    assert s["noise_warning"].startswith("WARNING: the data give no standard deviations")
    assert d.conclusion == "no significant discrepancy"


def test_laplace_evidence_of_a_linear_gaussian_model_is_exact():
    # r = (a theta - y) / s, one parameter, uniform prior on [-10, 10]: Z = int L p dtheta
    a, y, s = np.array([1.0, 2.0, 0.5]), np.array([0.9, 2.2, 0.4]), 0.1
    theta_hat = float(a @ y / (a @ a))
    chi2 = float(np.sum(((a * theta_hat - y) / s) ** 2))
    grid = np.linspace(theta_hat - 1, theta_hat + 1, 200001)
    like = np.exp(-0.5 * np.sum(((a[:, None] * grid - y[:, None]) / s) ** 2, axis=0))
    exact = math.log(np.trapezoid(like, grid) / 20.0)
    jac_x = (a / s)[:, None] * 20.0  # dr/dx with theta = -10 + 20 x
    assert laplace_log_evidence_chi2(chi2, jac_x, np.array([20.0])) == pytest.approx(exact, abs=1e-6)
    assert laplace_log_evidence_chi2(chi2, jac_x, np.array([20.0]), n_variants=4) == pytest.approx(exact - math.log(4))


def test_targets_and_agreement_tables():
    rows = [
        {"hidden_effect": "a", "named_effect": "a", "hidden_variant": "x", "named_variant": "x", "partial": False,
         "magnitude": 1.0, "data_stds": True, "hidden_in_candidates": True},
        {"hidden_effect": "a", "named_effect": "b", "hidden_variant": "x", "named_variant": "", "partial": True,
         "magnitude": 1.0, "data_stds": True, "hidden_in_candidates": True},
        {"hidden_effect": "none", "named_effect": "none", "hidden_variant": "", "named_variant": "", "partial": False,
         "magnitude": 1.0, "data_stds": False, "hidden_in_candidates": True},
        {"hidden_effect": "c", "named_effect": "a", "hidden_variant": "", "named_variant": "x", "partial": True,
         "magnitude": 1.0, "data_stds": True, "hidden_in_candidates": False},
    ]  # fmt: skip
    summary = pd.DataFrame([r | {"data_source": "generated", "status": "ok", "case": f"c{i}", "seed": i,
                                 "structure": "s", "noise": "low", "run_id": str(i), "bic_decisive_round1": True,
                                 "bic_best_round1": "a", "bic_best_variant_round1": "x",
                                 "evidence_best_round1": "a" if i else "b", "evidence_best_variant_round1": "x",
                                 "evidence_named_round1": True}
                            for i, r in enumerate(rows)])  # fmt: skip
    t = targets(cases(summary)).set_index("target")
    assert t.loc["correct effect and location at full magnitude", "rate"] == 0.5
    assert t.loc["wrong names (cases with a hidden effect)", "count"] == 2
    assert t.loc["false discoveries, null cases without stds", "n_cases"] == 1
    assert t.loc["out-of-candidate cases named as a full explanation", "rate"] == 0.0
    assert t.loc["out-of-candidate cases named as partial", "rate"] == 1.0
    ag = agreement(summary)
    assert ag["same_effect"].tolist() == [False, True, True, True]


def _gomu(args: list[str], cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT), MPLBACKEND="Agg")  # the user's folder is not on PYTHONPATH
    return subprocess.run([str(Path(sys.executable).with_name("gomu")), *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=300)  # fmt: skip


@pytest.mark.skipif(not Path(sys.executable).with_name("gomu").exists(), reason="gomu command not installed")
def test_user_module_in_a_temporary_folder_through_the_gomu_command(tmp_path):
    for name in ("my_frame.py", "my_modes.yaml", "auto.yaml"):
        shutil.copy(EXAMPLE / name, tmp_path / name)
    # from another folder: valid, and the user's module is not imported without --build
    out = _gomu(["validate", str(tmp_path / "auto.yaml")], tmp_path.parent)
    assert out.returncode == 0 and "code named in the config was not imported" in out.stdout, out.stderr
    out = _gomu(["validate", "auto.yaml", "--build"], tmp_path)
    assert out.returncode == 0 and "OK - kind 'diagnose', 1 runs" in out.stdout, out.stderr
    out = _gomu(["diagnose", "auto.yaml", "--set", "settings.max_evaluations=40"], tmp_path)
    assert out.returncode == 0, out.stderr
    assert "explained by added_brace[n1-n12]" in out.stdout and "named effect(s): added_brace at n1-n12" in out.stdout
    assert (tmp_path / "results" / "my_frame_auto" / "candidates.csv").exists()
    # a build that raises: one line naming the module and the error, exit 2, no traceback
    (tmp_path / "broken.py").write_text(
        "from my_frame import PARAMETERS, SENSORS\nfrom framework.models.opensees import OpenSeesModel\n"
        "from framework.core.parameters import ParameterSet\n\n"
        "def build(values):\n    raise ValueError('section table missing')\n\n"
        "def model():\n    return OpenSeesModel(build, ParameterSet(PARAMETERS), SENSORS, n_modes=4)\n")
    (tmp_path / "broken.yaml").write_text((tmp_path / "auto.yaml").read_text().replace("my_frame:model",
                                                                                        "broken:model"))
    out = _gomu(["diagnose", "broken.yaml"], tmp_path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    lines = [ln for ln in out.stderr.splitlines() if ln.startswith("gomu: error")]
    assert len(lines) == 1 and "broken:model" in lines[0] and "section table missing" in lines[0], out.stderr


def test_unknown_candidate_is_one_clear_error(frame):
    with pytest.raises(InputError, match=r"candidates \['brace'\] unknown"):
        with_candidates(frame, ["auto", "brace"])

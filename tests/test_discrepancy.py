"""Discrepancy workflow: statistics, scoring, generator, and hidden-effect recovery (beam, lab frame)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from framework.core.errors import InputError
from framework.diagnosis.calibrate import calibrate, gaussian_spec
from framework.diagnosis.generate import NOISE_LEVELS, HiddenCase, Noise, generate
from framework.diagnosis.score import bic, rank
from framework.diagnosis.tables import diagnosis_tables
from framework.diagnosis.workflow import DiagnoseSettings, diagnose
from framework.inference.noise import data_noise, with_stds
from framework.measured.modes import MeasuredModes
from framework.models.base import ModalResult
from framework.structures.beam.effects import catalogue as beam_catalogue
from framework.updating.formulations import gaussian

FAST = DiagnoseSettings(n_starts=2, max_evaluations=200)


def _modes(f, phi, dofs=("a", "b", "c")):
    return ModalResult(np.asarray(f, float), np.asarray(phi, float), dofs)


def test_residuals_zero_for_exact_model_and_weighted_mac_identity():
    phi = np.array([[1.0, 0.5], [0.5, -1.0], [0.2, 0.3]])
    measured = MeasuredModes(
        np.array([2.0, 5.0]),
        ("a", "b", "c"),
        phi.copy(),
        frequency_std_hz=np.array([0.01, 0.02]),
        shape_std=np.full((3, 2), 0.01),
    )
    spec = gaussian_spec()
    r, corr = gaussian.gaussian_residuals(_modes([2.0, 5.0], 3 * phi), measured, spec)
    assert r.shape == (2 + 6,)
    assert np.allclose(r, 0.0, atol=1e-12)
    # frequency residual is (f_a - f_e) / sigma; shape chi2 = ||e||^2 (1 - MAC) / s^2 for equal s
    a = phi.copy()
    a[2, 0] += 0.1
    r, corr = gaussian.gaussian_residuals(_modes([2.02, 5.0], a), measured, spec)
    assert r[0] == pytest.approx(2.0)
    chi_s = np.sum(r[2:5] ** 2)
    e = phi[:, 0]
    assert chi_s == pytest.approx(np.sum(e**2) * (1 - corr.mac[0]) / 0.01**2, rel=1e-9)


def test_unmatched_mode_costs_at_least_a_pair_at_the_matching_limit():
    phi = np.eye(3)[:, :2]
    measured = MeasuredModes(np.array([2.0, 5.0]), ("a", "b", "c"), phi)  # no stds: 1 % and 5 % assumed
    spec = gaussian_spec(mac_threshold=0.5)
    # model has only the first shape (twice): the second measured mode is unmatched
    r, corr = gaussian.gaussian_residuals(
        _modes([2.0, 6.0], np.array([[1.0, 1.0], [0, 0.01], [0, 0]])), measured, spec
    )
    assert corr.matched.tolist() == [True, False]
    expected = (0.1 * 5.0 / (0.01 * 5.0)) ** 2 + 0.5 * 1.0 / 0.05**2
    assert r[1] ** 2 == pytest.approx(expected)
    assert gaussian.n_data(measured, spec) == 2 + 2 * 2


def test_default_noise_model_and_bad_std():
    m = MeasuredModes(np.array([4.0]), ("a", "b"), np.array([[2.0], [1.0]]))
    noise = data_noise(m)
    assert (noise.frequency_source, noise.shape_source) == ("assumed", "assumed")
    assert noise.assumed == "frequency std 1 % of f; shape std 5 % of the peak"
    w = with_stds(m, noise)
    assert w.frequency_std_hz[0] == pytest.approx(0.04)  # the stated assumption: 1 % of f
    assert np.allclose(w.shape_std, 0.10)  # 5 % of the largest component
    assert data_noise(w).assumed == "" and data_noise(w).frequency_source == "data"
    with pytest.raises(InputError, match="noise.frequency_std_rel must be a number > 0"):
        data_noise(m, frequency_std_rel=0.0)
    zero = MeasuredModes(np.array([4.0]), ("a", "b"), np.array([[2.0], [1.0]]), frequency_std_hz=[0.0])
    with pytest.raises(InputError, match="frequency_std_hz of mode 1 is 0"):
        data_noise(zero)


def test_bic_and_decisive_rule():
    assert bic(10.0, 2, 50, 10) == pytest.approx(10 + 2 * math.log(50) + 2 * math.log(10))

    class F:  # minimal stand-in for Fit
        def __init__(self, chi2, k, active=None):
            self.chi2, self.k, self.active, self.n_data, self.n_unmatched = chi2, k, active or {}, 50, 0

    cur = F(200.0, 1)
    r = rank(cur, {"a": (F(40.0, 2, {"a": ""}), 1), "b": (F(45.0, 2, {"b": ""}), 1)})
    assert r.named is None and "cannot tell them apart" in r.reason  # a and b within 10
    r = rank(cur, {"a": (F(40.0, 2, {"a": ""}), 1), "b": (F(90.0, 2, {"b": ""}), 1)})
    assert r.named == "a"
    assert r.table.iloc[0]["delta_bic_vs_none"] == pytest.approx(160 - math.log(50))
    r = rank(cur, {"a": (F(192.0, 2, {"a": ""}), 1)})
    assert r.named is None and "gains only" in r.reason


def test_generator_is_reproducible_and_records_truth():
    cat = beam_catalogue()
    case = HiddenCase({"localized_stiffness_loss": None}, seed=7, noise=Noise(0.002, 0.01))
    a, b = generate(cat, case), generate(cat, case)
    assert np.array_equal(a.frequencies_hz, b.frequencies_hz) and np.array_equal(a.shapes, b.shapes)
    assert a.meta["hidden"]["localized_stiffness_loss"] in [f"e{i:02d}" for i in range(2, 10)]
    assert 0.3 <= a.meta["truth_parameters"]["stiffness_loss"] <= 0.5
    assert np.allclose(a.frequency_std_hz, 0.002 * a.frequencies_hz)
    c = generate(cat, HiddenCase({"localized_stiffness_loss": None}, seed=8))
    assert not np.array_equal(a.frequencies_hz, c.frequencies_hz)
    with pytest.raises(InputError, match="unknown parameters"):
        generate(cat, HiddenCase({}, values={"nope": 1.0}))
    with pytest.raises(InputError, match="effect 'bogus' unknown"):
        generate(cat, HiddenCase({"bogus": None}))


def test_calibration_recovers_truth_on_noise_free_beam():
    cat = beam_catalogue()
    active = {"support_rotational_restraint": ""}
    model = cat.model(active)
    truth = {"EI_ratio": 0.93, "support_fixity": 0.4}
    res = model.modal(truth)
    exact = MeasuredModes(
        res.frequencies_hz[:5], res.dofs, res.shapes[:, :5], frequency_std_hz=1e-3 * res.frequencies_hz[:5]
    )
    measured = with_stds(exact, data_noise(exact, shape_std_rel=0.01))
    fit = calibrate(model, measured, n_starts=2, max_evaluations=300)
    assert fit.chi2 < 1e-6
    assert dict(zip(fit.parameters.names, fit.theta)) == pytest.approx(truth, rel=1e-4)


@pytest.mark.parametrize("noise", ["low", "high"])
@pytest.mark.parametrize("seed", [1, 2])
def test_beam_null_case_names_nothing(noise, seed):
    d = diagnose(
        beam_catalogue(), generate(beam_catalogue(), HiddenCase({}, seed=seed, noise=NOISE_LEVELS[noise])), FAST
    )
    assert d.named_effects == []
    assert d.rounds[0].detection.p_value > 0.01
    assert "no significant discrepancy" in d.conclusion


@pytest.mark.parametrize(
    ("effect", "seed"),
    [("support_rotational_restraint", 3), ("localized_stiffness_loss", 4), ("midspan_mass", 5)],
)
def test_beam_hidden_effect_is_named_and_gap_shrinks(effect, seed):
    cat = beam_catalogue()
    m = generate(cat, HiddenCase({effect: None}, seed=seed, noise=NOISE_LEVELS["high"]))
    d = diagnose(cat, m, FAST)
    assert d.named_effects == [effect]
    if effect == "localized_stiffness_loss":
        assert d.after.active[effect] == m.meta["hidden"][effect]  # the right element
    s = d.summary()
    assert s["p_before"] < 1e-6 and s["p_after"] > 0.01
    assert s["max_freq_error_pct_after"] < s["max_freq_error_pct_before"] / 3
    tables = diagnosis_tables(d)
    assert set(tables["modes"]["stage"]) == {"before", "after"}
    assert tables["candidates"].query("named")["effect"].tolist() == [effect]
    # every candidate's fitted parameters are reported, the named one's value next to its truth
    params = tables["parameters"]
    assert set(params.query("round == 1")["candidate"]) == {"none", *cat.effects}
    named = params.query("round == 1 and named and effect == @effect").iloc[0]
    truth = m.meta["truth_parameters"][named["parameter"]]
    assert named["truth"] == truth and named["value"] == pytest.approx(truth, rel=0.3)
    assert params.query("final")["model"].nunique() == 1


def test_lab_frame_semi_rigid_joints_named_and_null_case():
    from framework.structures.lab_frame.effects import catalogue as lab_catalogue

    cat = lab_catalogue()
    m = generate(cat, HiddenCase({"semi_rigid_joints": None}, seed=1, noise=NOISE_LEVELS["high"]))
    d = diagnose(cat, m, DiagnoseSettings(n_starts=2, max_evaluations=150, rank_always=False))
    assert d.named_effects == ["semi_rigid_joints"]
    s = d.summary()
    assert s["max_freq_error_pct_before"] > 10 and s["max_freq_error_pct_after"] < 1.5
    fitted = dict(zip(d.after.parameters.names, d.after.theta))
    truth = m.meta["truth_parameters"]
    assert fitted["flex_r2"] == pytest.approx(truth["flex_r2"], rel=0.15)
    null = generate(cat, HiddenCase({}, seed=2, noise=NOISE_LEVELS["low"]))
    d0 = diagnose(cat, null, DiagnoseSettings(n_starts=1, max_evaluations=150, rank_always=False))
    assert d0.named_effects == [] and not d0.rounds[0].detection.significant


def test_holdout_modes_scores_candidates_by_prediction():
    cat = beam_catalogue()
    m = generate(cat, HiddenCase({"localized_stiffness_loss": None}, seed=3, noise=NOISE_LEVELS["high"]))
    d = diagnose(cat, m, DiagnoseSettings(n_starts=2, max_evaluations=200, holdout_modes=True, max_rounds=1))
    table = d.rounds[0].ranking.table.set_index("effect")
    assert d.named_effects == ["localized_stiffness_loss"]
    assert table.loc["localized_stiffness_loss", "loo_chi2"] < table.loc["none", "loo_chi2"] / 2
    assert table.loc["localized_stiffness_loss", "delta_loo_vs_none"] > 0

"""Figure helpers that decide what a reader sees: outliers off the scale, mode ticks, Delta BIC axis."""

import numpy as np
import pandas as pd

from framework.report.figures.updating import frequencies, mode_ticks, robust_limits


def test_one_outlier_does_not_set_the_scale_and_is_counted():
    values = np.r_[np.linspace(-1.0, 1.0, 40), 250.0]
    lo, hi, n_off = robust_limits(values)
    assert -1.5 < lo < -0.5 and 0.5 < hi < 1.5 and n_off == 1
    assert robust_limits(np.linspace(-1.0, 1.0, 40)) is None  # no outlier: the full range


def test_mode_ticks_name_the_mode_and_its_measured_frequency():
    df = pd.DataFrame({"mode": [1, 2, 1], "mode_label": ["1st y", "1st x", "1st y"],
                       "f_measured_hz": [3.58, 5.01, 3.58]})
    assert mode_ticks(df) == {1: "1\n1st y\n3.58 Hz", 2: "2\n1st x\n5.01 Hz"}


def test_frequency_figure_with_an_outlying_run(tmp_path):
    rows = [{"run_id": f"r{i}", "label": "pso", "variant": "default", "case": "base", "mode": m,
             "mode_label": f"m{m}", "f_measured_hz": 1.0 + m, "error_pct": (40.0 if i == 0 else 0.1 * i),
             "mac": 0.99} for i in range(10) for m in (1, 2)]
    frequencies(pd.DataFrame(rows), tmp_path / "f.png")
    assert (tmp_path / "f.png").stat().st_size > 5_000

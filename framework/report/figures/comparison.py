"""Figure of the ``comparison`` analysis (:mod:`framework.report.analyses.comparison`),
drawn from its ``comparison`` table.

- ``comparison.png``: frequency error per mode, one bar per model (its best run), one panel
  per case (the updated base case and the validation cases).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import seaborn as sns

from framework.report.figures.style import save_figure, styled, subplots
from framework.report.figures.updating import mode_ticks


@styled
def comparison_figure(table: pd.DataFrame, path: Path) -> Path:
    cases = list(dict.fromkeys(table["case"]))
    n_modes = table["mode"].nunique() if "mode" in table else 8
    fig, axes = subplots(1, len(cases), figsize=((0.9 * n_modes + 1.5) * len(cases) + 1.5, 4.2), sharey=True,
                         squeeze=False)
    for ax, case in zip(axes[0], cases):
        d = table[table["case"] == case]
        sns.barplot(data=d, x="mode" if "mode" in d else "mode_label", y="error_pct", hue="model", ax=ax)
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set(title=case, xlabel="measured mode", ylabel="(f_model - f_measured) / f_measured [%]")
        if "mode" in d and "f_measured_hz" in d:
            ticks = mode_ticks(d)
            ax.set_xticks(range(len(ticks)), list(ticks.values()), fontsize=7)
        if ax is not axes[0][-1]:
            ax.get_legend().remove()
        else:
            ax.legend(fontsize=7, title="best run of", title_fontsize=7, loc="upper left", bbox_to_anchor=(1, 1))
    fig.suptitle("Updated frequencies and validation predictions (one bar: the best run of each model)")
    return save_figure(fig, path)

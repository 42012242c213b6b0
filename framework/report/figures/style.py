"""The one look of every figure and the one way a figure is written to a file.

Every figure of gomu is drawn by a function of :mod:`framework.report.figures` from a
results folder's tables, and goes through this module (tests/test_figure_style.py checks it):

- **backend**: Agg (writes files, opens no window, needs no display; the same in a worker
  process or on a server), chosen here, once, when this module is imported, and only when
  the user has chosen none (``MPLBACKEND``, which a notebook sets, a ``matplotlibrc``, or
  ``matplotlib.use`` called before). No other module calls ``matplotlib.use`` or imports
  ``matplotlib.pyplot``: figures are made with :func:`subplots` and :func:`figure`.
- **style** (:data:`STYLE`): white background with a light grey grid and light grey axes
  (seaborn's "whitegrid", which most figures had already), DejaVu Sans (the font
  matplotlib ships, so a figure looks the same on every machine) at 9 pt, titles 10 pt,
  tick labels and legends 8 pt, and the colours of matplotlib's ``tab10`` palette, the
  ones the figure code names (``tab:blue``, ``C0``), so that named and cycled colours are
  one family. A drawing function applies it with the :func:`styled` decorator: only while
  it draws, so a user's own figures in the same session keep their settings (matplotlib
  reads some of these settings when it draws, so the whole function, saving included,
  runs inside).
- **resolution**: :data:`DPI` for every figure: 110 dots per inch, legible 7 pt labels
  (about 11 pixels high) at a moderate file size.
- **file**: :func:`save_figure` crops the figure to its content (nothing outside the axes,
  e.g. a legend beside them, is cut off), writes it as an 8-bit palette PNG (256 colours),
  atomically, and closes it. Why palette PNGs for every figure: they are line drawings,
  markers, bars and heat maps of a few colours with anti-aliased edges, which 256 colours
  render without a visible difference, and the files are 2-3 times smaller than
  matplotlib's RGBA PNGs. Figures are committed with the results and every regeneration
  adds them to the repository's history again (before this module: 245 PNGs, 16.2 MB, of
  which 110 RGBA files held 9.6 MB that would be 3.4 MB as palette PNGs).
"""

from __future__ import annotations

import functools
import io
from pathlib import Path

import matplotlib
from matplotlib import cycler


def _choose_backend() -> None:
    """Agg, unless the user chose a backend (``MPLBACKEND``, a ``matplotlibrc`` or ``matplotlib.use``)."""
    import os

    if os.environ.get("MPLBACKEND"):
        return
    if matplotlib.rcParams._get_backend_or_none() is not None:  # set in a matplotlibrc or by matplotlib.use
        return
    matplotlib.use("Agg")


_choose_backend()

import matplotlib.pyplot as plt  # noqa: E402  (after the backend choice)

#: resolution of every figure (dots per inch)
DPI = 110

#: matplotlib's tab10 colours (``tab:blue``, ``tab:orange``, ...), the colour cycle of every figure
PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
           "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf")  # fmt: skip

#: the settings of every figure (matplotlib rcParams), applied by :func:`styled`
STYLE = {
    # white background, light grey axes and grid, no tick marks (the grid shows the values)
    "figure.facecolor": "white",
    "axes.facecolor": "white",
    "axes.edgecolor": "0.8",
    "axes.linewidth": 1.0,
    "axes.grid": True,
    "axes.axisbelow": True,
    "grid.color": "0.8",
    "grid.linestyle": "-",
    "grid.linewidth": 0.8,
    "xtick.bottom": False,
    "ytick.left": False,
    "xtick.direction": "out",
    "ytick.direction": "out",
    # text: one font, dark grey
    "font.family": "sans-serif",
    "font.sans-serif": ["DejaVu Sans"],
    "text.color": "0.15",
    "axes.labelcolor": "0.15",
    "xtick.color": "0.15",
    "ytick.color": "0.15",
    "font.size": 9.0,
    "axes.titlesize": 10.0,
    "axes.labelsize": 9.0,
    "figure.titlesize": 11.0,
    "xtick.labelsize": 8.0,
    "ytick.labelsize": 8.0,
    "legend.fontsize": 8.0,
    "legend.title_fontsize": 9.0,
    # lines, markers and colours
    "lines.linewidth": 1.2,
    "lines.markersize": 5.0,
    "patch.linewidth": 0.8,
    "axes.prop_cycle": cycler(color=list(PALETTE)),
    # resolution
    "figure.dpi": DPI,
    "savefig.dpi": DPI,
    "savefig.facecolor": "white",
}


def styled(draw):
    """Decorator of a drawing function: it runs with :data:`STYLE` (and only while it runs)."""

    @functools.wraps(draw)
    def wrapper(*args, **kwargs):
        with matplotlib.rc_context(STYLE):
            return draw(*args, **kwargs)

    return wrapper


def subplots(*args, **kwargs):
    """A new figure and its axes (``matplotlib.pyplot.subplots``)."""
    return plt.subplots(*args, **kwargs)


def figure(**kwargs):
    """A new empty figure (``matplotlib.pyplot.figure``)."""
    return plt.figure(**kwargs)


def save_figure(fig, path: str | Path) -> Path:
    """Write ``fig`` to ``path`` as a palette PNG at :data:`DPI`, cropped to its content,
    atomically (readers see the old file or the new one), and close it; returns the path."""
    from PIL import Image

    from framework.core.io import atomic_write_bytes

    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight", facecolor="white")
    finally:
        plt.close(fig)
    buf.seek(0)
    image = Image.open(buf).convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT)
    out = io.BytesIO()
    image.save(out, format="PNG", optimize=True, dpi=(DPI, DPI))
    atomic_write_bytes(path, out.getvalue())
    return Path(path)

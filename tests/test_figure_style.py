"""One reporting layer: every figure is drawn in framework/report/figures/ and goes through its
style module (one backend choice, one style, one resolution, one saver)."""

import ast
import os
import subprocess
import sys
from pathlib import Path

import matplotlib
import pandas as pd
import pytest
from PIL import Image

from framework.report.figures import style
from framework.report.figures.selection import selection_figure

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ROOT / "framework" / "report" / "figures"
STYLE = FIGURES / "style.py"


def _trees():
    for path in sorted((ROOT / "framework").rglob("*.py")):
        yield path, ast.parse(path.read_text())


def _imported(tree) -> set[str]:
    names = set()
    for node in ast.walk(tree):  # also the imports inside functions
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
            names |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
    return names


def _calls(tree, attribute: str, on: str | None = None) -> int:
    """Calls ``<x>.<attribute>(...)`` (with ``on``: ``<on>.<attribute>(...)``)."""
    return sum(isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute) and n.func.attr == attribute
               and (on is None or isinstance(n.func.value, ast.Name) and n.func.value.id == on)
               for n in ast.walk(tree))


def test_only_the_figures_package_imports_matplotlib_and_only_style_imports_pyplot():
    plotting = ("matplotlib", "seaborn", "mpl_toolkits")
    outside, pyplot = [], []
    for path, tree in _trees():
        names = _imported(tree)
        if any(n.split(".")[0] in plotting for n in names) and FIGURES not in path.parents:
            outside.append(str(path.relative_to(ROOT)))
        if any(n.startswith("matplotlib.pyplot") for n in names) and path != STYLE:
            pyplot.append(str(path.relative_to(ROOT)))
    assert outside == [], f"modules outside framework/report/figures that import a plotting library: {outside}"
    assert pyplot == [], f"modules other than the style module that import matplotlib.pyplot: {pyplot}"


def test_one_backend_choice_one_savefig_and_no_other_resolution():
    use, savefig, dpi = {}, {}, []
    for path, tree in _trees():
        name = str(path.relative_to(ROOT))
        if n := _calls(tree, "use", on="matplotlib"):
            use[name] = n
        if n := _calls(tree, "savefig"):
            savefig[name] = n
        if path != STYLE:
            dpi += [f"{name}:{k.value.lineno}" for k in ast.walk(tree) if isinstance(k, ast.keyword) and k.arg == "dpi"]
    assert use == {"framework/report/figures/style.py": 1}
    assert savefig == {"framework/report/figures/style.py": 1}
    assert dpi == [], f"a resolution chosen outside the style module: {dpi}"


def test_every_drawing_function_draws_in_the_style():
    """A function that makes a figure (style.subplots or style.figure) runs inside ``@styled``."""
    unstyled = []
    for path in sorted(FIGURES.glob("*.py")):
        if path == STYLE:
            continue
        for fn in ast.walk(ast.parse(path.read_text())):
            if not isinstance(fn, ast.FunctionDef):
                continue
            makes = any(isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id in ("subplots", "figure")
                        for n in ast.walk(fn))
            if makes and "styled" not in {ast.unparse(d) for d in fn.decorator_list}:
                unstyled.append(f"{path.name}:{fn.name}")
    assert unstyled == []


def test_a_figure_is_a_palette_png_at_the_one_resolution_and_the_style_does_not_leak(tmp_path):
    summary = pd.DataFrame({"label": ["pso", "pso"], "variant": ["swarm_size=5", "swarm_size=20"],
                            "converged": [False, True], "mean_evaluations_to_converge": [float("nan"), 524.0],
                            "mean_best": [3.5e-4, 1.6e-6], "f_star": [1.3e-6, 1.3e-6], "tolerance": [1e-5, 1e-5]})
    before = dict(matplotlib.rcParams)
    path = selection_figure(summary, tmp_path / "sub" / "selection.png", "pso swarm")
    image = Image.open(path)
    assert image.mode == "P"  # 8-bit palette
    assert image.info["dpi"] == pytest.approx((style.DPI, style.DPI), abs=0.01)
    # 12 x 3.5 in at 110 dpi, cropped to the content (a few pixels of margin either way)
    assert 0.9 * 12 * style.DPI < image.size[0] < 1.1 * 12 * style.DPI
    assert matplotlib.pyplot.get_fignums() == []  # the figure is closed
    assert dict(matplotlib.rcParams) == before  # the style applies while drawing only
    assert style.STYLE["axes.grid"] and not matplotlib.rcParams["axes.grid"]


def _backend(env_backend: str | None, code: str = "") -> str:
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"} | {"PYTHONPATH": str(ROOT)}
    if env_backend:
        env["MPLBACKEND"] = env_backend
    script = f"import matplotlib\n{code}\nimport framework.report.figures.style\nprint(matplotlib.get_backend())"
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
    return out.stdout.strip().lower()


def test_agg_is_chosen_only_when_the_user_chose_no_backend():
    assert _backend(None) == "agg"
    assert _backend("svg") == "svg"  # MPLBACKEND (a notebook sets it) wins
    assert _backend(None, "matplotlib.use('pdf')") == "pdf"  # so does matplotlib.use before


def test_a_blank_figure_is_smaller_than_what_the_figure_tests_take_for_a_drawn_one(tmp_path):
    """The figure tests take a file of more than 5 kB for a drawn figure (palette PNGs are small)."""

    @style.styled
    def blank(path):
        fig, _ = style.subplots(1, 2, figsize=(8, 4))
        return style.save_figure(fig, path)

    assert blank(tmp_path / "blank.png").stat().st_size < 5_000

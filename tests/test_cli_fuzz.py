"""Property-based tests of the command line (issue 14): fuzzed config text, data files and
``--set`` values through ``gomu validate`` and ``gomu run`` (``framework.cli.main`` in this
process). Whatever the input: exit code 0 or 2; on 2 exactly one line ``gomu: error: ...``
naming the config or data file, no traceback; an existing results folder is left exactly
as it was. The default profile is small (a few seconds); the ``slow`` tests run the same
properties with many more examples."""

import contextlib
import hashlib
import io
import shutil
import tempfile
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from framework.cli import main

BASE = {
    "study": "fuzz",
    "structure": {"name": "lab_frame_3dof"},
    "measured": {"builtin": "lab_frame", "case": "base"},
    "budget": {"max_evaluations": 20, "stall_iterations": 5},
    "algorithms": {"sm": {"algorithm": "sm"}},
    "runs": 1,
    "execution": {"progress": False},
}
#: dotted paths a fuzzer changes (every section and typed field of the updating kind's schema)
PATHS = [
    "study", "kind", "runs", "seed", "description", "structure", "structure.name", "structure.options",
    "structure.options.case", "measured", "measured.builtin", "measured.case", "measured.modes", "measured.file",
    "validation", "budget", "budget.max_evaluations", "budget.stall_iterations", "budget.stall_tolerance",
    "budget.target_objective", "algorithms", "algorithms.sm", "algorithms.sm.algorithm", "algorithms.sm.settings",
    "algorithms.sm.settings.start", "algorithms.sm.runs", "algorithms.sm.budget", "algorithms.pso",
    "objective", "objective.alpha", "objective.beta", "objective.failure_penalty", "objective.formulation",
    "parameters", "parameters.names", "parameters.bounds", "parameters.bounds.kxx", "sweep", "variants",
    "report", "execution.workers", "execution.isolate", "execution.evaluation_timeout_s", "execution.backend",
]  # fmt: skip
#: paths that change where or how a run executes: not fuzzed through ``gomu run``
RUN_EXCLUDED = ("execution", "output", "runs", "sweep", "variants")

scalars = st.one_of(
    st.none(), st.booleans(), st.integers(-1000, 1000), st.sampled_from([0, 1, -1, 2**31, 2**63, -(2**63), 10**30]),
    st.floats(allow_nan=True, allow_infinity=True), st.sampled_from([1.7e308, -1.7e308, 5e-324, 1e-9]),
    st.text(max_size=12), st.sampled_from(["lab_frame", "base", "sm", "pso", "os:system", "../x", "1st y", "yx"]),
)
values = st.recursive(scalars, lambda inner: st.lists(inner, max_size=3) | st.dictionaries(
    st.text(max_size=6) | st.sampled_from(["sm", "algorithm", "kxx", "case", "builtin"]), inner, max_size=3),
    max_leaves=6)


def _set(data: dict, dotted: str, value) -> None:
    node = data
    keys = dotted.split(".")
    for key in keys[:-1]:
        if not isinstance(node.get(key), dict):
            node[key] = {}
        node = node[key]
    node[keys[-1]] = value


def _cli(*argv) -> tuple[int, str]:
    """Exit code and stderr of ``gomu <argv>`` run in this process."""
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:  # argparse
            code = exc.code
    return code, err.getvalue()


def _check(code: int, err: str, *names: Path) -> None:
    """Exit 0, or exit 2 with one line naming one of ``names`` (files); never a traceback."""
    assert code in (0, 2), (code, err)
    assert "Traceback" not in err, err
    if code == 2:
        lines = err.strip().splitlines()
        assert len(lines) == 1, err
        assert lines[0].startswith(("gomu: error: ", "gomu validate: error: ", "gomu run: error: ")), err
        assert any(str(n) in lines[0] for n in names) or "--set" in lines[0], err


def _tree(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


# ---- properties -------------------------------------------------------------------------------
def _changed_config(changes, deletions, folder: Path) -> Path:
    data = yaml.safe_load(yaml.safe_dump(BASE))
    for path, value in changes:
        _set(data, path, value)
    for path in deletions:
        node = data
        *head, last = path.split(".")
        for key in head:
            node = node.get(key) if isinstance(node, dict) else None
        if isinstance(node, dict):
            node.pop(last, None)
    data["output"] = str(folder / "out")
    cfg = folder / "study.yaml"
    cfg.write_text(yaml.safe_dump(data, allow_unicode=True))
    return cfg


def prop_changed_config(changes, deletions):
    with tempfile.TemporaryDirectory() as tmp:
        cfg = _changed_config(changes, deletions, Path(tmp))
        _check(*_cli("validate", cfg), cfg)


def prop_config_text(text: str):
    with tempfile.TemporaryDirectory() as tmp:
        cfg = Path(tmp) / "study.yaml"
        cfg.write_bytes(text.encode("utf-8", "surrogatepass"))
        _check(*_cli("validate", cfg), cfg)


def prop_spliced_config_text(cut: int, length: int, insert: str):
    text = yaml.safe_dump(BASE)
    cut = cut % len(text)
    prop_config_text(text[:cut] + insert + text[cut + length:])


def prop_data_file(file: tuple[str, str]):
    suffix, text = file
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp) / f"modes{suffix}"
        data.write_text(text)
        cfg = _changed_config([("measured", {"file": data.name})], [], Path(tmp))
        _check(*_cli("validate", cfg), cfg, data)


def prop_set_values(overrides):
    with tempfile.TemporaryDirectory() as tmp:
        cfg = _changed_config([], [], Path(tmp))
        argv = ["validate", cfg]
        for key, value in overrides:
            argv += ["--set", f"{key}={value}"]
        _check(*_cli(*argv), cfg)


OTHER_KINDS = {
    "diagnose": ({"study": "d", "kind": "diagnose", "structure": "lab_frame",
                  "measured": {"builtin": "lab_frame", "case": "base"}, "settings": {"n_starts": 1}},
                 ["structure", "structure_options", "start_effects", "measured", "measured.builtin", "measured.case",
                  "measured.generate", "measured.generate.noise", "measured.generate.hidden", "measured.generate.seed",
                  "measured.file", "settings", "settings.n_starts", "settings.alpha", "runs", "report"]),
    "analysis": ({"study": "a", "kind": "analysis", "structure": {"name": "lab_frame_3dof"},
                  "measured": {"builtin": "lab_frame"}},
                 ["structure", "structure.name", "structure.options", "measured", "points", "points.p",
                  "points.p.values", "points.p.ratios", "sensitivity", "sensitivity.rel_step", "pairings",
                  "parameters", "objective", "validation"]),
}  # fmt: skip


def prop_other_kinds(kind: str, data):
    """Changed fields of the diagnose and analysis kinds' configs through ``gomu validate``."""
    base, paths = OTHER_KINDS[kind]
    config = yaml.safe_load(yaml.safe_dump(base))
    for path, value in data.draw(st.lists(st.tuples(st.sampled_from(paths), values), min_size=1, max_size=3)):
        _set(config, path, value)
    with tempfile.TemporaryDirectory() as tmp:
        config["output"] = str(Path(tmp) / "out")
        cfg = Path(tmp) / "study.yaml"
        cfg.write_text(yaml.safe_dump(config, allow_unicode=True))
        _check(*_cli("validate", cfg), cfg)


def prop_run_leaves_stored_results_alone(results, overrides, resume: bool):
    """``gomu run`` with fuzzed --set values into an existing results folder: exit 0 or 2, and
    after an error the folder is byte for byte what it was."""
    pristine, cfg = results
    out = cfg.parent / "out"
    if out.exists():
        shutil.rmtree(out)
    shutil.copytree(pristine, out)
    before = _tree(out)
    argv = ["run", cfg, "--no-figures", "--quiet"] + (["--resume"] if resume else [])
    for key, value in overrides:
        argv += ["--set", f"{key}={value}"]
    argv += ["--set", "budget.max_evaluations=20", "--set", "runs=1"]  # keeps a valid run cheap
    code, err = _cli(*argv)
    _check(code, err, cfg)
    if code == 2:
        assert _tree(out) == before


# ---- strategies -------------------------------------------------------------------------------
changes = st.lists(st.tuples(st.sampled_from(PATHS), values), min_size=1, max_size=3)
deletions = st.lists(st.sampled_from(PATHS), max_size=2)
yaml_like = st.one_of(
    st.text(max_size=30),
    values.map(lambda v: yaml.safe_dump(v, default_flow_style=True).strip()),
    st.sampled_from(["[99]", "[0]", "[-1]", "1e23", "1e400", "true", ".nan", "{a: 1", "*x", "&a [1]", "'", "",
                     "!!python/object:os.system x", "[" * 200, "0x10", "1:30", "yes", "1,5"]),
)
set_keys = st.one_of(st.sampled_from(PATHS), st.text(max_size=10), st.sampled_from(["", ".", "a..b", "runs.x"]))
overrides = st.lists(st.tuples(set_keys, yaml_like), min_size=1, max_size=3)
run_keys = st.sampled_from([p for p in PATHS if not p.startswith(RUN_EXCLUDED)])
run_overrides = st.lists(st.tuples(run_keys, yaml_like), min_size=1, max_size=2)
cell = st.one_of(st.sampled_from(["3.58", "3,58", "1e400", "nan", "-1", "0", "", "1st y", '"x', "1" * 50, "1e-400",
                                  "inf", " 5.01 ", "true"]), st.text(max_size=6))
columns = st.lists(st.sampled_from(["label", "frequency_hz", "damping_ratio", "y", "x", "torsion", "mode", "", "freq"]),
                   min_size=1, max_size=5)
csv_text = st.builds(
    lambda header, rows, sep: sep.join(header) + "\n" + "\n".join(sep.join(r) for r in rows) + "\n",
    columns, st.lists(st.lists(cell, min_size=1, max_size=6), max_size=4), st.sampled_from([",", ";", "\t"]))
mode = st.fixed_dictionaries({}, optional={
    "frequency_hz": scalars, "shape": st.lists(scalars, max_size=4), "label": scalars, "damping_ratio": scalars,
    "extra": scalars})
yaml_data = st.builds(
    lambda d: yaml.safe_dump(d, allow_unicode=True),
    st.fixed_dictionaries({}, optional={"dofs": st.one_of(st.lists(scalars, max_size=4), scalars),
                                        "modes": st.one_of(st.lists(mode, max_size=4), scalars),
                                        "units": values, "name": scalars}))
data_file = st.one_of(st.tuples(st.just(".yaml"), yaml_data), st.tuples(st.just(".csv"), csv_text),
                      st.tuples(st.sampled_from([".yaml", ".csv", ".txt"]), st.text(max_size=80)))


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    """A finished tiny study (its folder kept as a pristine copy) and its config."""
    root = tmp_path_factory.mktemp("fuzz_run")
    cfg = _changed_config([], [], root)
    code, err = _cli("run", cfg, "--no-figures", "--quiet")
    assert code == 0, err
    pristine = root / "pristine"
    shutil.copytree(root / "out", pristine)
    return pristine, cfg


FAST = dict(deadline=None, derandomize=True, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                    HealthCheck.too_slow])
SLOW = dict(FAST, derandomize=False)


def _both(prop, strategies, fast: int, slow: int):
    """A fast test (``fast`` examples, same every time) and a slow one (``slow`` random examples)."""
    quick = settings(max_examples=fast, **FAST)(given(*strategies)(prop))
    long = pytest.mark.slow(settings(max_examples=slow, **SLOW)(given(*strategies)(prop)))
    return quick, long


test_changed_config, test_changed_config_long = _both(prop_changed_config, (changes, deletions), 60, 1000)
test_config_text, test_config_text_long = _both(prop_config_text, (st.text(max_size=200),), 30, 500)
test_spliced_config, test_spliced_config_long = _both(
    prop_spliced_config_text, (st.integers(0, 10_000), st.integers(0, 20), st.text(max_size=20)), 30, 500)
test_data_file, test_data_file_long = _both(prop_data_file, (data_file,), 40, 800)
test_set_values, test_set_values_long = _both(prop_set_values, (overrides,), 40, 800)
test_other_kinds, test_other_kinds_long = _both(prop_other_kinds, (st.sampled_from(sorted(OTHER_KINDS)), st.data()),
                                                30, 600)


@settings(max_examples=12, **FAST)
@given(overrides=run_overrides, resume=st.booleans())
def test_run_leaves_stored_results_alone(results, overrides, resume):
    prop_run_leaves_stored_results_alone(results, overrides, resume)


@pytest.mark.slow
@settings(max_examples=200, **SLOW)
@given(overrides=run_overrides, resume=st.booleans())
def test_run_leaves_stored_results_alone_long(results, overrides, resume):
    prop_run_leaves_stored_results_alone(results, overrides, resume)


@pytest.mark.parametrize("key", ["0\x850", "a\u2028b", "x\ny", "t\tz"])
def test_a_key_with_a_line_break_is_reported_on_one_line(tmp_path, key):
    """Found by the fuzzer: a key holding U+0085 (a line break for ``splitlines``) was echoed raw."""
    cfg = _changed_config([], [], tmp_path)
    code, err = _cli("validate", cfg, "--set", f"{key}=1")
    assert code == 2 and len(err.strip().splitlines()) == 1, err

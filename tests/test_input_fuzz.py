"""Property tests of the input layer (issue 14): random text, bytes and structures given to the
YAML reader and to the measured-modes loaders (YAML and CSV) raise only InputError, with a
one-line message naming the file; valid files round-trip exactly (save -> load)."""

import csv
import io
import math

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from framework.core import textio
from framework.core.errors import InputError
from framework.measured import modes as measurements
from framework.measured.modes import MeasuredModes

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

#: YAML-ish text: fragments of the syntax mixed with random characters
yaml_tokens = st.sampled_from(
    ["a", "b", ":", ": ", "- ", "\n", "  ", "[", "]", "{", "}", ",", "&x ", "*x", "<<", "? ", "!!int ", "!!str ",
     "!!python/name:os.system", "'", '"', "#", "---", "...", "|", ">", "1", "1e400", "-.inf", ".nan", "true", "~",
     "0x1F", "010", "1:30", "%YAML 1.1\n", "\t", "\\", "é", "\x00", "\ufeff"]
)
yaml_like = st.lists(yaml_tokens | st.text(max_size=4), max_size=40).map("".join)

scalars = (st.none() | st.booleans() | st.integers() | st.integers(min_value=10**300, max_value=10**400)
           | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=6))
structures = st.recursive(
    scalars, lambda kids: st.lists(kids, max_size=4) | st.dictionaries(st.text(max_size=6), kids, max_size=4),
    max_leaves=16)


def _assert_named_one_line(exc: InputError, name: str) -> None:
    message = str(exc)
    assert message.startswith(f"{name}: "), message
    assert "\n" not in message and "Traceback" not in message, message


def _load_expecting_input_error(path):
    try:
        return measurements.load(path)
    except InputError as exc:
        _assert_named_one_line(exc, str(path))
        return None


@FUZZ
@given(text=yaml_like)
def test_yaml_text_raises_only_named_one_line_errors(text):
    try:
        textio.read_yaml_text(text, "fuzz.yaml", mapping=False)
    except InputError as exc:
        _assert_named_one_line(exc, "fuzz.yaml")


@FUZZ
@given(text=st.text(max_size=60))
def test_override_values_raise_only_named_errors(text):
    try:
        textio.parse_override_value(text, "--set a.b")
    except InputError as exc:
        _assert_named_one_line(exc, "--set a.b")


@FUZZ
@given(data=st.binary(max_size=200))
def test_yaml_file_bytes(tmp_path, data):
    path = tmp_path / "c.yaml"
    path.write_bytes(data)
    try:
        value = textio.read_yaml_file(path)
    except InputError as exc:
        _assert_named_one_line(exc, str(path))
    else:
        assert isinstance(value, dict)


@FUZZ
@given(data=st.binary(max_size=200), suffix=st.sampled_from([".yaml", ".csv"]))
def test_measured_file_bytes(tmp_path, data, suffix):
    path = tmp_path / f"m{suffix}"
    path.write_bytes(data)
    m = _load_expecting_input_error(path)
    if m is not None:
        assert np.all(np.isfinite(m.frequencies_hz)) and np.all(m.frequencies_hz > 0)


mode_values = st.fixed_dictionaries(
    {"frequency_hz": scalars | structures},
    optional={k: scalars | structures for k in ("label", "shape", "damping_ratio", "frequency_std_hz", "shape_std",
                                               "weight_frequency", "weight_shape", "extra")},
)


@FUZZ
@given(data=st.fixed_dictionaries(
    {"modes": st.lists(mode_values, max_size=3) | structures},
    optional={"dofs": st.lists(scalars, max_size=3) | structures, "name": scalars, "meta": structures,
              "units": structures}))
def test_measured_yaml_structures(tmp_path, data):
    path = tmp_path / "m.yaml"
    try:
        text = yaml.safe_dump(data)
    except (yaml.YAMLError, OverflowError):  # PyYAML cannot write everything hypothesis makes
        return
    path.write_text(text)
    m = _load_expecting_input_error(path)
    if m is not None:
        assert np.all(np.isfinite(m.frequencies_hz)) and np.all(m.frequencies_hz > 0)
        assert all(isinstance(label, str) for label in m.labels) and len(set(m.labels)) == m.n_modes
        assert all(isinstance(d, str) for d in m.dofs)
        if m.shapes is not None:
            assert m.shapes.shape == (len(m.dofs), m.n_modes) and np.all(np.isfinite(m.shapes))


csv_cells = st.sampled_from(["3.58", "3,58", "1e400", "nan", "-1", "0", "", " ", "1st y", '"', "true", "0x1",
                             "5.", ".5", "1e-3", "é", "a;b", "\t"]) | st.text(max_size=5)
csv_header = st.lists(st.sampled_from(["label", "frequency_hz", "damping_ratio", "frequency_std_hz", "weight_shape",
                                       "weight_frequency", "mode", "shape:y", "shape:x", "shape:", "x", ""]),
                      min_size=1, max_size=5)


@FUZZ
@given(header=csv_header, rows=st.lists(st.lists(csv_cells, max_size=6), max_size=4),
       sep=st.sampled_from([",", ",", ";", "\t"]))
def test_measured_csv_tables(tmp_path, header, rows, sep):
    path = tmp_path / "m.csv"
    path.write_text("\n".join(sep.join(r) for r in [header, *rows]) + "\n")
    m = _load_expecting_input_error(path)
    if m is not None:
        assert np.all(np.isfinite(m.frequencies_hz)) and np.all(m.frequencies_hz > 0)
        assert m.n_modes == len([r for r in rows if "".join(r).strip()])


# ---- valid files round-trip ----------------------------------------------------------------------
finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_subnormal=False)
positive = st.floats(min_value=1e-3, max_value=1e4, allow_nan=False)
label_text = st.text(st.characters(codec="utf-8", exclude_categories=("Cs", "Cc")), min_size=1, max_size=8).filter(
    lambda s: s.strip() == s and s != "")


@st.composite
def measured_modes(draw):
    m = draw(st.integers(1, 4))
    n = draw(st.integers(0, 3))
    dofs = draw(st.lists(label_text, min_size=n, max_size=n, unique=True))
    shapes = None
    if n and draw(st.booleans()):
        shapes = np.array(draw(st.lists(st.lists(finite, min_size=m, max_size=m), min_size=n, max_size=n)))
        assume(np.all(np.any(shapes != 0, axis=0)))
    opt = lambda strategy: draw(st.none() | st.lists(strategy, min_size=m, max_size=m))  # noqa: E731
    return MeasuredModes(
        frequencies_hz=draw(st.lists(positive, min_size=m, max_size=m)),
        dofs=tuple(dofs),
        shapes=shapes,
        damping_ratio=opt(st.floats(0.0, 0.99)),
        labels=tuple(draw(st.lists(label_text, min_size=m, max_size=m, unique=True))),
        weight_frequency=opt(st.floats(0.0, 10.0)),
        frequency_std_hz=opt(st.floats(0.0, 1.0)),
        name=draw(label_text),
    )


def _same(a: MeasuredModes, b: MeasuredModes) -> None:
    assert (a.labels, a.dofs, a.name) == (b.labels, b.dofs, b.name)
    for key in ("frequencies_hz", "shapes", "damping_ratio", "weight_frequency", "weight_shape", "frequency_std_hz",
                "shape_std"):
        x, y = getattr(a, key), getattr(b, key)
        assert (x is None) == (y is None), key
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=key)  # exact: floats are written with repr


@FUZZ
@given(m=measured_modes())
def test_yaml_roundtrip_is_exact(tmp_path, m):
    back = measurements.load(measurements.save(m, tmp_path / "m.yaml"))
    _same(m, back)


@FUZZ
@given(m=measured_modes())
def test_csv_roundtrip_is_exact(tmp_path, m):
    assume(all(label == label.strip() for label in m.labels))
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    cols = ["label", "frequency_hz"] + [c for c in ("damping_ratio", "weight_frequency", "frequency_std_hz")
                                        if getattr(m, c) is not None]
    shape_cols = [f"shape:{d}" for d in m.dofs] if m.shapes is not None else []
    writer.writerow(cols + shape_cols)
    for j in range(m.n_modes):
        row = [m.labels[j]] + [repr(float(getattr(m, "frequencies_hz" if c == "frequency_hz" else c)[j]))
                               for c in cols[1:]]
        row += [repr(float(v)) for v in (m.shapes[:, j] if m.shapes is not None else [])]
        writer.writerow(row)
    path = tmp_path / "m.csv"
    path.write_text(buf.getvalue())
    expected = MeasuredModes(m.frequencies_hz, m.dofs if m.shapes is not None else (), m.shapes, m.damping_ratio,
                             m.labels, m.weight_frequency, None, m.frequency_std_hz, None, name="m")
    _same(expected, measurements.load(path))


@pytest.mark.parametrize("value", [math.pi, 1e-300, 1.7976931348623157e308, 5e-324, -0.0])
def test_float_text_roundtrip_edges(value):
    assert textio.read_yaml_text(textio.dump_yaml({"v": value}), "t")["v"] == value


plain_scalars = (st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False)
                 | st.text(st.characters(codec="utf-8", exclude_categories=("Cs",)), max_size=6))
plain_data = st.recursive(
    plain_scalars, lambda kids: st.lists(kids, max_size=4) | st.dictionaries(st.text(max_size=6), kids, max_size=4),
    max_leaves=20)


@FUZZ
@given(data=plain_data)
def test_dump_then_read_gives_the_same_data(data):
    text = textio.dump_yaml(data)
    assert textio.read_yaml_text(text, "t", mapping=False) == data
    assert yaml.safe_load(text) == data

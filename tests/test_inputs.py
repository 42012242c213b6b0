"""Parameters, measured-modes files and the strict text reader (framework.core.textio): loading and
errors that name file, field and value; one test per input defect of issue 14."""

import math
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest
import yaml

from framework.core import textio
from framework.core.errors import InputError
from framework.core.parameters import Parameter, ParameterSet
from framework.measured import modes as measurements
from framework.measured.modes import MeasuredModes

ROOT = Path(__file__).resolve().parents[1]


def test_roundtrip_yaml_and_csv(tmp_path):
    m = MeasuredModes(np.array([3.58, 5.01]), ("y", "x"), np.array([[1.0, 0.07], [0.004, 1.0]]),
                      damping_ratio=np.array([0.012, 0.008]), frequency_std_hz=np.array([0.01, 0.02]))
    path = measurements.save(m, tmp_path / "m.yaml")
    back = measurements.load(path)
    np.testing.assert_allclose(back.frequencies_hz, m.frequencies_hz)
    np.testing.assert_allclose(back.shapes, m.shapes)
    assert back.dofs == ("y", "x")
    csv = tmp_path / "m.csv"
    csv.write_text("label,frequency_hz,damping_ratio,shape:y,shape:x\nA,3.58,0.012,1.0,0.004\nB,5.01,0.008,0.07,1.0\n")
    c = measurements.load(csv)
    np.testing.assert_allclose(c.shapes, m.shapes)
    assert c.labels == ("A", "B")


@pytest.mark.parametrize(
    "text, message",
    [
        ("dofs: [y]\nmodes:\n  - {frequency_hz: .nan}\n", "frequency_hz: must be a finite positive number, got nan"),
        ("dofs: [y]\nmodes:\n  - {frequency_hz: -3.0}\n", "frequency_hz: must be a finite positive number, got -3.0"),
        ("dofs: [y]\nmodes:\n  - {frequency_hz: abc}\n", "frequency_hz: not a number: 'abc'"),
        ("dofs: [y, x]\nmodes:\n  - {frequency_hz: 3.0, shape: [1.0]}\n", "modes\\[0\\].shape: has 1 values, expected 2"),
        ("dofs: [y, y]\nmodes:\n  - {frequency_hz: 3.0, shape: [1.0, 2.0]}\n", "duplicate DOF labels \\['y'\\]"),
        ("dofs: [y]\nmodes:\n  - {frequency_hz: 3.0, shape: [0.0]}\n", "mode 1 shape is all zeros"),
        ("dofs: [y]\nmodes:\n  - {frequency_hz: 3.0, frequncy: 2}\n", "unknown key\\(s\\) \\['frequncy'\\]"),
        ("dofs: [y]\nmodes: []\n", "'modes' must be a non-empty list"),
        ("dofs: [y]\nmodes:\n  - {frequency_hz: 3.0, shape: [1.0]}\n  - {frequency_hz: 4.0}\n",
         "'shape' given for some modes but missing for modes \\[1\\]"),
        ("[1, 2", "not valid YAML"),
    ],
)
def test_bad_measured_files(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        measurements.load(path)
    assert str(path) in str(info.value)


def test_missing_empty_and_unsupported_files(tmp_path):
    with pytest.raises(InputError, match="not found"):
        measurements.load(tmp_path / "nope.yaml")
    (tmp_path / "e.yaml").write_text("")
    with pytest.raises(InputError, match="file is empty"):
        measurements.load(tmp_path / "e.yaml")
    (tmp_path / "x.txt").write_text("1")
    with pytest.raises(InputError, match="unsupported measured-modes format '.txt'"):
        measurements.load(tmp_path / "x.txt")


@pytest.mark.parametrize(
    "args, message",
    [
        (("k", 1.0, 2.0, 0.5), "bounds are swapped \\(lower=2.0 > upper=0.5\\)"),
        (("k", 1.0, 1.0, 1.0), "bounds are empty"),
        (("k", 5.0, 0.0, 1.0), "initial=5.0 is outside bounds"),
        (("k", float("nan"), 0.0, 1.0), "initial must be finite"),
        (("k", "1", 0.0, 1.0), "initial must be a number, got '1'"),
    ],
)
def test_bad_parameters(args, message):
    with pytest.raises(InputError, match=message):
        Parameter(*args)


def test_parameter_maps_roundtrip():
    ps = ParameterSet([Parameter("a", 2.0, 1.0, 3.0, "N/m"), Parameter("b", 0.0, -1.0, 1.0, "m")])
    theta = np.array([2.5, -0.5])
    np.testing.assert_allclose(ps.to_physical(ps.to_normalized(theta)), theta)
    np.testing.assert_allclose(ps.x_initial, [0.5, 0.5])
    assert np.isnan(ps.to_ratio(theta)[1]) and ps.to_ratio(theta)[0] == 1.25
    with pytest.raises(InputError, match="duplicate names"):
        ParameterSet([ps[0], ps[0]])


# ---- framework.core.textio: the one reader of user YAML/CSV/text (issue 14, defects 3, 4, 7, 8) --------------


def _read_error(tmp_path, text, name="c.yaml", **kw) -> str:
    path = tmp_path / name
    path.write_bytes(text if isinstance(text, bytes) else text.encode("utf-8"))
    with pytest.raises(InputError) as info:
        textio.read_yaml_file(path, **kw)
    message = str(info.value)
    assert message.startswith(f"{path}: ") and "\n" not in message, message
    return message


@pytest.mark.parametrize(
    "text, message",
    [
        ("a: 1\nb: 2\na: 3\n", "a: duplicate key (line 3, first given at line 1)"),
        ("algorithms:\n  pso: {runs: 1}\n  pso: {runs: 2}\n", "algorithms.pso: duplicate key (line 3, first given at line 2)"),
        ("modes:\n  - {frequency_hz: 3.0, frequency_hz: 4.0}\n", "modes[0].frequency_hz: duplicate key (line 2, columns 6 and 25)"),
        ("a: {1: x, true: y}\n", "a.true: duplicate key"),  # 1 and true would be one Python key
    ],
)
def test_duplicate_keys_are_errors_naming_path_and_lines(tmp_path, text, message):
    assert message in _read_error(tmp_path, text)


def test_alias_bomb_is_refused_before_expansion(tmp_path):
    lines = ['a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    for i in range(1, 10):
        lines.append(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]")
    message = _read_error(tmp_path, "\n".join(lines) + "\n")
    assert f"more than the limit of {textio.MAX_ALIAS_NODES}" in message and "alias bomb" in message


def test_small_aliases_and_merge_keys_still_work(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("base: &b {swarm_size: 20, w: 0.7}\npso: {settings: *b}\npso2: {<<: *b, w: 0.5}\n")
    data = textio.read_yaml_file(path)
    assert data["pso"]["settings"] == {"swarm_size": 20, "w": 0.7}
    assert data["pso2"] == {"swarm_size": 20, "w": 0.5}


@pytest.mark.parametrize("text", ["a: &x [*x]\n", "&x {a: *x}\n"])
def test_recursive_alias_is_an_error(tmp_path, text):
    assert "recursive alias" in _read_error(tmp_path, text)


def test_nesting_depth_is_limited_without_recursion_error(tmp_path):
    assert f"nesting deeper than {textio.MAX_DEPTH} levels" in _read_error(tmp_path, "a: " + "[" * 500 + "]" * 500)
    # 3000 levels: libyaml's own limit (1000) may answer first; either way one named line
    assert re.search(r"nesting deeper than|maximum nesting depth", _read_error(tmp_path, "a: " + "[" * 3000 + "]" * 3000))
    path = tmp_path / "ok.yaml"
    path.write_text("a: " + "[" * (textio.MAX_DEPTH - 1) + "]" * (textio.MAX_DEPTH - 1))
    textio.read_yaml_file(path)  # the limit itself is allowed
    deep_alias = "a: &a " + "[" * (textio.MAX_DEPTH - 1) + "]" * (textio.MAX_DEPTH - 1) + "\nb: [*a]\n"
    assert "once aliases are expanded" in _read_error(tmp_path, deep_alias)


def test_size_limit_is_checked_before_parsing(tmp_path):
    message = _read_error(tmp_path, "a: [" + "1, " * 400_000 + "1]\n")
    assert f"more than the limit of {textio.CONFIG_MAX_BYTES} bytes" in message
    assert "limit of 10 bytes" in _read_error(tmp_path, "a: 12345678\n", max_bytes=10)


@pytest.mark.parametrize(
    "content, message",
    [
        (b"a: caf\xe9\n", "not UTF-8 text (byte 0xe9 at offset 6)"),
        (b"\xff\xfea\x00:\x00 \x001\x00", "not UTF-8 text (byte 0xff at offset 0)"),  # UTF-16
        (b"", "config file is empty"),
        (b"  \n\n", "config file is empty"),
        (b"# only a comment\n", "config file is empty"),
        (b"- 1\n- 2\n", "a config must be a mapping (key: value lines), got a list"),
        (b"just text\n", "a config must be a mapping (key: value lines), got a text"),
        (b"a: 1\n---\nb: 2\n", "expected a single document"),
        (b"a: [1, 2\n", "not valid YAML: line 2, column 1"),
        (b"a: \x00\n", "not valid YAML"),
        (b"a: !!python/object/apply:os.system [echo hacked]\n", "unsupported tag"),
        (b"a: !!binary aGVsbG8=\n", "unsupported tag"),
        (b"? [1, 2]\n: 3\n", "a mapping key must be a plain value, not a list"),
        (b"a: *nowhere\n", "undefined alias"),
    ],
)
def test_bad_files_are_one_line_input_errors(tmp_path, content, message):
    assert message in _read_error(tmp_path, content)


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(InputError, match=r"nope.yaml: config file not found$"):
        textio.read_yaml_file(tmp_path / "nope.yaml")
    with pytest.raises(InputError, match=r": is a folder, not a config file$"):
        textio.read_yaml_file(tmp_path)
    with pytest.raises(InputError, match=r": is a folder, not a measured-modes file$"):
        measurements.load(tmp_path)
    (tmp_path / "d.yaml").mkdir()
    with pytest.raises(InputError, match=r"d.yaml: is a folder"):
        measurements.load(tmp_path / "d.yaml")


def test_utf8_byte_order_mark_is_accepted(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_bytes(b"\xef\xbb\xbfa: 1\n")
    assert textio.read_yaml_file(path) == {"a": 1}


def test_scalars_follow_the_yaml_1_2_core_schema():
    text = ("[1e-6, 1E+3, 5., .5, 010, 0o10, 0x1F, -0, yes, no, on, off, y, 1:30, 2024-01-01, 1_000, "
            "true, False, ~, null, '', .inf, -.Inf, .NaN, '1.5']")
    got = textio.read_yaml_text(text, "t", mapping=False)
    assert got[:8] == [1e-6, 1000.0, 5.0, 0.5, 10, 8, 31, 0]
    assert [type(v) for v in got[:8]] == [float, float, float, float, int, int, int, int]
    assert got[8:16] == ["yes", "no", "on", "off", "y", "1:30", "2024-01-01", "1_000"]
    assert got[16:20] == [True, False, None, None] and got[20] == "" and got[-1] == "1.5"
    assert got[21] == math.inf and got[22] == -math.inf and math.isnan(got[23])


@pytest.mark.parametrize(
    "text, message",
    [
        ("a: 1e400", "number 1e400 is outside the double-precision range"),
        ("a: -2e308", "number -2e308 is outside the double-precision range"),
        ("a: 1e-400", "number 1e-400 is too small: it would be read as 0"),
        ("a: " + "9" * 1200, "integer of 1200 digits is too large"),
        ("a: !!int 1.5", "not an integer: '1.5'"),
    ],
)
def test_numbers_are_exact_or_refused(text, message):
    with pytest.raises(InputError, match="^t: .*" + re.escape(message)):
        textio.read_yaml_text(text, "t")
    assert textio.read_yaml_text("a: " + "9" * 400, "t")["a"] == 10**400 - 1  # exact; ranges are the schema's job


def test_override_values():
    assert textio.parse_override_value("[5, 10]") == [5, 10]
    assert textio.parse_override_value("1e-6") == 1e-6
    assert textio.parse_override_value("true") is True
    assert textio.parse_override_value("pso") == "pso"
    assert textio.parse_override_value("") is None
    with pytest.raises(InputError, match=r"^--set measured.modes: not valid YAML: .*\(quote the value if it is text\)$"):
        textio.parse_override_value("[1, 2", "--set measured.modes")
    with pytest.raises(InputError, match=r"^--set x: a: duplicate key"):
        textio.parse_override_value("{a: 1, a: 2}", "--set x")
    with pytest.raises(InputError, match=r"nesting deeper than 100"):
        textio.parse_override_value("[" * 500 + "]" * 500)


def test_dump_yaml_quotes_text_that_any_reader_would_retype():
    data = {"labels": ["1e5", "yes", "no", "on", "2024-01-01", "", "1_000", "010", "0o10", "1:30", "null", "~", ".5",
                       "1st y", "y"],
            "numbers": [1e20, 1e-5, 3, -0.0, 10**30, 0.1 + 0.2], "flags": [True, False, None]}
    text = textio.dump_yaml(data)
    assert textio.read_yaml_text(text, "t") == data
    assert yaml.safe_load(text) == data  # plain PyYAML (YAML 1.1) reads it alike


def test_repo_yaml_files_read_as_before():
    files = subprocess.run(["git", "ls-files", "*.yaml", "*.yml"], cwd=ROOT, capture_output=True, text=True).stdout.split()
    assert len(files) > 10
    for name in files:
        path = ROOT / name
        assert textio.read_yaml_file(path, max_bytes=textio.DATA_MAX_BYTES) == yaml.safe_load(path.read_text()), name


# ---- CSV ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, message",
    [
        ("label,frequency_hz\n1st y,3,58\n", "line 2: 3 fields, more than the 2 columns of the header (a decimal comma?"),
        ('label,frequency_hz\n1st y,"3,58"\n', "line 2, column 'frequency_hz': not numeric: '3,58' (decimal comma? use '.')"),
        ("label;frequency_hz\n1st y;3,58\n", "line 1: columns separated by ';'?"),
        ("label\tfrequency_hz\n1st y\t3.58\n", "line 1: columns separated by tabs?"),
        ("label,frequency_hz,damping_ratio\n1st y,3.58\n", "line 2: 2 fields, fewer than the 3 columns"),
        ("frequency_hz,frequency_hz\n3.5,3.6\n", "repeated column(s) ['frequency_hz']"),
        ("frequency_hz,\n3.5,1\n", "empty column name"),
        ("frequency_hz\nnan\n", "line 2, column 'frequency_hz': not numeric: 'nan'"),
        ("frequency_hz\ninf\n", "not numeric: 'inf'"),
        ("frequency_hz\n1e400\n", "number 1e400 is outside the double-precision range"),
        ("frequency_hz\n0\n", "line 2, column 'frequency_hz': must be a finite positive number, got 0.0"),
        ("frequency_hz\n\n", "no modes (only a header line)"),
        ("label,frequency_hz\nA,\n", "line 2, column 'frequency_hz': is empty"),
        ("frequency_hz,weight_frequency\n3.5,-1\n", "column 'weight_frequency': must be a finite number >= 0, got -1.0"),
        ("frequency_hz,damping_ratio\n3.5,58\n", "column 'damping_ratio': must be a finite fraction of critical damping"),
        ("frequency_hz,shape:y,shape:x\n3.5,1.0,\n", "line 2: shape cells ['shape:x'] are empty"),
        ("frequency_hz,shape:\n3.5,1.0\n", "column 'shape:' names no DOF"),
        ("label,frequency_hz\nA,3.5\nA,4.5\n", "duplicate mode labels ['A']"),
        ("mode,frequency_hz\n1,3.5\n1,4.5\n", "column 'mode': must be a distinct mode number >= 1"),
        ('label,frequency_hz\n"A,3.5\n', "not valid CSV"),
    ],
)
def test_bad_csv_files(tmp_path, text, message):
    path = tmp_path / "m.csv"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        measurements.load(path)
    assert str(info.value).startswith(f"{path}: ") and "\n" not in str(info.value)
    assert message in str(info.value), str(info.value)


def test_csv_reads_like_the_yaml_file(tmp_path):
    (tmp_path / "m.csv").write_text(
        "mode,label,frequency_hz,frequency_std_hz,shape:y,shape:x\n"
        "1, 1st y ,3.58,0.01,1.0,0.004\n\n2,1,5.01,,0.07,1.0\n3,,7.2,,1,-0.5\n".replace(",,", ",,"))
    with pytest.raises(InputError, match="'frequency_std_hz' given for some modes but missing for modes"):
        measurements.load(tmp_path / "m.csv")
    (tmp_path / "m.csv").write_text("label,frequency_hz,shape:y,shape:x\n 1st y ,3.58,1.0,0.004\n1,5.01,0.07,1.0\n,7.2,1,-0.5\n")
    m = measurements.load(tmp_path / "m.csv")
    assert m.labels == ("1st y", "1", "mode 3") and m.dofs == ("y", "x")
    np.testing.assert_array_equal(m.frequencies_hz, [3.58, 5.01, 7.2])
    np.testing.assert_array_equal(m.shapes, [[1.0, 0.07, 1.0], [0.004, 1.0, -0.5]])


# ---- measured-modes YAML: strict values ------------------------------------------------------------------
@pytest.mark.parametrize(
    "text, message",
    [
        ("dofs: [y]\nmodes:\n  - {frequency_hz: 3.0, frequency_hz: 4.0}\n", "modes[0].frequency_hz: duplicate key"),
        ("dofs: [y]\ndofs: [x]\nmodes:\n  - {frequency_hz: 3.0}\n", "dofs: duplicate key (line 2, first given at line 1)"),
        ('dofs: "yx"\nmodes:\n  - {frequency_hz: 3.0, shape: [1.0, 0.5]}\n', "dofs: must be a list of DOF labels, got a text: 'yx'"),
        ("dofs: [1, 2]\nmodes:\n  - {frequency_hz: 3.0, shape: [1.0, 0.5]}\n", "dofs[0]: must be text, got int: 1; write it in quotes: '1'"),
        ("modes:\n  - {label: 1, frequency_hz: 3.0}\n  - {label: 1st x, frequency_hz: 4.0}\n",
         "modes[0].label: must be text, got int: 1; write it in quotes: '1'"),
        ("modes:\n  - {label: {a: 1}, frequency_hz: 3.0}\n", "modes[0].label: must be text, got a mapping"),
        ("modes:\n  - {label: true, frequency_hz: 3.0}\n", "modes[0].label: must be text, got a boolean"),
        ("modes:\n  - {label: A, frequency_hz: 3.0}\n  - {label: A, frequency_hz: 4.0}\n", "labels: duplicate mode labels ['A']"),
        ("modes:\n  - {label: mode 2, frequency_hz: 3.0}\n  - {frequency_hz: 4.0}\n", "duplicate mode labels ['mode 2']"),
        ("modes:\n  - {frequency_hz: " + "1" * 400 + "}\n", "modes[0].frequency_hz: 111111111111...(400 digits) is outside"),
        ("modes:\n  - {frequency_hz: true}\n", "modes[0].frequency_hz: not a number: True"),
        ("modes:\n  - {frequency_hz: '3.5'}\n", "modes[0].frequency_hz: not a number: '3.5'"),
        ("modes:\n  - {frequency_hz: 1e400}\n", "number 1e400 is outside the double-precision range"),
        ("dofs: [y, x]\nmodes:\n  - {frequency_hz: 3.0, shape: [1.0, true]}\n", "modes[0].shape: not a number: True"),
        ("dofs: [y, x]\nmodes:\n  - {frequency_hz: 3.0, shape: [1.0, '0.5']}\n", "modes[0].shape: not a number: '0.5'"),
        ("dofs: [y, x]\nmodes:\n  - {frequency_hz: 3.0, shape: [1.0, .nan]}\n", "modes[0].shape: must be a finite number, got nan"),
        ("dofs: [y]\nmodes:\n  - {frequency_hz: 3.0, shape: 1.0}\n", "modes[0].shape: expected a list of numbers, got float"),
        ("modes:\n  - {frequency_hz: 3.0, frequency_std_hz: -0.1}\n", "frequency_std_hz: must be a finite number >= 0, got -0.1"),
        ("modes:\n  - {frequency_hz: 3.0, frequency_std_hz: .inf}\n", "frequency_std_hz: must be a finite number >= 0, got inf"),
        ("modes:\n  - {frequency_hz: 3.0, weight_frequency: -1}\n", "weight_frequency: must be a finite number >= 0, got -1.0"),
        ("modes:\n  - {frequency_hz: 3.0, weight_shape: .nan}\n", "weight_shape: must be a finite number >= 0, got nan"),
        ("modes:\n  - {frequency_hz: 3.0, damping_ratio: 1.5}\n", "damping_ratio: must be a finite fraction of critical damping"),
        ("dofs: [y]\nmodes:\n  - {frequency_hz: 3.0, shape: [1.0], shape_std: [-0.1]}\n", "shape_std: must be a finite number >= 0"),
        ("name: [a]\nmodes:\n  - {frequency_hz: 3.0}\n", "name: must be a non-empty text, got ['a']"),
        ("meta: [1]\nmodes:\n  - {frequency_hz: 3.0}\n", "meta: must be a mapping, got a list"),
        ("units: {frequency: 1}\nmodes:\n  - {frequency_hz: 3.0}\n", "units.frequency: unsupported unit 1"),
        ("modes:\n  - " + "[" * 500 + "]" * 500 + "\n", "nesting deeper than 100 levels"),
    ],
)
def test_strict_measured_yaml(tmp_path, text, message):
    path = tmp_path / "m.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as info:
        measurements.load(path)
    assert str(info.value).startswith(f"{path}: ") and "\n" not in str(info.value)
    assert message in str(info.value), str(info.value)


def test_non_utf8_measured_file(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_bytes("modes:\n  - {label: 1ère, frequency_hz: 3.0}\n".encode("latin-1"))
    with pytest.raises(InputError, match=r"m.yaml: measured-modes file is not UTF-8 text \(byte 0xe8"):
        measurements.load(path)
    csv = tmp_path / "m.csv"
    csv.write_bytes("label,frequency_hz\n1ère,3.0\n".encode("latin-1"))
    with pytest.raises(InputError, match=r"m.csv: measured-modes file is not UTF-8 text"):
        measurements.load(csv)


def test_python_api_is_as_strict():
    with pytest.raises(InputError, match="dofs: must be a list of DOF labels, got a text: 'yx'"):
        MeasuredModes([3.0], dofs="yx", shapes=[[1.0], [0.5]])
    with pytest.raises(InputError, match="frequencies_hz: not a number: True"):
        MeasuredModes([True, 3.0])
    with pytest.raises(InputError, match="frequencies_hz: not a number: True"):
        MeasuredModes(np.array([True, False]))
    with pytest.raises(InputError, match="frequencies_hz: 100000000000...\\(401 digits\\) is outside"):
        MeasuredModes([10**400])
    with pytest.raises(InputError, match="labels\\[0\\]: must be text, got int: 1"):
        MeasuredModes([3.0, 4.0], labels=(1, "1st x"))
    with pytest.raises(InputError, match="duplicate mode labels \\['a'\\]"):
        MeasuredModes([3.0, 4.0], labels=("a", "a"))
    with pytest.raises(InputError, match="shape_std is given but there are no shapes"):
        MeasuredModes([3.0], shape_std=[[0.1]])
    with pytest.raises(InputError, match="shapes: must be real"):
        MeasuredModes([3.0], ("y",), np.array([[1.0 + 1j]]))


@pytest.mark.parametrize(
    "numbers, message",
    [
        ([0], "mode 0 does not exist: the data have 3 modes, numbered 1 to 3"),
        ([-1], "mode -1 does not exist: the data have 3 modes, numbered 1 to 3"),
        ([4], "mode 4 does not exist"),
        ([99], "mode 99 does not exist"),
        ([1, 1], "mode 1 is selected twice"),
        ([True], "True is not a mode (an integer 1 to 3)"),
        ([1.0], "1.0 is not a mode "),
        ("12", "expected a list of mode numbers, got a text"),
        ([], "no modes selected"),
    ],
)
def test_select_modes_is_one_based_and_strict(numbers, message):
    m = MeasuredModes([3.0, 4.0, 5.0], labels=("a", "b", "c"))
    with pytest.raises(InputError, match="^cfg.yaml: measured.modes: " + re.escape(message)):
        m.select_modes(numbers, where="cfg.yaml: measured.modes")
    assert m.select_modes([3, 1]).labels == ("c", "a")
    assert m.select([2, 0]).labels == ("c", "a")
    with pytest.raises(InputError, match="index -1 does not exist: the data have 3 modes, indices 0 to 2"):
        m.select([-1])


def test_repo_data_files_load_as_written():
    files = sorted([*ROOT.glob("results/identification/*_identified.yaml"), *ROOT.glob("studies/discrepancy_data/*.yaml")])
    assert len(files) >= 4
    for path in files:
        raw = yaml.safe_load(path.read_text())
        m = measurements.load(path)
        assert m.frequencies_hz.tolist() == [mode["frequency_hz"] for mode in raw["modes"]]
        assert list(m.labels) == [mode["label"] for mode in raw["modes"]] and list(m.dofs) == raw["dofs"]
        if m.shapes is not None:
            assert m.shapes.T.tolist() == [mode["shape"] for mode in raw["modes"]]
        assert m.meta == raw.get("meta", {})


def test_save_load_roundtrip_keeps_meta_and_text_labels(tmp_path):
    m = MeasuredModes([3.0, 4.0, 5.0], ("y", "x"), [[1.0, 0.1, 0.2], [0.3, 1.0, -1.0]], labels=("1e5", "yes", "010"),
                      shape_std=np.zeros((2, 3)), weight_frequency=[1.0, 0.0, 2.0],
                      meta={"seed": np.int64(3), "truth": np.array([1.5, 2.5]), "note": "on"})
    back = measurements.load(measurements.save(m, tmp_path / "m.yaml"))
    assert back.labels == m.labels and back.meta == {"seed": 3, "truth": [1.5, 2.5], "note": "on"}
    np.testing.assert_array_equal(back.shapes, m.shapes)
    np.testing.assert_array_equal(back.weight_frequency, m.weight_frequency)

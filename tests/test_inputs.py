"""Parameters and measured-modes files: loading and errors that name file, field and value."""

import numpy as np
import pytest

from framework import measurements
from framework.errors import InputError
from framework.measurements import MeasuredModes
from framework.parameters import Parameter, ParameterSet


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

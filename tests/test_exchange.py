"""Test-data exchange (issue 19): UFF mode shapes in and out, pyOMA2 results, mapping files."""

import logging
import runpy
import tempfile
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from framework.core.correlation import mac_matrix
from framework.core.errors import InputError
from framework.measured.complex_shapes import real_mode_shape
from framework.measured.load import load_measured, parse_mapping, read_uff_modes, write_uff_modes
from framework.measured.mapping import SensorDof, load_mapping, parse_sensor_dof
from framework.measured.modes import MeasuredModes
from framework.structures.lab_frame.model import ThreeDofFrame
from framework.updating.problem import UpdatingProblem

pyuff = pytest.importorskip("pyuff")

ROOT = Path(__file__).resolve().parents[1]
E13_5 = np.vectorize(lambda v: float(f"{v:.5e}"))  # what pyuff's E13.5 fields keep of a value


def _write_yaml(path, data):
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


# ------------------------------------------------------------------------- mapping files
def test_sensor_dof_grammar():
    assert parse_sensor_dof("101+x", "t") == SensorDof(101, "x", 1)
    assert parse_sensor_dof(" 7 - RZ ", "t") == SensorDof(7, "rz", -1)
    assert SensorDof(12, "ry", -1).label == "12-ry"
    for bad in ("101x", "101+w", "+x", "0+x", "x+101", 101, None, True):
        with pytest.raises(InputError, match="test DOF"):
            parse_sensor_dof(bad, "m.yaml: dofs")


@pytest.mark.parametrize(
    "data, message",
    [
        ({"dofs": {"101+x": "a", "101-x": "b"}}, r"node 101 axis x already mapped by '101\+x'"),
        ({"dofs": {"101+x": "a", "102+y": "a"}}, r"model DOF 'a' already mapped from '101\+x'"),
        ({"dofs": {"101+x": 3}}, r"dofs\['101\+x'\]: model DOF label must be a non-empty string, got 3"),
        ({"dofs": {"101": "a"}}, r"dofs\['101'\]: test DOF '101' is not <node><\+\|-><axis>"),
        ({"channels": {0: "a", 1: "-a"}}, r"channels\[1\]: model DOF 'a' already mapped from channel 0"),
        ({"channels": {-1: "a"}}, r"channel index must be >= 0, got -1"),
        ({"channels": {0: "-"}}, r"model DOF label must be a non-empty string, got ''"),
        ({"dof": {"101+x": "a"}}, r"unknown key\(s\) \['dof'\]"),
        ({"dofs": {}}, r"give a non-empty 'dofs' \(UFF\) or 'channels' \(pyOMA2\) mapping"),
        ([1, 2], r"expected a mapping with 'dofs' and/or 'channels', got list"),
    ],
)
def test_mapping_errors_name_file_key_and_value(tmp_path, data, message):
    path = _write_yaml(tmp_path / "map.yaml", data)
    with pytest.raises(InputError, match=message) as info:
        load_mapping(path)
    assert str(info.value).startswith(str(path))


def test_mapping_keeps_order_and_signs():
    m = parse_mapping({"dofs": {"102-y": "b", "101+x": "a"}, "channels": {0: "a", "acc2": "-b"}}, "m.yaml")
    assert [(s.label, d) for s, d in m.dofs] == [("102-y", "b"), ("101+x", "a")]
    assert [(c.channel, c.dof, c.sign) for c in m.channels] == [(0, "a", 1), ("acc2", "b", -1)]


_yaml_scalars = st.none() | st.booleans() | st.integers(-5, 300) | st.floats(allow_nan=True) | st.text(max_size=8)
_yaml_values = st.recursive(
    _yaml_scalars,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6) | st.integers(-2, 5), inner, max_size=3),
    max_leaves=10,
)
_dof_keys = st.from_regex(r"\A\s?[0-9]{1,3}\s?[+\-]?\s?(x|y|z|rx|ry|rz|w|X)\s?\Z") | st.text(max_size=6) | st.integers(-3, 200)
_mapping_like = st.fixed_dictionaries(
    {},
    optional={
        "dofs": st.dictionaries(_dof_keys, _yaml_scalars, max_size=4) | _yaml_values,
        "channels": st.dictionaries(st.integers(-2, 5) | st.text(max_size=4), _yaml_scalars, max_size=4) | _yaml_values,
        "extra": _yaml_values,
    },
)


@settings(max_examples=300, deadline=None)
@given(st.one_of(_mapping_like, _yaml_values))
def test_mapping_parser_raises_only_one_line_input_errors(data):
    try:
        m = parse_mapping(data, "map.yaml")
    except InputError as exc:
        assert "\n" not in str(exc) and "\r" not in str(exc) and str(exc).startswith("map.yaml")
    else:
        assert m.dofs or m.channels
        labels = [d for _, d in m.dofs]
        assert len(set(labels)) == len(labels)


@settings(max_examples=100, deadline=None)
@given(st.text(max_size=60) | st.binary(max_size=40))
def test_mapping_file_with_any_content_is_an_input_error_or_a_mapping(content):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "map.yaml"
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8")
        try:
            load_mapping(path)
        except InputError as exc:
            assert "\n" not in str(exc) and str(path) in str(exc)


# ------------------------------------------------------------------------ complex shapes
def test_complex_shape_made_real_by_rotation():
    v = np.array([1.0, -0.5, 0.25])
    real, loss = real_mode_shape(v * np.exp(0.7j))
    np.testing.assert_allclose(real, v, atol=1e-12)
    assert loss < 1e-12
    real, loss = real_mode_shape(-v * np.exp(-2.0j) + np.array([0.0, 0.3j, 0.0]))
    assert real[0] > 0 and 0.01 < loss < 0.2  # a genuinely complex mode loses MAC


# --------------------------------------------------------------------------- round trips
LAB_MAP = {"dofs": {"1+y": "y", "1-x": "x", "2+rz": "torsion"}}
LAB_GEOMETRY = {1: [0.0, 0.0, 1.0], 2: [0.325, 0.0, 1.0]}


def test_uff_round_trip_lab_frame_model_modes(tmp_path):
    model = ThreeDofFrame()
    modes = model.modal({})
    mapping = _write_yaml(tmp_path / "map.yaml", LAB_MAP)
    path = write_uff_modes(tmp_path / "lab.unv", modes, mapping, LAB_GEOMETRY, name="lab frame 3 dof")
    types = pyuff.UFF(str(path)).get_set_types().tolist()
    assert types == [164, 2411, 55, 55, 55]
    measured = load_measured(path, mapping)
    assert measured.dofs == ("y", "x", "torsion") and measured.labels == ("mode 1", "mode 2", "mode 3")
    # identical to the 6 significant digits of the E13.5 format
    np.testing.assert_array_equal(measured.frequencies_hz, E13_5(modes.frequencies_hz))
    np.testing.assert_array_equal(measured.shapes, E13_5(modes.shapes))
    np.testing.assert_allclose(measured.frequencies_hz, modes.frequencies_hz, rtol=5e-6, atol=0)
    assert measured.damping_ratio is None
    assert measured.meta["geometry_m"] == {1: [0.0, 0.0, 1.0], 2: [0.325, 0.0, 1.0]}
    assert measured.meta["test_dofs"] == ["1+y", "1-x", "2+rz"]
    # the file's own sign convention: node 1 +x holds minus the model x
    raw = pyuff.UFF(str(path)).read_sets(2)
    assert raw["r1"][0] == pytest.approx(-modes.shapes[1, 0], rel=1e-5)
    # read back as measured data: the model at the same point matches it
    table = UpdatingProblem(model, measured).mode_table(model.parameters.initial)
    assert np.all(table["mac"] > 1 - 1e-9)


def test_uff_round_trip_opensees_example_and_measured_modes(tmp_path):
    pytest.importorskip("openseespy.opensees")
    ns = runpy.run_path(str(ROOT / "examples" / "own_model.py"))
    modes = ns["model"].modal({})
    mapping = {"dofs": {"10+x": "floor1", "20-x": "floor2"}}
    path = write_uff_modes(tmp_path / "frame.uff", modes, mapping)
    back = read_uff_modes(path, mapping)
    np.testing.assert_array_equal(back.frequencies_hz, E13_5(modes.frequencies_hz))
    np.testing.assert_array_equal(back.shapes, E13_5(modes.shapes))
    # MeasuredModes (with labels and damping) round trip; test labels when no mapping is given
    measured = MeasuredModes(back.frequencies_hz, ("10+x", "20-x"), back.shapes, damping_ratio=[0.012, 0.0234],
                             labels=("bending 1", "bending 2"), name="frame test")
    again = read_uff_modes(write_uff_modes(tmp_path / "m.uff", measured))
    assert again.labels == ("bending 1", "bending 2")
    np.testing.assert_array_equal(again.damping_ratio, [0.012, 0.0234])
    assert again.dofs == ("10+x", "20+x")
    np.testing.assert_array_equal(again.shapes, back.shapes * np.array([[1.0], [-1.0]]))


# ---------------------------------------------------------------- a file written by pyuff
def _pyuff_file(path, *, complex_shapes=False, mode2_nodes=(101, 102, 103), length_factor=1000.0):
    """Three nodes in mm (dataset 164 + 15), two modes (dataset 55) written by pyuff alone."""
    shapes_m = {  # per mode: node -> (x, y, z) in metres
        1: {101: (0.010, 0.001, 0.0), 102: (0.020, -0.002, 0.0), 103: (0.0, 0.0, 0.5)},
        2: {101: (-0.002, 0.015, 0.0), 102: (0.001, 0.030, 0.0), 103: (0.0, 0.0, -0.4)},
    }
    sets = [
        pyuff.prepare_164(units_code=5, units_description="mm (milli newton)", temp_mode=1,
                          length=length_factor, force=1000.0, temp=1.0, temp_offset=273.15),
        pyuff.prepare_15(node_nums=[101, 102, 103], def_cs=[0, 0, 0], disp_cs=[0, 0, 0], color=[1, 1, 1],
                         x=[0.0, 3000.0, 6000.0], y=[0.0, 0.0, 0.0], z=[2500.0, 2500.0, 5000.0]),
    ]
    phase = {1: np.exp(0.4j), 2: np.exp(-1.1j)}
    for n, (f, zeta, name) in {1: (2.5, 0.011, "first lateral"), 2: (4.75, 0.018, "second lateral")}.items():
        nodes = [k for k in shapes_m[n] if n == 1 or k in mode2_nodes]
        r = {c: np.array([shapes_m[n][k][i] * 1000.0 for k in nodes]) for i, c in enumerate(("r1", "r2", "r3"))}
        if complex_shapes:
            r = {c: v * phase[n] for c, v in r.items()}
        sets.append(pyuff.prepare_55(
            model_type=1, id1="footbridge test", id2="run 3", id3="NONE", id4=name, id5="NONE",
            analysis_type=2, data_ch=2, spec_data_type=8, data_type=5 if complex_shapes else 2, n_data_per_node=3,
            node_nums=np.array(nodes), load_case=1, mode_n=n, freq=f, modal_m=0.0, modal_damp_vis=zeta,
            modal_damp_his=0.0, **r))
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    return path, shapes_m


BRIDGE_MAP = {"dofs": {"101+x": "deck1_x", "102+x": "deck2_x", "102-y": "deck2_y", "103+z": "pylon_z"}}


@pytest.mark.parametrize("complex_shapes", [False, True])
def test_pyuff_written_file_with_mapping_file(tmp_path, caplog, complex_shapes):
    path, truth = _pyuff_file(tmp_path / "test.unv", complex_shapes=complex_shapes)
    mapping = _write_yaml(tmp_path / "map.yaml", BRIDGE_MAP)
    with caplog.at_level(logging.INFO, logger="framework.measured"):
        m = load_measured(path, mapping)
    assert "1 measured test DOFs not in the mapping were ignored" in caplog.text  # 101+y
    np.testing.assert_allclose(m.frequencies_hz, [2.5, 4.75])
    np.testing.assert_allclose(m.damping_ratio, [0.011, 0.018])
    assert m.labels == ("first lateral", "second lateral")
    assert m.dofs == ("deck1_x", "deck2_x", "deck2_y", "pylon_z")
    expected = np.array([[truth[n][101][0], truth[n][102][0], -truth[n][102][1], truth[n][103][2]] for n in (1, 2)]).T
    if complex_shapes:  # rotated back to real; the sign of each mode is free
        expected = expected * np.sign(expected[np.argmax(np.abs(expected), axis=0), [0, 1]])
        assert max(m.meta["complex_to_real_mac_loss"]) < 1e-9
        assert "complex shape made real, MAC loss" in caplog.text
    np.testing.assert_allclose(m.shapes, expected, rtol=1e-5, atol=1e-12)  # mm -> m
    np.testing.assert_allclose(m.meta["geometry_m"][102], [3.0, 0.0, 2.5])
    assert m.meta["length_factor"] == 1000.0


def test_uff_without_mapping_keeps_every_measured_test_dof(tmp_path):
    path, _ = _pyuff_file(tmp_path / "test.uff")
    m = read_uff_modes(path)
    assert m.dofs == ("101+x", "101+y", "102+x", "102+y", "103+z")  # zero components of all modes left out


# ------------------------------------------------------------------------------- errors
def test_missing_node_names_file_dataset_mode_and_node(tmp_path):
    path, _ = _pyuff_file(tmp_path / "test.unv", mode2_nodes=(101, 102))
    with pytest.raises(InputError) as info:
        read_uff_modes(path, BRIDGE_MAP)
    assert str(info.value) == (
        f"{path}: dataset #4 (type 55, mode 2): node 103 is missing (test DOF '103+z' -> model DOF 'pylon_z')"
    )


@pytest.mark.parametrize(
    "mapping, message",
    [
        ({"dofs": {"101+rx": "a"}}, r"dataset #3 \(type 55, mode 1\): node 101: axis rx needs 6 values per node"),
        ({"dofs": {"104+x": "a"}}, r"dataset #3 \(type 55, mode 1\): node 104 is missing"),
        ({"dofs": {"103+x": "a"}}, r"node 103 axis x \(test DOF '103\+x' -> model DOF 'a'\) is zero in every mode"),
        ({"channels": {0: "a"}}, r"map: no 'dofs' section"),
    ],
)
def test_uff_mapping_errors(tmp_path, mapping, message):
    path, _ = _pyuff_file(tmp_path / "test.unv")
    mp = parse_mapping(mapping, "map")
    with pytest.raises(InputError, match=message) as info:
        read_uff_modes(path, mp)
    assert "\n" not in str(info.value)


def test_uff_file_errors(tmp_path):
    junk = tmp_path / "junk.unv"
    junk.write_text("this is not a universal file\n")
    with pytest.raises(InputError, match="junk.unv: no UFF datasets found"):
        read_uff_modes(junk)
    with pytest.raises(InputError, match="UFF file not found"):
        read_uff_modes(tmp_path / "nope.uff")
    bad_units, _ = _pyuff_file(tmp_path / "units.unv", length_factor=-1.0)
    with pytest.raises(InputError, match=r"units.unv: dataset #1 \(type 164\): length factor -1.0 must be a positive"):
        read_uff_modes(bad_units)
    frf = tmp_path / "frf.unv"
    pyuff.UFF(str(frf)).write_sets([pyuff.prepare_55(
        analysis_type=5, data_ch=2, spec_data_type=8, n_data_per_node=3, node_nums=np.array([1]), load_case=1,
        freq_step_n=1, freq=10.0, r1=np.array([1.0]), r2=np.array([0.0]), r3=np.array([0.0]))], mode="overwrite")
    with pytest.raises(InputError, match=r"frf.unv: dataset #1 \(type 55\): analysis type 5 \(frequency response\)"):
        read_uff_modes(frf)
    yaml_modes = _write_yaml(tmp_path / "m.yaml", {"dofs": ["y"], "modes": [{"frequency_hz": 3.0, "shape": [1.0]}]})
    assert load_measured(yaml_modes).frequencies_hz.tolist() == [3.0]
    with pytest.raises(InputError, match="a mapping applies to UFF files"):
        load_measured(yaml_modes, LAB_MAP)


def test_write_errors(tmp_path):
    modes = ThreeDofFrame().modal({})
    with pytest.raises(InputError, match=r"model DOF\(s\) \['floor9'\] not among the modes' DOFs"):
        write_uff_modes(tmp_path / "x.uff", modes, {"dofs": {"1+x": "floor9"}})
    with pytest.raises(InputError, match=r"no mapping given, so DOF labels must be test DOFs\): test DOF 'y' is not"):
        write_uff_modes(tmp_path / "x.uff", modes)
    assert not (tmp_path / "x.uff").exists()


# ------------------------------------------------------------------------------- pyOMA2
@pytest.fixture(scope="module")
def oma_lab_frame():
    """A 300 s ambient record of the 3-DOF lab frame (y, x, torsion b/2 channels) through pyOMA2."""
    pytest.importorskip("pyoma2")
    from pyoma2.algorithms import FDD, SSI
    from pyoma2.setup import SingleSetup

    from framework.identification.simulate import ModalSystem, add_noise, simulate

    frame = ThreeDofFrame()
    truth = frame.modal({})
    outputs = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.325]])  # rows y, x, torsion
    system = ModalSystem.from_matrices(frame.mass(), frame.stiffness({}), 0.02, np.eye(3), outputs,
                                       ("y", "x", "torsion"), ("fx", "fy", "mz"))
    rng = np.random.default_rng(7)
    record = add_noise(simulate(system, rng.standard_normal((12000, 3)) * [10.0, 10.0, 2.0], 40.0), 0.05, rng)
    record[:, 1] *= -1.0  # the x accelerometer points against the model's x axis
    setup = SingleSetup(record, fs=40.0)
    ssi, fdd = SSI(name="ssi", method="cov", br=30, ordmax=30), FDD(name="fdd", nxseg=1024)
    setup.add_algorithms(ssi, fdd)
    setup.run_all()
    setup.mpe("ssi", sel_freq=truth.frequencies_hz.tolist(), order_in=20)
    setup.mpe("fdd", sel_freq=truth.frequencies_hz.tolist())
    return truth, ssi, fdd


OMA_MAP = {"channels": {0: "y", 1: "-x", 2: "torsion"}}


def test_from_pyoma2_ssi_result(oma_lab_frame):
    from framework.measured.load import from_pyoma2

    truth, ssi, _ = oma_lab_frame
    m = from_pyoma2(ssi.result, OMA_MAP)
    assert m.dofs == ("y", "x", "torsion") and m.source == "pyOMA2 SSIResult"
    np.testing.assert_allclose(m.frequencies_hz, truth.frequencies_hz, rtol=0.01)
    assert np.all((m.damping_ratio > 0.005) & (m.damping_ratio < 0.05))
    # with the sign of channel 1 honoured, each identified shape matches its model mode
    assert np.all(np.diag(mac_matrix(truth.shapes, m.shapes)) > 0.99)
    problem = UpdatingProblem(ThreeDofFrame(), m)
    assert problem.measured.n_modes == 3
    # the '-' of channel 1 reverses the x row of every mode (up to the free sign of each mode)
    flipped = from_pyoma2(ssi, {"channels": {0: "y", 1: "x", 2: "torsion"}})
    signed = np.diag([1.0, -1.0, 1.0]) @ flipped.shapes
    np.testing.assert_allclose(np.abs(signed), np.abs(m.shapes), rtol=1e-12)
    np.testing.assert_allclose(np.diag(mac_matrix(signed, m.shapes)), 1.0, rtol=1e-12)


def test_from_pyoma2_fdd_result_and_errors(oma_lab_frame):
    from framework.measured.load import from_pyoma2

    truth, _, fdd = oma_lab_frame
    m = from_pyoma2(fdd, {"channels": {"acc_y": "y", "acc_x": "-x"}}, channel_names=["acc_y", "acc_x", "acc_t"])
    assert m.damping_ratio is None and m.dofs == ("y", "x")
    np.testing.assert_allclose(m.frequencies_hz, truth.frequencies_hz, rtol=0.02)
    with pytest.raises(InputError, match=r"channels\[5\]: channel index out of range; pyOMA2 FDDResult has 3 channels"):
        from_pyoma2(fdd, {"channels": {5: "y"}})
    with pytest.raises(InputError, match=r"channels\['acc_z'\]: unknown channel name"):
        from_pyoma2(fdd, {"channels": {"acc_z": "y"}}, channel_names=["acc_y", "acc_x", "acc_t"])
    with pytest.raises(InputError, match="no 'channels' section"):
        from_pyoma2(fdd, LAB_MAP)

"""my_frame (``my_frame.py``) as a structure with every feature: one ``StructureDescriptor``.

Without registration, a config names it ``module:DESCRIPTOR`` (run from this folder)::

    structure: {name: "my_frame_structure:MY_FRAME"}
    measured: {builtin: "my_frame_structure:MY_FRAME"}

Built in (docs/tutorials/add-a-structure.md): ``framework/structures/my_frame/`` with
``model.py`` (= my_frame.py) and ``descriptor.py`` (= this file), plus the line ``MY_FRAME,``
in ``BUILTIN`` of ``framework/structures/registry.py``; configs then say ``my_frame``.
"""

from __future__ import annotations

from pathlib import Path

import my_frame
import numpy as np

from framework.core.errors import InputError
from framework.identification.campaign import Campaign, SimulatedTest, TrueModes
from framework.identification.excitation import sine_sweep
from framework.identification.records import VibrationRecord
from framework.identification.simulate import ModalSystem, add_noise, simulate
from framework.measured.modes import MeasuredModes, load
from framework.structures.descriptor import StructureDescriptor

HERE = Path(__file__).resolve().parent

# ---- measured data ------------------------------------------------------------------------
CASES = ("base",)


def measured(case: str = "base") -> MeasuredModes:
    """The test's modes (my_modes.yaml, written by make_modes.py)."""
    if case not in CASES:
        raise InputError(f"my_frame: unknown measured case {case!r}; known: {list(CASES)}")
    return load(HERE / "my_modes.yaml")


# ---- modelling choices (the report's `choices` analysis) -----------------------------------
def modelling_choices(**_) -> list[dict]:
    """Rows item, value, origin ("source-given" or "our assumption"), reason."""
    return [
        {"item": "members", "value": "elastic beam-columns, HEB 300 columns, IPE 400 beams", "origin": "our assumption",
         "reason": "a typical office frame"},
        {"item": "mass", "value": f"{my_frame.FLOOR_MASS_KG:g} kg per floor, lumped at the beam nodes",
         "origin": "our assumption", "reason": "floor slab and finishes"},
        {"item": "sensors", "value": ", ".join(my_frame.SENSORS), "origin": "source-given", "reason": "the test"},
    ]


# ---- simulated vibration tests (the `identification` kind) -----------------------------------
#: the "true" frame of the simulated tests, its modal damping and two synchronized shakers
TRUE_THETA = {"column_stiffness_ratio": 1.03, "beam_stiffness_ratio": 0.97}
DAMPING_RATIO = 0.02
SHAKERS = ("x2", "y2")
TESTS = {"sweep": SimulatedTest(has_input=True, duration_s=60.0, f_range_hz=(1.0, 25.0))}


def truth() -> TrueModes:
    """The modes of the true frame at every sensor (mass-normalized shapes)."""
    r = my_frame.model().modal(TRUE_THETA)
    return TrueModes(r.frequencies_hz, np.full(r.n_modes, DAMPING_RATIO), r.shapes,
                     tuple(f"mode {j + 1}" for j in range(r.n_modes)), channels=r.dofs)


def record(test: str, seed: int, *, duration_s: float, sampling_hz: float, output_noise: float,
           input_noise: float | None, f_range_hz) -> VibrationRecord:
    """A shaker sweep: one force signal drives both shakers; accelerations at every sensor."""
    t = truth()
    gamma = t.shapes[[t.channels.index(s) for s in SHAKERS]].sum(axis=0)[:, None]
    system = ModalSystem(t.f_hz, t.zeta, gamma, t.shapes, t.channels, ("force",))
    u = sine_sweep(duration_s, sampling_hz, *f_range_hz, 1000.0)
    rng = np.random.default_rng(seed)
    y = simulate(system, u[:, None], sampling_hz)
    return VibrationRecord(np.arange(u.size) / sampling_hz, add_noise(y, output_noise, rng), t.channels,
                           add_noise(u[:, None], input_noise or 0.0, rng), ("force",), f"my_frame_{test}_{seed}",
                           {"structure": "my_frame", "kind": test, "seed": seed})


def campaign() -> Campaign:
    return Campaign("my_frame", TESTS, record, truth)


def identified_sweep() -> MeasuredModes:
    """The modes N4SID identifies from one simulated sweep (``measured: {builtin: identified, case: my_frame}``)."""
    from framework.identification import pipeline as pl

    rec = campaign().simulate("sweep", seed=1, duration_s=60.0, sampling_hz=200.0, output_noise=0.02,
                              input_noise=0.01)
    settings = pl.IdentificationSettings(orders=tuple(range(8, 31, 2)), block_rows=20, decimate=4, mac_min=0.9,
                                         band_hz=(1.0, 25.0))
    return pl.to_measured_modes(pl.identify(rec, settings).selected, "my_frame_identified")


# ---- reproduction report (docs/reproduction.md, when registered) -----------------------------
def reproduction_rows(results_dir: Path) -> list[dict]:
    """One row: the updated column stiffness ratio (results/my_frame/parameters.csv) against the test's truth."""
    from framework.report.reproduction import fmt, missing, read_table

    study, item = "My frame", "column stiffness ratio"
    source = f"the simulated test's frame: {TRUE_THETA['column_stiffness_ratio']}"
    table = read_table(results_dir, "my_frame/parameters.csv")
    if table is None:
        return [missing(study, item, source, "my_frame/parameters.csv")]
    value = table[table["parameter"] == "column_stiffness_ratio"]["value"].median()
    close = abs(value / TRUE_THETA["column_stiffness_ratio"] - 1) < 0.02
    return [{"study": study, "item": item, "source": source, "ours": fmt(value), "choice": "source-given",
             "verdict": "within 2 %" if close else "differs: the tested frame has an infill strut the model "
                                                   "lacks (gomu diagnose names it)"}]


MY_FRAME = StructureDescriptor(
    name="my_frame",
    title="two-storey one-bay steel frame, OpenSeesPy (examples/diagnosis)",
    make_model=my_frame.model,
    measured=measured,
    cases=CASES,
    effects=my_frame.catalogue,
    geometry=None,  # an OpenSeesModel: drawn from its built domain
    reproduction=reproduction_rows,
    tests=campaign,
    modelling_choices=modelling_choices,
    identified={"my_frame": identified_sweep},
)

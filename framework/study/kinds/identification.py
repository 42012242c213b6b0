"""Run kind ``identification``: simulated vibration tests identified by one method.

A study lists ``tests`` (name -> structure, test, methods, record settings, method
settings). One run is one (test, method) with its records: the records of a test are
repeated tests with consecutive seeds, averaged by the method (peak picking: the H1 over
the records; N4SID / SSI-cov: each record identified, then the mean of the identifications),
so they belong to one run. ``runs: n`` repeats a whole test with new seeds (noise
realizations); run i of a test with r records uses the seeds seed + i r ... seed + i r + r - 1.

Methods: ``n4sid`` (input-output subspace), ``ssi_cov`` (output-only covariance SSI; free
decays use biased correlations), ``peak_picking`` (H1 FRF peaks). Every identified mode is
compared with the true modes of the simulating model (see :mod:`framework.identification`).

Tables (columns in :mod:`framework.identification.rows`): ``runs`` (one row per run:
status ok/failed/error, n_records, n_modes, n_true, n_found, input_channel, wall_s),
``modes``, ``identified``, ``shapes``, ``stability``, ``peaks``, ``frf``. Every setting is
a typed column: structure, test, method, records, duration_s, sampling_hz, output_noise,
input_noise, f_start_hz, f_end_hz (sweeps), component; subspace: orders_min, orders_max,
orders_step, block_rows, decimate, band_min_hz, band_max_hz, freq_tol, mac_min,
damping_max, min_fraction, max_spread, mpc_min; peak picking: band_min_hz, band_max_hz,
min_coherence, min_phase_change_deg, phase_window, prominence, n_segments, overlap,
frf_f_max_hz, frf_channels, frf_max_lines.

Derived (from the tables, ``gomu report`` redoes them): ``accuracy`` (per run and record:
true modes found, spurious modes, largest frequency and damping errors, smallest MAC), the
figures of :mod:`framework.report.figures.identification`, and the measured-modes files asked for
in ``report.export`` (:mod:`framework.identification.export`).
"""

from __future__ import annotations

import json
import time
from typing import Annotated, Any, Literal

import numpy as np
import pandas as pd
from pydantic import AfterValidator, Field, StrictBool, StrictInt, field_validator, model_validator

from framework.core.errors import InputError
from framework.core.status import Status
from framework.study.kinds.base import Kind, failure
from framework.study.schema import MAX_RUNS_PER_ENTRY, NAME_PATTERN, Strict, StudyHeader

TABLES = ("runs", "modes", "identified", "shapes", "stability", "peaks", "frf")
METHODS = ("n4sid", "ssi_cov", "peak_picking")
INPUT_METHODS = ("n4sid", "peak_picking")


# ---- schema ------------------------------------------------------------------------------
def _check_band(b: list[float]) -> list[float]:
    if len(b) != 2 or not all(np.isfinite(b)) or not 0 <= b[0] < b[1]:
        raise ValueError(f"a band is [low, high] with 0 <= low < high, in Hz, got {b}")
    return b


Band = Annotated[list[float], AfterValidator(_check_band)]


class OrderRange(Strict):
    """Model orders min, min + step, ..., <= max of the stability sweep."""

    min: StrictInt = Field(ge=1)
    max: StrictInt = Field(le=1000)
    step: StrictInt = Field(2, ge=1)

    @model_validator(mode="after")
    def _two_orders(self):
        if len(self.values()) < 2:
            raise ValueError(f"orders from {self.min} to {self.max} by {self.step} give fewer than two orders")
        return self

    def values(self) -> list[int]:
        return list(range(self.min, self.max + 1, self.step))


class SubspaceConfig(Strict):
    """N4SID / SSI-cov: model orders, block rows, decimation and the stability criteria."""

    orders: OrderRange
    block_rows: StrictInt = Field(ge=2, le=1000)
    decimate: StrictInt = Field(1, ge=1, le=1000)
    #: modes outside the band are not physical; default 0 to 0.45 x the decimated rate
    band_hz: Band | None = None
    freq_tol: float = Field(0.01, gt=0, lt=1)
    mac_min: float = Field(0.9, ge=0, le=1)
    damping_max: float = Field(0.2, gt=0, lt=1)
    min_fraction: float = Field(0.5, gt=0, le=1)
    max_spread: float = Field(0.0025, gt=0)
    mpc_min: float = Field(0.5, ge=0, le=1)


class PeakPickingConfig(Strict):
    """H1 (Welch) and the acceptance rules of the peaks; what the ``frf`` table stores."""

    band_hz: Band | None = None
    min_coherence: float = Field(0.8, ge=0, le=1)
    min_phase_change_deg: float = Field(120.0, ge=0, le=180)
    phase_window: float = Field(0.05, gt=0, lt=1)
    prominence: float = Field(0.05, ge=0, le=1)
    n_segments: StrictInt = Field(5, ge=1, le=1000)
    overlap: float = Field(0.5, ge=0, lt=1)
    #: FRF lines stored up to this frequency (default: the band's upper limit)
    frf_f_max_hz: float | None = Field(None, gt=0)
    #: channels stored: "peaks" (strongest at each peak), "all", or a list of names
    frf_channels: Literal["peaks", "all"] | list[str] = "peaks"
    #: at most about this many lines stored outside the peaks (min-max decimation)
    frf_max_lines: StrictInt = Field(300, ge=10, le=1_000_000)


class SimulatedTestConfig(Strict):
    #: a structure with simulated tests (its descriptor's ``tests``): lab_frame, bridge
    structure: str
    test: str
    methods: list[Literal["n4sid", "ssi_cov", "peak_picking"]] = Field(min_length=1)
    #: seed of the first record (default: the study's seed)
    seed: StrictInt | None = Field(None, ge=0, le=2**32 - 1)
    #: repeated records of the test (consecutive seeds)
    records: StrictInt = Field(1, ge=1, le=1000)
    duration_s: float | None = Field(None, gt=0, le=86_400)
    sampling_hz: float = Field(200.0, gt=0, le=100_000)
    #: sensor noise: standard deviation as a fraction of each channel's RMS
    output_noise: float = Field(0.02, ge=0, le=10)
    input_noise: float = Field(0.01, ge=0, le=10)
    f_range_hz: Band | None = None
    #: channels identified: "all" or a DOF suffix (bridge: uz, uy); default: the test's
    component: str | None = None
    subspace: SubspaceConfig | None = None
    peak_picking: PeakPickingConfig = Field(default_factory=PeakPickingConfig)

    @model_validator(mode="after")
    def _consistent(self):
        from framework.structures.registry import campaign

        try:
            tests = campaign(self.structure)
            tt = tests.test(self.test)
        except InputError as exc:
            raise ValueError(str(exc)) from None
        if len(set(self.methods)) != len(self.methods):
            raise ValueError(f"methods are repeated: {self.methods}")
        needs_input = [m for m in self.methods if m in INPUT_METHODS]
        if needs_input and not tt.has_input:
            raise ValueError(f"methods {needs_input} need a measured input; test {self.test!r} is output only "
                             "(use ssi_cov)")
        if self.subspace is None and any(m in ("n4sid", "ssi_cov") for m in self.methods):
            raise ValueError("subspace: settings (orders, block_rows, ...) are required for n4sid and ssi_cov")
        if self.f_range_hz is not None:
            if tt.f_range_hz is None:
                raise ValueError(f"f_range_hz: test {self.test!r} is not a sweep")
            if self.f_range_hz[1] >= self.sampling_hz / 2:
                raise ValueError(f"f_range_hz: {self.f_range_hz} reaches the Nyquist frequency {self.sampling_hz / 2}")
        if self.component is not None and self.component not in tests.components:
            raise ValueError(f"component: {self.component!r} is not one of "
                             f"{list(tests.components)} for {self.structure}")
        # defaults of the test type, written out so that they are columns and part of the task
        if self.duration_s is None:
            self.duration_s = tt.duration_s
        if self.f_range_hz is None and tt.f_range_hz is not None:
            self.f_range_hz = list(tt.f_range_hz)
        if self.component is None:
            self.component = tt.component
        return self


class ExportConfig(Strict):
    label: str
    method: Literal["n4sid", "ssi_cov", "peak_picking"] = "n4sid"
    #: record exported (default: "mean" when the test has several records, else its record)
    record: str | None = None
    true_labels: StrictBool = False


class ReportConfig(Strict):
    """The ``report`` section: measured-modes files written from the identified modes."""

    export: dict[str, ExportConfig] = Field(default_factory=dict)

    @field_validator("export")
    @classmethod
    def _file_names(cls, v):
        for name in v:
            if not NAME_PATTERN.match(name):
                raise ValueError(f"file name {name!r} must be letters, digits and _ . + -")
        return v


class Config(StudyHeader):
    kind: Literal["identification"] = "identification"
    runs: StrictInt = Field(1, ge=1, le=MAX_RUNS_PER_ENTRY)
    tests: dict[str, SimulatedTestConfig]

    @field_validator("tests")
    @classmethod
    def _names(cls, v):
        if not v:
            raise ValueError("at least one test is required")
        for name in v:
            if not NAME_PATTERN.match(name):
                raise ValueError(f"test name {name!r} must be letters, digits and _ . + -")
        return v



def check(cfg: Config, source: str, base_dir=None) -> None:
    """Every exported test and method exists."""
    for name, ex in ReportConfig.model_validate(cfg.report).export.items():
        test = cfg.tests.get(ex.label)
        if test is None:
            raise InputError(f"{source}: report.export.{name}.label: no test {ex.label!r}; tests: {sorted(cfg.tests)}")
        if ex.method not in test.methods:
            raise InputError(f"{source}: report.export.{name}.method: test {ex.label!r} has no method {ex.method!r}")


# ---- plan --------------------------------------------------------------------------------
def _band(settings: dict, default: tuple[float, float]) -> list[float]:
    return list(settings["band_hz"]) if settings.get("band_hz") is not None else list(default)


def method_settings(test: SimulatedTestConfig, method: str) -> dict[str, Any]:
    """The settings of ``method`` for ``test``, with the band and the FRF range resolved."""
    if method == "peak_picking":
        s = test.peak_picking.model_dump(mode="json")
        s["band_hz"] = _band(s, (0.0, test.sampling_hz / 2))
        s["frf_f_max_hz"] = s["frf_f_max_hz"] or s["band_hz"][1]
        return s
    s = test.subspace.model_dump(mode="json")
    s["band_hz"] = _band(s, (0.0, 0.45 * test.sampling_hz / test.subspace.decimate))
    return s


#: the setting columns, in this order in every table (None where a setting does not apply)
SETTING_COLUMNS = (
    "structure", "test", "method", "records", "duration_s", "sampling_hz", "output_noise", "input_noise", "f_start_hz",
    "f_end_hz", "component", "band_min_hz", "band_max_hz",
    "orders_min", "orders_max", "orders_step", "block_rows", "decimate", "freq_tol", "mac_min", "damping_max",
    "min_fraction", "max_spread", "mpc_min",
    "min_coherence", "min_phase_change_deg", "phase_window", "prominence", "n_segments", "overlap", "frf_f_max_hz",
    "frf_channels", "frf_max_lines",
)


def setting_columns(task: dict) -> dict[str, Any]:
    """Every setting of a run as a typed scalar column (None where it does not apply)."""
    cols: dict[str, Any] = {"structure": task["structure"], "test": task["test"], "method": task["method"],
                            "records": len(task["record_seeds"]), "duration_s": task["duration_s"],
                            "sampling_hz": task["sampling_hz"], "output_noise": task["output_noise"]}
    if task["input_noise"] is not None:
        cols["input_noise"] = task["input_noise"]
    if task["f_range_hz"] is not None:
        cols["f_start_hz"], cols["f_end_hz"] = task["f_range_hz"]
    cols["component"] = task["component"]
    s = dict(task["settings"])
    cols["band_min_hz"], cols["band_max_hz"] = s.pop("band_hz")
    if "orders" in s:
        orders = s.pop("orders")
        cols.update({"orders_min": orders["min"], "orders_max": orders["max"], "orders_step": orders["step"]})
    if isinstance(s.get("frf_channels"), list):
        s["frf_channels"] = ",".join(s["frf_channels"])
    cols.update(s)
    return {**{k: cols.get(k) for k in SETTING_COLUMNS}, **cols}


def plan_runs(cfg: Config, sweep_values: dict[str, Any]) -> list[dict]:
    """One run per test, method and repetition; the task holds everything the run needs."""
    from framework.structures.registry import campaign

    parts = []
    for label, test in cfg.tests.items():
        tt = campaign(test.structure).test(test.test)
        first = cfg.seed if test.seed is None else test.seed
        for method in test.methods:
            other = "subspace" if method == "peak_picking" else "peak_picking"
            relevant = [k for k in sweep_values if not k.startswith("tests.")
                        or (k.startswith(f"tests.{label}.") and not k.startswith(f"tests.{label}.{other}."))]
            for i in range(cfg.runs):
                seeds = [first + i * test.records + j for j in range(test.records)]
                task = {
                    "structure": test.structure, "test": test.test, "method": method, "record_seeds": seeds,
                    "duration_s": test.duration_s, "sampling_hz": test.sampling_hz,
                    "output_noise": test.output_noise, "input_noise": test.input_noise if tt.has_input else None,
                    "f_range_hz": test.f_range_hz, "component": test.component,
                    "settings": method_settings(test, method),
                }
                parts.append({"label": label, "seed": seeds[0], "task": task, "columns": setting_columns(task),
                              "relevant": relevant})
    return parts


def preflight(spec: dict, build_references: bool = True) -> None:
    """Channels named in ``peak_picking.frf_channels`` exist (InputError before any run)."""
    from framework.structures.registry import campaign

    task = spec["task"]
    names = task["settings"].get("frf_channels")
    if not isinstance(names, list):
        return
    known = campaign(task["structure"]).channels(task["component"])
    unknown = [c for c in names if c not in known]
    if unknown:
        raise InputError(f"tests.{spec['label']}.peak_picking.frf_channels: {unknown} are not channels of "
                         f"{task['structure']} (component {task['component']}): {list(known)}")


def channels_key(spec: dict) -> str:
    task = spec["task"]
    return json.dumps([task["structure"], task["component"], task["settings"].get("frf_channels")])


# ---- one run -----------------------------------------------------------------------------
def run(spec: dict) -> dict[str, list[dict]]:
    """Simulate the records of one test, identify them with one method, compare with the truth."""
    from framework.structures.registry import campaign

    task = spec["task"]
    tables: dict[str, list[dict]] = {t: [] for t in TABLES}
    t0 = time.perf_counter()
    tests = campaign(task["structure"])
    tt = tests.test(task["test"])
    summary = {"status": Status.OK, "error": "", "n_records": len(task["record_seeds"])}
    try:
        records = [tests.simulate(task["test"], seed, task["duration_s"], task["sampling_hz"], task["output_noise"],
                                  task["input_noise"], task["f_range_hz"], task["component"])
                   for seed in task["record_seeds"]]
        truth = tests.true_modes(records[0].output_labels, task["settings"]["band_hz"], task["component"])
        if task["method"] == "peak_picking":
            final = _peak_picking(records, truth, task["settings"], tables)
        else:
            final = _subspace(records, truth, task["method"], task["settings"], tt.free_decay, tables)
    except (InputError, ValueError, np.linalg.LinAlgError) as exc:  # e.g. a record too short for the block rows
        summary.update(failure(exc))
        tables = {t: [] for t in TABLES}
    else:
        found = [r for r in tables["modes"] if r["record"] == final and r["mode_label"] != "spurious"]
        n_modes = sum(r["record"] == final for r in tables["identified"])
        summary.update(n_modes=n_modes, n_true=len(found), n_found=sum(r["stable"] == "yes" for r in found),
                       input_channel=",".join(records[0].input_labels))
        if n_modes == 0:
            summary.update(failure("no mode identified"))
    tables["runs"] = [{**summary, "wall_s": time.perf_counter() - t0}]
    return tables


def _compare(record: str, selected, truth, tables: dict) -> None:
    from framework.identification import pipeline as pl
    from framework.identification import rows

    cmp = pl.compare_to_truth(selected, truth.f_hz, truth.zeta, truth.shapes, truth.labels)
    tables["modes"] += rows.mode_rows(record, cmp, truth.deck_energy)
    tables["identified"] += rows.identified_rows(record, selected, cmp)
    tables["shapes"] += rows.shape_rows(record, selected)


def _subspace(records, truth, method: str, s: dict, free_decay: bool, tables: dict) -> str:
    """Identify every record, then their mean; returns the name of the final record."""
    from framework.identification import pipeline as pl
    from framework.identification import rows

    settings = pl.IdentificationSettings(
        method=method, orders=tuple(range(s["orders"]["min"], s["orders"]["max"] + 1, s["orders"]["step"])),
        block_rows=s["block_rows"], decimate=s["decimate"], freq_tol=s["freq_tol"], mac_min=s["mac_min"],
        damping_max=s["damping_max"], band_hz=tuple(s["band_hz"]), min_fraction=s["min_fraction"],
        max_spread=s["max_spread"], mpc_min=s["mpc_min"], free_decay=free_decay)
    selected = []
    for rec in records:
        ident = pl.identify(rec, settings)
        tables["stability"] += rows.stability_rows(rec.name, ident.stability)
        _compare(rec.name, ident.selected, truth, tables)
        selected.append(ident.selected)
    if len(records) == 1:
        return records[0].name
    _compare("mean", pl.average_identifications(selected), truth, tables)
    return "mean"


def _peak_picking(records, truth, s: dict, tables: dict) -> str:
    """Peaks of the H1 averaged over the records; returns the name of the (averaged) record."""
    from framework.identification import pipeline as pl
    from framework.identification import rows

    frf, peaks, selected = pl.peak_picking(
        records, band_hz=tuple(s["band_hz"]), n_segments=s["n_segments"], overlap=s["overlap"],
        min_coherence=s["min_coherence"], min_phase_change_deg=s["min_phase_change_deg"],
        phase_window=s["phase_window"], prominence=s["prominence"])
    record = records[0].name if len(records) == 1 else "average"
    tables["peaks"] += rows.peak_rows(record, peaks)
    tables["frf"] += rows.frf_rows(record, frf, rows.frf_channels(s["frf_channels"], frf, peaks), s["frf_f_max_hz"],
                                   peaks["frequency_hz"].tolist(), s["frf_max_lines"])
    _compare(record, selected, truth, tables)
    return record


# ---- analyses, figures, exported files ---------------------------------------------------
def accuracy(modes: pd.DataFrame) -> pd.DataFrame:
    """Per run and record: true modes, found, spurious; max |f error| (%), max |zeta error|
    (%), min MAC over the found modes."""
    if modes is None or modes.empty or "record" not in modes:
        return pd.DataFrame()
    keys = [c for c in ("label", "variant", "seed", "structure", "test", "method", "record") if c in modes]
    out = []
    for key, g in modes.groupby(keys, sort=False):
        true = g[g["mode_label"] != "spurious"]
        found = true[true["stable"] == "yes"]
        out.append({**dict(zip(keys, key)), "n_true": len(true), "n_found": len(found),
                    "n_spurious": int((g["mode_label"] == "spurious").sum()),
                    "max_abs_f_error_pct": found["f_error_pct"].abs().max(),
                    "max_abs_zeta_error_pct": found["zeta_error_pct"].abs().max(),
                    "min_mac": found["mac_to_true"].min()})
    order = [k for k in ("label", "variant", "seed", "method") if k in keys]
    return pd.DataFrame(out).sort_values(order, kind="stable").reset_index(drop=True)


def analyses(tables: dict, report: dict) -> dict:
    return {"accuracy": accuracy(tables.get("modes"))}


def figures(tables: dict, out_dir, report: dict) -> list:
    """The stability and FRF figures, and the measured-modes files of ``report.export``."""
    from framework.identification.export import export_files
    from framework.report.figures.identification import frf_figures, stability_figures

    export = {k: v.model_dump() for k, v in ReportConfig.model_validate(report).export.items()}
    return stability_figures(tables, out_dir) + frf_figures(tables, out_dir) + export_files(tables, out_dir, export)


KIND = Kind(
    name="identification", config=Config, tables=TABLES, plan_runs=plan_runs, run=run, check=check,
    preflight=preflight, preflight_key=channels_key, report=ReportConfig, analyses=analyses, figures=figures,
)

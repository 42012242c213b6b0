"""Run kind ``diagnose``: one run is one diagnosis of model-form discrepancy (SPEC 9).

A run calibrates the model under test of a structure's effect catalogue to measured modes
(a file, a built-in data set, or data generated with hidden effects), tests the residuals,
names the missing effect, adds it and repeats (:func:`framework.diagnosis.workflow.diagnose`).
Example (one diagnosis; ``gomu diagnose`` or ``gomu run``)::

    study: lab_two_effects
    kind: diagnose
    structure: lab_frame              # a catalogue: beam, lab_frame, bridge, frame_two_bay, or module:function
    measured:                         # exactly one of file / builtin / generate
      generate: {hidden: {semi_rigid_joints: null, sensor_mass_eccentricity: null}, noise: high}
    seed: 2                           # the data's seed when generate gives none
    settings: {n_starts: 2, max_evaluations: 150}

A study of many diagnoses sweeps the data (``variants``: structure and hidden effects;
``sweep``: ``measured.generate.noise``, ``measured.generate.magnitude``; ``runs``: seeds);
see ``studies/discrepancy.yaml``. A magnitude changes nothing when the hidden effects have
no free parameter (or none at all): such runs are planned once, with magnitude 1.

Tables (:mod:`framework.diagnosis.tables`): ``summary`` (one row per run, with ``status``
"ok" or "failed" (:class:`framework.core.status.Status`), ``error``, ``wall_s``, ``n_evaluations``, and every workflow
setting as a column), ``rounds``, ``candidates``, ``modes``, ``parameters``, ``comac``.
Every table carries the columns ``structure`` and, for generated data, ``hidden_effect``,
``magnitude`` and ``noise``.

Report options (``report:``; they never change a run): ``outcomes: true`` derives the
``cases`` and ``rates`` tables (:mod:`framework.diagnosis.outcomes`) and ``study.png``;
``showcase_seeds: [1]`` draws ``showcase/<case>.png`` for every run of those seeds. A study of
one run draws ``discrepancy.png``.

Runs execute serially, on processes or on Dask (``execution.backend``); a diagnosis's
own calibrations evaluate the model in the run's process (``execution.evaluation_backend``
and ``isolate`` do not apply to this kind).
"""

from __future__ import annotations

import functools
import hashlib
import json
import logging
import time
from pathlib import Path
from typing import Any, Literal

from pydantic import (
    Field,
    StrictBool,
    StrictInt,
    field_serializer,
    field_validator,
    model_validator,
)

from framework.core.errors import InputError, ModelEvaluationError
from framework.core.status import Status
from framework.diagnosis.auto import with_candidates
from framework.diagnosis.effects import Catalogue
from framework.diagnosis.score import NO_CHANGE
from framework.diagnosis.tables import TABLES, diagnosis_rows
from framework.diagnosis.workflow import DiagnoseSettings, diagnose
from framework.structures import registry
from framework.structures.registry import check_reference
from framework.study.kinds.base import Kind, failure, task_key
from framework.study.kinds.diagnose_measured import MeasuredSource, data_seed, measured_of, noise_of, source_kind
from framework.study.schema import MAX_RUNS_PER_ENTRY, Strict, StudyHeader

log = logging.getLogger(__name__)

__all__ = ["KIND", "TABLES", "Config", "analyses", "check", "figures", "identity", "plan_runs", "preflight",
           "run"]  # fmt: skip

#: where ``gomu diagnose`` writes a legacy config (``name:`` instead of ``study:``)
LEGACY_ROOT = "results/discrepancy"


# ---- schema ------------------------------------------------------------------------------
class ReportConfig(Strict):
    """The ``report`` section (module docstring)."""

    outcomes: StrictBool = False
    showcase_seeds: list[StrictInt] = Field(default_factory=list)


class Config(StudyHeader):
    kind: Literal["diagnose"] = "diagnose"
    runs: StrictInt = Field(1, ge=1, le=MAX_RUNS_PER_ENTRY)
    structure: str = Field(min_length=1)
    structure_options: dict[str, Any] = Field(default_factory=dict)
    #: effects already in the model under test {name: variant ("" or null if it has none)}
    start_effects: dict[str, str | None] = Field(default_factory=dict)
    measured: MeasuredSource
    #: candidate effects: "catalogue" (the hand-written ones), "auto" (generated from the
    #: OpenSees model, :mod:`framework.diagnosis.auto`), or a list of names ("auto" = all generated)
    candidates: Literal["catalogue", "auto"] | list[str] = "catalogue"
    #: workflow settings; those left out take the catalogue's recommendation, else the default
    settings: DiagnoseSettings = Field(default_factory=DiagnoseSettings)

    @model_validator(mode="before")
    @classmethod
    def _legacy_name(cls, data):
        """A ``gomu diagnose`` config of earlier versions names its case with ``name:`` and
        writes to results/discrepancy/<name>."""
        if isinstance(data, dict) and "name" in data and "study" not in data:
            data = dict(data)
            name = data.pop("name")
            data["study"] = name
            if isinstance(name, str):
                data.setdefault("output", f"{LEGACY_ROOT}/{name}")
        return data

    @field_validator("structure")
    @classmethod
    def _catalogue_or_user_reference(cls, v: str) -> str:
        """A built-in catalogue, or ``module:function`` of a user module (returning a
        ``Catalogue`` or an ``OpenSeesModel``): checked by form here, imported only when the
        study runs or ``gomu validate --build`` asks (the trust model in the README)."""
        if v in registry.CATALOGUES:
            return v
        if ":" not in v:
            raise ValueError(f"structure {v!r} has no effect catalogue; known: {sorted(registry.CATALOGUES)} "
                             "or 'module:function' of your own model")
        try:
            check_reference(v, "structure")
        except InputError as exc:
            raise ValueError(str(exc).removeprefix("structure: ")) from None
        return v

    @field_serializer("settings")
    def _explicit_settings(self, settings: DiagnoseSettings) -> dict:
        """Only the settings the config gives (so variants and config.yaml keep the rest open)."""
        return settings.model_dump(mode="json", exclude_unset=True)

    @model_validator(mode="after")
    def _seeded_runs(self):
        uses_seed = self.measured.generate is not None and self.measured.generate.seed is None
        if self.runs > 1 and not uses_seed:
            where = "measured.generate.seed is given" if self.measured.generate is not None else "the data are fixed"
            raise ValueError(f"runs: {self.runs} runs would repeat one diagnosis ({where}; only generated data "
                             "without their own seed change with the run's seed); use runs: 1")
        return self


def check(cfg: Config, source: str, base_dir: Path | None = None) -> None:
    """Resolve the data file's path (relative to the config's folder if not found as given)."""
    if cfg.measured.file is None:
        return
    path = Path(cfg.measured.file)
    if not path.is_absolute() and not path.exists() and base_dir is not None and (base_dir / path).exists():
        path = base_dir / path
    if not path.exists():
        raise InputError(f"{source}: measured.file: file not found: {cfg.measured.file}")
    if path.is_dir():
        raise InputError(f"{source}: measured.file: is a folder, not a data file: {cfg.measured.file}")
    cfg.measured.file = str(path)


# ---- plan --------------------------------------------------------------------------------
@functools.lru_cache(maxsize=16)
def _catalogue(structure: str, options_json: str, candidates_json: str) -> Catalogue:
    return with_candidates(registry.catalogue(structure, **json.loads(options_json)), json.loads(candidates_json))


def catalogue_of(task: dict) -> Catalogue:
    return _catalogue(task["structure"], json.dumps(task["structure_options"], sort_keys=True),
                      json.dumps(task.get("candidates", "catalogue")))  # fmt: skip


def plan_runs(cfg: Config, sweep_values: dict[str, Any]) -> list[dict]:
    """``runs`` diagnoses (seeds ``seed``, ``seed + 1``, ...); the task holds the resolved settings."""
    task = {
        "structure": cfg.structure,
        "structure_options": cfg.structure_options,
        "start_effects": {k: v or "" for k, v in cfg.start_effects.items()},
        "measured": cfg.measured.model_dump(mode="json"),
        "candidates": cfg.candidates,
    }
    relevant = list(sweep_values)
    explicit = cfg.settings.model_dump(exclude_unset=True)
    if not _trusted(cfg.structure):
        # a user's module is imported only when runs (or validate --build) need it: its
        # recommended settings are merged then, and every magnitude is planned
        task["settings"] = None
        task["explicit_settings"] = cfg.settings.model_dump(mode="json", exclude_unset=True)
    else:
        try:
            catalogue = catalogue_of(task)
            # the catalogue's recommended settings, overridden by those the config gives
            settings = DiagnoseSettings(**(dict(catalogue.settings) | explicit))
            gen = task["measured"]["generate"]
            if gen is not None and not _magnitude_matters(catalogue, gen):
                gen["magnitude"] = 1.0
                relevant = [k for k in relevant if k != "measured.generate.magnitude"]
        except InputError as exc:
            raise InputError(f"study {cfg.study!r}: {exc}") from None
        task["settings"] = settings.model_dump(mode="json")
    columns = run_columns(task)
    return [{"label": cfg.structure, "seed": cfg.seed + i, "task": task, "columns": columns, "relevant": relevant}
            for i in range(cfg.runs)]  # fmt: skip


def _trusted(structure: str) -> bool:
    """Not a user's ``module:function``: a built-in name (or an unknown one, refused when planned),
    or a catalogue in the framework's own modules (planned by importing it)."""
    return ":" not in structure or structure.startswith("framework.")


def settings_of(task: dict, catalogue: Catalogue) -> dict:
    """The run's resolved workflow settings (a user's catalogue: its recommendation + the config's)."""
    if task.get("settings") is not None:
        return task["settings"]
    explicit = task.get("explicit_settings") or {}
    return DiagnoseSettings(**(dict(catalogue.settings) | explicit)).model_dump(mode="json")


def _magnitude_matters(catalogue: Catalogue, gen: dict) -> bool:
    """True when some hidden effect has a parameter whose value is drawn (and so scaled)."""
    return any(p.name not in gen["values"] for e in gen["hidden"] for p in catalogue.effect(e).parameters)


def hidden_name(gen: dict) -> str:
    return "+".join(gen["hidden"]) or NO_CHANGE


def run_columns(task: dict) -> dict[str, Any]:
    """The settings that tell runs apart, as columns of every table."""
    columns: dict[str, Any] = {"structure": task["structure"]}
    gen = task["measured"]["generate"]
    if gen is not None:
        noise = gen["noise"]
        columns |= {"hidden_effect": hidden_name(gen), "magnitude": float(gen["magnitude"]),
                    "noise": noise if isinstance(noise, str) else "custom",
                    "data_stds": bool(gen.get("stds", True))}  # fmt: skip
    candidates = task.get("candidates", "catalogue")
    columns["candidates"] = candidates if isinstance(candidates, str) else "+".join(candidates)
    return columns


def identity(task: dict) -> dict:
    """The task with a data file replaced by a hash of its content."""
    measured = task["measured"]
    if not measured.get("file"):
        return task
    try:
        digest = hashlib.sha256(Path(measured["file"]).read_bytes()).hexdigest()
    except OSError:
        digest = f"unreadable:{measured['file']}"
    return {**task, "measured": {**{k: v for k, v in measured.items() if k != "file"}, "file_sha256": digest}}


def preflight(spec: dict, build_references: bool = True) -> None:
    """Check the run's catalogue, start model and data source before any run starts."""
    task = spec["task"]
    if not (build_references or _trusted(task["structure"])):
        return  # a user's module is imported only with build_references (gomu validate --build, runs)
    builtin = task["measured"].get("builtin") or ""
    if not build_references and ":" in builtin:  # gomu validate imports no code named in the config
        check_reference(builtin, f"measured.builtin={builtin!r}")
        return
    _check_task(task)


def input_key(spec: dict) -> str:
    return task_key(spec, ("structure", "structure_options", "start_effects", "measured", "candidates"))


def _check_task(task: dict) -> None:
    from framework.diagnosis.calibrate import gaussian_spec
    from framework.inference.noise import data_noise, with_stds
    from framework.updating.problem import UpdatingProblem

    catalogue = catalogue_of(task)
    settings_of(task, catalogue)
    start = catalogue.check_active(task["start_effects"])
    gen = task["measured"]["generate"]
    if gen is not None:
        catalogue.check_active({e: v for e, v in gen["hidden"].items() if v is not None})
        known = {p.name for e in gen["hidden"] for p in catalogue.effect(e).parameters}
        unknown = sorted(set(gen["values"]) - known)
        if unknown:
            raise InputError(f"measured.generate.values: {unknown} are not parameters of the hidden effects; "
                             f"known: {sorted(known)}")  # fmt: skip
        noise_of(gen)
        return
    measured = measured_of(task["measured"], catalogue)
    UpdatingProblem(catalogue.model(start), with_stds(measured, data_noise(measured)), objective=gaussian_spec())


# ---- one run -----------------------------------------------------------------------------
def run(spec: dict) -> dict[str, list[dict]]:
    """One diagnosis and the rows of every table; a calibration or data failure is a row."""
    t0 = time.perf_counter()
    task = spec["task"]
    catalogue = catalogue_of(task)
    try:
        measured = measured_of(task["measured"], catalogue, spec["seed"])
        task = {**task, "settings": settings_of(task, catalogue)}
        diagnosis = diagnose(catalogue, measured, DiagnoseSettings(**task["settings"]), start=task["start_effects"])
    except (ModelEvaluationError, InputError) as exc:
        log.warning("diagnosis %s seed %s failed: %s", spec["label"], spec["seed"], exc)
        tables = {t: [] for t in TABLES}
        tables["summary"] = [{**failure(exc), "n_evaluations": 0}]
    else:
        tables = diagnosis_rows(diagnosis)
        tables["summary"][0] |= {"status": Status.OK, "error": ""}
        hidden = (measured.meta or {}).get("hidden")
        if hidden is not None:
            tables["summary"][0]["hidden_in_candidates"] = set(hidden) <= set(catalogue.candidate_effects())
    summary = tables["summary"][0]
    summary |= {"case": case_name(task, spec["seed"], summary.get("data", "")), **run_facts(task, spec["seed"])}
    summary["wall_s"] = time.perf_counter() - t0
    return tables


def case_name(task: dict, seed: int, data_name: str = "") -> str:
    """A readable name of a run: structure__hidden[__mag]__noise__seed for generated data."""
    gen = task["measured"]["generate"]
    if gen is None:
        return f"{task['structure']}__{data_name or source_kind(task['measured'])}"
    mag = float(gen["magnitude"])
    magnitude = "" if mag == 1.0 or not gen["hidden"] else f"__mag{mag:g}"
    noise = gen["noise"] if isinstance(gen["noise"], str) else "custom"
    return f"{task['structure']}__{hidden_name(gen)}{magnitude}__{noise}__seed{data_seed(task['measured'], seed)}"


def run_facts(task: dict, seed: int) -> dict[str, Any]:
    """The run's configured settings as columns of its summary row."""
    measured = task["measured"]
    facts: dict[str, Any] = {"data_source": source_kind(measured)}
    gen = measured["generate"]
    if gen is not None:
        noise = noise_of(gen)
        facts |= {
            "data_seed": data_seed(measured, seed),
            "noise_frequency_std_rel": noise.frequency_std_rel,
            "noise_shape_std_rel": noise.shape_std_rel,
            "parameter_error_rel": float(gen["parameter_error_rel"]),
            "hidden_values": json.dumps(gen["values"], sort_keys=True) if gen["values"] else "",
        }
    elif measured.get("builtin") is not None:
        facts |= {"builtin": measured["builtin"], "builtin_case": measured["case"]}
    facts["start_effects"] = "+".join(f"{k}[{v}]" if v else k for k, v in task["start_effects"].items())
    facts["structure_options"] = json.dumps(task["structure_options"], sort_keys=True)
    facts |= {("calibration_seed" if k == "seed" else k): v for k, v in (task["settings"] or {}).items()}
    return facts


# ---- analyses and figures ----------------------------------------------------------------
def analyses(tables: dict, report: dict) -> dict:
    """``cases`` and ``rates`` when ``report.outcomes`` is true."""
    from framework.diagnosis.outcomes import agreement, cases, rates, targets

    options = ReportConfig.model_validate(report or {})
    if not options.outcomes or "summary" not in tables:
        return {}
    scored = cases(tables["summary"])
    return {"cases": scored, "rates": rates(scored), "targets": targets(scored),
            "agreement": agreement(tables["summary"])}  # fmt: skip


def figures(tables: dict, out_dir: Path, report: dict) -> list[Path]:
    """discrepancy.png (a study of one run), showcase/<case>.png, study.png, power.png (see module
    docstring), drawn by :func:`framework.report.figures.diagnosis.diagnosis_figures`."""
    from framework.report.figures.diagnosis import diagnosis_figures

    options = ReportConfig.model_validate(report or {})
    return diagnosis_figures(tables, out_dir, options.showcase_seeds, options.outcomes)


KIND = Kind(
    name="diagnose", config=Config, tables=TABLES, plan_runs=plan_runs, run=run, check=check, identity=identity,
    preflight=preflight, preflight_key=input_key, report=ReportConfig, analyses=analyses, figures=figures,
)

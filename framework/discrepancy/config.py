"""Config of ``gomu diagnose CONFIG`` (pydantic, unknown keys rejected).

Example ::

    name: lab_joints             # results go to results/discrepancy/<name>/ by default
    structure: lab_frame         # a catalogue: beam, lab_frame, bridge (or module:function)
    structure_options: {}        # keyword options of the catalogue
    start_effects: {}            # effects already in the model {name: variant}
    measured:                    # exactly one of file / builtin / generate
      file: my_modes.yaml        # the framework's measured-modes file (YAML or CSV)
      # builtin: lab_frame       # a registry data set, with case:
      # generate: {hidden: {semi_rigid_joints: null}, seed: 3, noise: low}
    settings: {alpha: 0.01, decisive_delta_bic: 10, n_starts: 3}
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from framework.discrepancy.generate import NOISE_LEVELS, HiddenCase, Noise, generate
from framework.discrepancy.workflow import DiagnoseSettings, diagnose
from framework.errors import InputError
from framework.study.config import format_error, read_with_overrides

DEFAULT_ROOT = Path("results/discrepancy")


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class NoiseConfig(_Strict):
    frequency_std_rel: float = Field(gt=0)
    shape_std_rel: float = Field(gt=0)


class GenerateConfig(_Strict):
    """Simulated data with hidden effects ({effect: variant or null for random})."""

    hidden: dict[str, str | None] = Field(default_factory=dict)
    values: dict[str, float] = Field(default_factory=dict)
    seed: int = 0
    noise: Literal["low", "high"] | NoiseConfig = "low"
    parameter_error_rel: float = Field(0.05, ge=0)


class MeasuredSource(_Strict):
    file: str | None = None
    builtin: str | None = None
    case: str = "base"
    generate: GenerateConfig | None = None

    @model_validator(mode="after")
    def _one_source(self):
        given = [k for k in ("file", "builtin", "generate") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of file, builtin, generate (got {given or 'none'})")
        return self


class DiagnoseConfig(_Strict):
    name: str = Field(min_length=1)
    structure: str
    structure_options: dict = Field(default_factory=dict)
    start_effects: dict[str, str] = Field(default_factory=dict)
    measured: MeasuredSource
    settings: DiagnoseSettings = Field(default_factory=DiagnoseSettings)
    output: str | None = None


def load(path: str | Path, overrides: list[str] | None = None) -> DiagnoseConfig:
    """Read and validate a diagnose config; ``overrides`` are ``key.path=value`` strings."""
    path = Path(path)
    data = read_with_overrides(path, overrides, what="diagnose config")
    try:
        cfg = DiagnoseConfig.model_validate(data)
    except ValidationError as exc:
        raise InputError(format_error(exc, str(path))) from None
    if cfg.measured.file is not None:
        f = Path(cfg.measured.file)
        if not f.is_absolute() and not f.exists() and (path.parent / f).exists():
            cfg.measured.file = str(path.parent / f)
        elif not f.exists():
            raise InputError(f"{path}: measured.file: file not found: {cfg.measured.file}")
    return cfg


def measured_of(cfg: DiagnoseConfig, catalogue):
    """The measured modes named by ``cfg.measured``."""
    src = cfg.measured
    if src.file is not None:
        from framework.measurements import load as load_modes

        return load_modes(src.file)
    if src.builtin is not None:
        from framework.models.registry import builtin_measured

        return builtin_measured(src.builtin, src.case)
    g = src.generate
    noise = NOISE_LEVELS[g.noise] if isinstance(g.noise, str) else Noise(**g.noise.model_dump())
    for eff in g.hidden:
        catalogue.effect(eff)  # names the unknown effect
    return generate(catalogue, HiddenCase(g.hidden, g.values, g.seed, noise, g.parameter_error_rel))


def run(cfg: DiagnoseConfig, output: str | None = None):
    """Diagnose as configured and write the results; returns (diagnosis, output folder)."""
    from framework.discrepancy import report
    from framework.discrepancy.effects import get_catalogue

    catalogue = get_catalogue(cfg.structure, **cfg.structure_options)
    measured = measured_of(cfg, catalogue)
    # the catalogue's recommended settings, overridden by those the config sets explicitly
    settings = DiagnoseSettings(**(dict(catalogue.settings) | cfg.settings.model_dump(exclude_unset=True)))
    diagnosis = diagnose(catalogue, measured, settings, start=cfg.start_effects)
    out = Path(output or cfg.output or DEFAULT_ROOT / cfg.name)
    report.write(diagnosis, out)
    from framework.io import atomic_write_text

    atomic_write_text(out / "config.yaml", yaml.safe_dump(cfg.model_dump(mode="json"), sort_keys=False))
    return diagnosis, out


def run_config(path: str, overrides: list[str], output: str | None) -> int:
    """Entry point of ``gomu diagnose``: prints the verdict and the tables' folder."""
    cfg = load(path, overrides)
    diagnosis, out = run(cfg, output)
    s = diagnosis.summary()
    lines = [
        f"{cfg.name}: {diagnosis.conclusion}",
        f"named effect(s): {s['named_effect']}",
        f"gap before: max |freq error| {s['max_freq_error_pct_before']:.2f} %, min MAC {s['min_mac_before']:.3f}, "
        f"unmatched {s['n_unmatched_before']} (chi2 {s['chi2_before']:.1f}, p {s['p_before']:.3g})",
        f"gap after:  max |freq error| {s['max_freq_error_pct_after']:.2f} %, min MAC {s['min_mac_after']:.3f}, "
        f"unmatched {s['n_unmatched_after']} (chi2 {s['chi2_after']:.1f}, p {s['p_after']:.3g})",
        f"tables and figure in {out}",
    ]
    sys.stdout.write("\n".join(lines) + "\n")
    return 0

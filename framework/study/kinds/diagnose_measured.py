"""Where a diagnosis gets its measured modes: the ``measured`` section of a diagnose config.

Exactly one of::

    measured: {file: my_modes.yaml}                      # the framework's measured-modes file
    measured: {builtin: lab_frame, case: base}           # a registry data set
    measured:                                            # simulated, with hidden effects
      generate: {hidden: {semi_rigid_joints: null}, noise: high, magnitude: 1.0}

``generate`` draws the truth and the noise from ``np.random.default_rng(seed)``
(:mod:`framework.diagnosis.generate`); ``seed`` defaults to the run's seed, so a study
with ``runs: 10`` diagnoses ten independent data sets. The schema of the whole config is
:class:`framework.study.kinds.diagnose.Config`.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Discriminator, Field, StrictInt, Tag, model_validator

from framework.diagnosis.effects import Catalogue
from framework.diagnosis.generate import NOISE_LEVELS, HiddenCase, Noise, generate
from framework.measured.modes import MeasuredModes
from framework.study.schema import Strict

#: the named noise levels of :data:`framework.diagnosis.generate.NOISE_LEVELS`
NoiseLevel = Literal["low", "high", "very_high"]


class NoiseConfig(Strict):
    """Noise given by its two standard deviations (relative to f, and to the largest shape component)."""

    frequency_std_rel: float = Field(gt=0, le=1)
    shape_std_rel: float = Field(gt=0, le=1)


#: a noise level's name, or the two standard deviations (errors name only the form given)
NoiseSpec = Annotated[
    Annotated[NoiseLevel, Tag("level")] | Annotated[NoiseConfig, Tag("std")],
    Discriminator(lambda v: "std" if isinstance(v, dict | NoiseConfig) else "level"),
]


class GenerateConfig(Strict):
    """Simulated data: hidden effects ({effect: variant, or null for a random variant}),
    optional true values of their parameters, seed (default: the run's seed), noise level,
    magnitude of the hidden effects (1 = the catalogue's clearly present effect, see
    :class:`~framework.diagnosis.generate.HiddenCase`) and relative error of the base
    parameters."""

    hidden: dict[str, str | None] = Field(default_factory=dict)
    values: dict[str, float] = Field(default_factory=dict)
    seed: StrictInt | None = Field(None, ge=0, le=2**32 - 1)
    noise: NoiseSpec = "low"
    magnitude: float = Field(1.0, gt=0, le=10)
    parameter_error_rel: float = Field(0.05, ge=0, le=1)
    #: false: the data carry no standard deviations (the diagnosis must assume or estimate them)
    stds: bool = True


class MeasuredSource(Strict):
    file: str | None = None
    builtin: str | None = None
    case: str = "base"
    #: keywords for a built-in data set's provider (e.g. the lab frame's ``congruence``)
    options: dict[str, Any] = Field(default_factory=dict)
    generate: GenerateConfig | None = None

    @model_validator(mode="after")
    def _one_source(self):
        given = [k for k in ("file", "builtin", "generate") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(f"give exactly one of file, builtin, generate (got {given or 'none'})")
        return self


def source_kind(measured: dict) -> str:
    """"file", "builtin" or "generated"."""
    if measured.get("generate") is not None:
        return "generated"
    return "file" if measured.get("file") is not None else "builtin"


def noise_of(generate_cfg: dict) -> Noise:
    """The noise of a ``generate`` section (a level name or the two standard deviations)."""
    noise = generate_cfg.get("noise", "low")
    return NOISE_LEVELS[noise] if isinstance(noise, str) else Noise(**noise, name="custom")


def data_seed(measured: dict, run_seed: int) -> int | None:
    """The seed of generated data (the section's own, else the run's); None for real data."""
    gen = measured.get("generate")
    if gen is None:
        return None
    return int(run_seed if gen.get("seed") is None else gen["seed"])


def hidden_case(generate_cfg: dict, seed: int) -> HiddenCase:
    g = generate_cfg
    return HiddenCase(
        dict(g.get("hidden", {})),
        dict(g.get("values", {})),
        seed=seed,
        noise=noise_of(g),
        parameter_error_rel=float(g.get("parameter_error_rel", 0.05)),
        magnitude=float(g.get("magnitude", 1.0)),
        with_stds=bool(g.get("stds", True)),
    )


def measured_of(measured: dict, catalogue: Catalogue, run_seed: int = 0) -> MeasuredModes:
    """The measured modes named by a ``measured`` section (a plain dict, as in a run's task)."""
    if measured.get("file") is not None:
        from framework.measured.modes import load as load_modes

        return load_modes(measured["file"])
    if measured.get("builtin") is not None:
        from framework.structures.registry import builtin_measured

        return builtin_measured(measured["builtin"], measured.get("case", "base"), **(measured.get("options") or {}))
    gen = measured["generate"]
    for effect in gen.get("hidden", {}):
        catalogue.effect(effect)  # names an unknown effect
    return generate(catalogue, hidden_case(gen, data_seed(measured, run_seed)))

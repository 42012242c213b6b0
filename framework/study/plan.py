"""Expand a study config into run specs: sweep grid x algorithms x seeds.

A run spec is a small, picklable dict holding everything one run needs. Its identity
``run_id`` is a hash of what determines its result (structure, data, parameters,
objective, budget, algorithm and settings, seed) - not of the output folder or backend -
so ``--resume`` recognises a run that is already stored, and sweeping one algorithm's
settings does not duplicate the runs of the others.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from typing import Any

from framework.study.config import StudyConfig, set_path, validate

IDENTITY_FIELDS = ("structure", "measured", "validation", "parameters", "objective", "kind", "options")


def _canonical(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)


def run_id(spec: dict) -> str:
    ident = {k: spec["config"][k] for k in IDENTITY_FIELDS}
    ident.update(
        algorithm=spec["algorithm"], settings=spec["settings"], budget=spec["budget"], seed=spec["seed"]
    )
    return hashlib.sha1(_canonical(ident).encode()).hexdigest()[:16]


def expand_sweep(cfg: StudyConfig) -> list[tuple[dict, StudyConfig]]:
    """Every combination of the sweep values, as (values, config with them applied)."""
    if not cfg.sweep:
        return [({}, cfg)]
    keys = list(cfg.sweep)
    out = []
    base = cfg.model_dump(mode="json")
    base["sweep"] = {}
    for combo in itertools.product(*(cfg.sweep[k] for k in keys)):
        data = json.loads(json.dumps(base))
        values = dict(zip(keys, combo))
        for key, value in values.items():
            set_path(data, key, value)
        out.append((values, validate(data, source=f"sweep {values}")))
    return out


def plan(cfg: StudyConfig) -> list[dict]:
    """All run specs of a study, in a stable order, without duplicates."""
    specs: list[dict] = []
    seen: set[str] = set()
    for values, variant_cfg in expand_sweep(cfg):
        data = variant_cfg.model_dump(mode="json")
        variant = ",".join(f"{k.split('.')[-1]}={v}" for k, v in values.items()) or "default"
        for label, alg in variant_cfg.algorithms.items():
            relevant = {
                k: v
                for k, v in values.items()
                if not k.startswith("algorithms.") or k.startswith(f"algorithms.{label}.")
            }
            if values and not relevant and any(k.startswith("algorithms.") for k in values):
                variant_label = "default"
            else:
                variant_label = ",".join(f"{k.split('.')[-1]}={v}" for k, v in relevant.items()) or variant
            budget = {**data["budget"], **alg.budget}
            for i in range(alg.runs or variant_cfg.runs):
                spec = {
                    "study": variant_cfg.study,
                    "label": label,
                    "algorithm": alg.algorithm,
                    "settings": alg.settings,
                    "budget": budget,
                    "seed": variant_cfg.seed + i,
                    "run_index": i,
                    "variant": variant_label,
                    "config": data,
                }
                spec["run_id"] = run_id(spec)
                if spec["run_id"] in seen:
                    continue
                seen.add(spec["run_id"])
                specs.append(spec)
    return specs

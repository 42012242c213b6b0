"""Run kinds: what one run of a study does. A static registry, name -> module.

Every kind is a module with:

- ``Config``: the pydantic schema of its studies (a subclass of
  :class:`framework.study.schema.StudyHeader`; unknown keys rejected);
- ``TABLES``: the names of the tables its runs write (the first is one row per run);
- ``plan_runs(cfg, sweep_values) -> list[dict]``: the runs of one variant of the study, each
  ``{"label", "seed", "task", "columns", "relevant"}``: ``task`` is everything the run needs
  (plain data, picklable; its hash is the run's identity), ``columns`` the settings shown as
  typed columns in every table, ``relevant`` the sweep keys that change this run (optional);
- ``check(cfg, source, base_dir)``: checks that need more than the schema (data files),
  raising InputError when the config is read; it imports no code named in the config;
- ``preflight(specs, build_references=True)``: checks of every distinct input of the plan
  (building models, reading data) before any run starts, raising InputError; with
  ``build_references=False`` (``gomu validate`` without ``--build``) it imports no code named
  in the config as ``module:function``;
- ``run(spec) -> dict[table, list[row]]``: one run; a failure is data (a row with
  ``status`` "error" or "failed"), it never ends the study;
- ``identity(task) -> dict`` (optional): the part of the task that determines the result,
  when the task also holds things that do not (e.g. a file's path next to its content hash);
- ``analyses(tables, report) -> dict[name, DataFrame]`` (optional): derived tables, from the
  tables only;
- ``figures(tables, out_dir, report) -> list[Path]`` (optional): figures, from the tables only.

The registry maps names to module paths and imports a module only when its kind is used,
so no kind depends on the import order of another.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from framework.core.errors import InputError

KINDS: dict[str, str] = {
    "updating": "framework.study.kinds.updating",
    "identification": "framework.study.kinds.identification",
    "analysis": "framework.study.kinds.analysis",
    "diagnose": "framework.study.kinds.diagnose",
    "posterior": "framework.study.kinds.posterior",
    "damage": "framework.study.kinds.damage",
}


def get_kind(name: str) -> ModuleType:
    """The module of run kind ``name``."""
    if not isinstance(name, str) or name not in KINDS:
        raise InputError(f"kind: unknown run kind {name!r}; known: {sorted(KINDS)}")
    return importlib.import_module(KINDS[name])

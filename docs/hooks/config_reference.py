"""MkDocs hook: the config reference page, generated from the pydantic schemas at build time.

``docs/reference/config.md`` holds the marker ``<!-- config-reference -->``; this hook
replaces it with one table per schema (the study header, each run kind's fields and
sections, every optimizer's settings): field, type, default and constraints, read from the
models themselves, so the page cannot fall behind the code.
"""

from __future__ import annotations

import inspect
import re
import typing

from pydantic import BaseModel
from pydantic_core import PydanticUndefined

MARKER = "<!-- config-reference -->"


def _type_name(annotation) -> str:
    text = annotation.__name__ if isinstance(annotation, type) else str(annotation)
    text = re.sub(r"\b(typing|framework\.[\w.]+|pydantic\.[\w.]+|annotated_types)\.", "", text)
    text = re.sub(r"Annotated\[([^,\]]+)[^\]]*\]", r"\1", text)
    return text.replace("NoneType", "None").replace("|", "\\|")


def _default(field) -> str:
    if field.default_factory is not None:
        try:
            value = field.default_factory()
        except TypeError:
            return "(computed)"
        if isinstance(value, BaseModel):
            return "(section defaults)"
        return f"`{value!r}`"
    if field.default is PydanticUndefined:
        return "**required**"
    return f"`{field.default!r}`"


def _constraints(field) -> str:
    parts = []
    for m in field.metadata:
        for attr, sym in (("ge", ">="), ("gt", ">"), ("le", "<="), ("lt", "<"), ("min_length", "min length"),
                          ("max_length", "max length")):
            value = getattr(m, attr, None)
            if value is not None:
                parts.append(f"{sym} {value}")
    return ", ".join(parts)


def _nested(annotation) -> list[type[BaseModel]]:
    if inspect.isclass(annotation) and issubclass(annotation, BaseModel):
        return [annotation]
    out = []
    for arg in typing.get_args(annotation):
        out += _nested(arg)
    return out


def model_table(model: type[BaseModel], title: str, level: int = 3, seen: set | None = None,
                skip: tuple[str, ...] = ()) -> str:
    """A markdown section for ``model``: its docstring, a field table, then its sub-sections."""
    seen = set() if seen is None else seen
    doc = inspect.getdoc(model) or ""
    base_doc = inspect.getdoc(BaseModel) or ""
    lines = [f"{'#' * level} {title}", ""]
    if doc and doc != base_doc:
        lines += [doc.split("\n\n")[0].replace("\n", " "), ""]
    lines += ["| field | type | default | constraints |", "| --- | --- | --- | --- |"]
    subs = []
    for name, field in model.model_fields.items():
        if name in skip:
            continue
        lines.append(f"| `{name}` | {_type_name(field.annotation)} | {_default(field)} | {_constraints(field)} |")
        for sub in _nested(field.annotation):
            if sub not in seen and sub.__module__.startswith("framework"):
                seen.add(sub)
                subs.append((name, sub))
    lines.append("")
    for name, sub in subs:
        lines.append(model_table(sub, f"`{name}`: {sub.__name__}", min(level + 1, 6), seen))
    return "\n".join(lines)


def config_reference() -> str:
    from framework.optimizers import OPTIMIZERS
    from framework.study.kinds import KINDS, get_kind
    from framework.study.schema import StudyHeader

    header_fields = tuple(StudyHeader.model_fields)
    parts = [model_table(StudyHeader, "Header (every study)", 2)]
    for kind in KINDS:
        cfg = get_kind(kind).config
        parts.append(model_table(cfg, f"Run kind `{kind}`", 2, skip=header_fields))
    parts.append("## Optimizer settings\n\nThe `settings:` of an `algorithms:` entry, per `algorithm:`.\n")
    for name in OPTIMIZERS:
        parts.append(model_table(OPTIMIZERS[name].settings, f"`{name}`", 3))
    return "\n".join(parts)


def on_page_markdown(markdown, page, config, files):  # noqa: ARG001 - MkDocs hook signature
    if MARKER in markdown:
        return markdown.replace(MARKER, config_reference())
    return markdown

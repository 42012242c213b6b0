"""Reading user text: YAML configs and data files, CSV tables and ``--set`` values, strictly.

User files and text (configs, measured-modes files, ``--set`` values) are read here, so
that each problem becomes one ``InputError("<file>: <problem>")`` line instead of a
traceback or, worse, a silent misreading:

- files: missing, a folder, unreadable, larger than a limit (checked before parsing), empty,
  not UTF-8 (a UTF-8 byte-order mark is accepted);
- YAML: syntax errors (with line and column), duplicate keys at any depth (with the key path
  and both lines), nesting deeper than ``MAX_DEPTH``, recursive aliases and aliases that
  expand to more than ``MAX_ALIAS_NODES`` extra nodes (alias bombs), non-scalar mapping keys,
  tags other than the core ones (``!!python/...``, ``!!binary``, ``!!set``, ``!!timestamp``);
- CSV: a delimiter other than ``,``, rows with more or fewer fields than the header, empty or
  repeated column names, malformed quoting; :func:`parse_number` reads a number strictly
  (a decimal comma is named as such).

YAML scalars follow the YAML 1.2 core schema, not PyYAML's YAML 1.1 defaults: ``true/false``
(any case form of the spec) are the only booleans, so ``yes``, ``no``, ``on`` and ``off``
stay text; ``1e-6`` is a float (YAML 1.1 reads it as the string ``'1e-6'``); ``010`` is
ten, ``0o10`` eight, ``0x10`` sixteen; ``1:30`` is text (not 90); dates stay text. A
number literal outside the double range (``1e400``) or one that rounds to zero
(``1e-400``) is an error, not inf or 0; ``.inf`` and ``.nan`` are read as written and it is
the data layer's job to refuse them where a finite number is needed. Booleans are not
numbers here either: the schema gets ``True``, not ``1``.

Why a custom PyYAML loader: PyYAML (a dependency already) keeps the last of duplicate keys
(a long-open PyYAML issue), expands aliases without limit, recurses without a depth limit
(RecursionError at ~1000 levels) and resolves YAML 1.1 scalars. We found no maintained
PyYAML add-on that adds duplicate-key, alias and depth limits together (the usual answer is
a ``construct_mapping`` override). ruamel.yaml rejects duplicate keys and speaks YAML 1.2,
but documents no limit on alias expansion or depth and would be a second YAML library;
strictyaml refuses flow style (``{frequency_hz: 3.58}``, ``[1, 2]``), which the project's
files use. So the loader below reuses PyYAML's parser (libyaml's when installed) and
composer, adds the checks on the composed node graph before anything is constructed, and
restricts the resolver and constructors to the core schema. :func:`dump_yaml` writes with
the same rules (text that any YAML reader could take for a number, boolean or null is
quoted), so that what the framework writes it reads back identically.
"""

from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path
from typing import Any

import yaml
from yaml.composer import Composer
from yaml.constructor import ConstructorError, SafeConstructor
from yaml.nodes import MappingNode, ScalarNode, SequenceNode
from yaml.resolver import BaseResolver, Resolver

from framework.core.errors import InputError

try:  # libyaml's parser, when PyYAML was built with it (same events, faster)
    from yaml.cyaml import CParser as _CParser
except ImportError:  # pragma: no cover
    _CParser = None

#: largest config file (bytes) read: configs are hand-written, a few kB
CONFIG_MAX_BYTES = 1_000_000
#: largest data file (bytes) read: measured modes of a few thousand DOFs stay far below
DATA_MAX_BYTES = 50_000_000
#: deepest nesting of sequences and mappings (also through aliases)
MAX_DEPTH = 100
#: most nodes that aliases may add to a document when expanded (a defence against alias bombs)
MAX_ALIAS_NODES = 10_000
#: longest integer literal (digits); longer ones are refused rather than converted slowly
MAX_INT_DIGITS = 1_000

_MERGE_TAG = "tag:yaml.org,2002:merge"
_FLOAT_TAG = "tag:yaml.org,2002:float"
_INT_TAG = "tag:yaml.org,2002:int"

# ---- YAML 1.2 core schema ------------------------------------------------------------------
_NULL_RE = re.compile(r"^(?:~|null|Null|NULL|)$")
_BOOL_RE = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_INT_RE = re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$")
_FLOAT_RE = re.compile(
    r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"
)
#: a decimal number as written in a CSV cell (no inf/nan, no hex, no digit separators)
_DECIMAL_RE = re.compile(r"^[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?$")


class _CoreResolver(BaseResolver):
    """Implicit tags of plain scalars by the YAML 1.2 core schema (plus the ``<<`` merge key)."""


_CoreResolver.add_implicit_resolver("tag:yaml.org,2002:null", _NULL_RE, ["~", "n", "N", ""])
_CoreResolver.add_implicit_resolver("tag:yaml.org,2002:bool", _BOOL_RE, list("tTfF"))
_CoreResolver.add_implicit_resolver(_INT_TAG, _INT_RE, list("-+0123456789"))
_CoreResolver.add_implicit_resolver(_FLOAT_TAG, _FLOAT_RE, list("-+0123456789."))
_CoreResolver.add_implicit_resolver(_MERGE_TAG, re.compile(r"^(?:<<)$"), ["<"])


class _LimitError(Exception):
    """A document breaks a limit of the reader (message without the source)."""


def _line(node_or_mark) -> int:
    mark = getattr(node_or_mark, "start_mark", node_or_mark)
    return mark.line + 1 if mark is not None else 0


class _StrictComposer(Composer):
    """PyYAML's composer with a nesting limit (no RecursionError on deep documents)."""

    def __init__(self) -> None:
        super().__init__()
        self._depth = 0

    def compose_node(self, parent, index):
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                raise _LimitError(
                    f"line {_line(self.peek_event())}: nesting deeper than {MAX_DEPTH} levels"
                )
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


class _CoreConstructor(SafeConstructor):
    """Constructors of the core tags only; numbers read exactly or refused."""

    yaml_constructors: dict = {}

    def construct_core_int(self, node) -> int:
        text = self.construct_scalar(node)
        if not _INT_RE.match(text):
            raise ConstructorError(None, None, f"not an integer: {text!r}", node.start_mark)
        sign = -1 if text.startswith("-") else 1
        digits = text.lstrip("+-")
        base = {"0o": 8, "0x": 16}.get(digits[:2], 10)
        if base != 10:
            digits = digits[2:]
        if len(digits) > MAX_INT_DIGITS:
            raise ConstructorError(
                None, None, f"integer of {len(digits)} digits is too large (limit {MAX_INT_DIGITS})", node.start_mark
            )
        return sign * int(digits, base)

    def construct_core_float(self, node) -> float:
        text = self.construct_scalar(node)
        if not _FLOAT_RE.match(text):
            raise ConstructorError(None, None, f"not a number: {text!r}", node.start_mark)
        lower = text.lower()
        if lower.endswith(".inf"):
            return -math.inf if lower.startswith("-") else math.inf
        if lower == ".nan":
            return math.nan
        value = float(text)
        if not math.isfinite(value):
            raise ConstructorError(None, None, f"number {text} is outside the double-precision range", node.start_mark)
        mantissa = re.split("[eE]", text)[0]
        if value == 0.0 and re.search("[1-9]", mantissa):
            raise ConstructorError(None, None, f"number {text} is too small: it would be read as 0", node.start_mark)
        return value

    def construct_core_bool(self, node) -> bool:
        text = self.construct_scalar(node)
        if not _BOOL_RE.match(text):
            raise ConstructorError(None, None, f"not a boolean: {text!r}", node.start_mark)
        return text.lower() == "true"

    def construct_core_null(self, node) -> None:
        text = self.construct_scalar(node)
        if not _NULL_RE.match(text):
            raise ConstructorError(None, None, f"not null: {text!r}", node.start_mark)
        return None

    def construct_unsupported(self, node):
        raise ConstructorError(
            None, None, f"unsupported tag {node.tag!r} (only text, numbers, booleans, null, lists, mappings)",
            node.start_mark,
        )


_CoreConstructor.add_constructor("tag:yaml.org,2002:null", _CoreConstructor.construct_core_null)
_CoreConstructor.add_constructor("tag:yaml.org,2002:bool", _CoreConstructor.construct_core_bool)
_CoreConstructor.add_constructor(_INT_TAG, _CoreConstructor.construct_core_int)
_CoreConstructor.add_constructor(_FLOAT_TAG, _CoreConstructor.construct_core_float)
_CoreConstructor.add_constructor("tag:yaml.org,2002:str", SafeConstructor.construct_yaml_str)
_CoreConstructor.add_constructor("tag:yaml.org,2002:seq", SafeConstructor.construct_yaml_seq)
_CoreConstructor.add_constructor("tag:yaml.org,2002:map", SafeConstructor.construct_yaml_map)
_CoreConstructor.add_constructor(None, _CoreConstructor.construct_unsupported)


class _GraphChecks:
    """Checks of a composed node graph, before construction: duplicate and non-scalar keys,
    recursive aliases, expanded size and depth."""

    def check_graph(self, root) -> None:
        size: dict[int, int] = {}
        depth: dict[int, int] = {}
        visiting = {id(root)}
        self._check_keys(root, "")
        stack = [(root, self._children(root, ""), 0)]
        while stack:
            node, kids, i = stack[-1]
            while i < len(kids) and id(kids[i][0]) in size:
                i += 1
            if i < len(kids):
                stack[-1] = (node, kids, i + 1)
                child, path = kids[i]
                if id(child) in visiting:
                    raise _LimitError(f"{path or 'top level'} (line {_line(child)}): recursive alias")
                visiting.add(id(child))
                self._check_keys(child, path)
                stack.append((child, self._children(child, path), 0))
                continue
            stack.pop()
            visiting.discard(id(node))
            size[id(node)] = 1 + sum(size[id(c)] for c, _ in kids)
            depth[id(node)] = 1 + max((depth[id(c)] for c, _ in kids), default=0)
        extra = size[id(root)] - len(size)
        if extra > MAX_ALIAS_NODES:
            raise _LimitError(
                f"aliases expand to {extra} more nodes, more than the limit of {MAX_ALIAS_NODES} "
                "(alias bomb?); write the repeated values out"
            )
        if depth[id(root)] > MAX_DEPTH:
            raise _LimitError(f"nesting deeper than {MAX_DEPTH} levels once aliases are expanded")

    @staticmethod
    def _children(node, path: str) -> list:
        if isinstance(node, SequenceNode):
            return [(item, f"{path}[{i}]") for i, item in enumerate(node.value)]
        if isinstance(node, MappingNode):
            out = []
            for key, value in node.value:
                name = key.value if isinstance(key, ScalarNode) else "?"
                out.append((key, path))
                out.append((value, f"{path}.{name}" if path else str(name)))
            return out
        return []

    def _check_keys(self, node, path: str) -> None:
        if not isinstance(node, MappingNode):
            return
        seen: dict = {}
        for key_node, _ in node.value:
            if not isinstance(key_node, ScalarNode):
                raise _LimitError(
                    f"{path or 'top level'} (line {_line(key_node)}): a mapping key must be a plain value, "
                    f"not a {'list' if isinstance(key_node, SequenceNode) else 'mapping'}"
                )
            if key_node.tag == _MERGE_TAG:
                continue
            key = self.construct_object(key_node)
            if key in seen:
                first = seen[key]
                where = f"{path}.{key_node.value}" if path else str(key_node.value)
                at = f"line {_line(key_node)}, first given at line {_line(first)}"
                if _line(key_node) == _line(first):
                    columns = f"{first.start_mark.column + 1} and {key_node.start_mark.column + 1}"
                    at = f"line {_line(key_node)}, columns {columns}"
                raise _LimitError(f"{where}: duplicate key ({at})")
            seen[key] = key_node


def _loader_class(parser_classes: tuple) -> type:
    class _Loader(_StrictComposer, *parser_classes, _CoreConstructor, _CoreResolver, _GraphChecks):
        def __init__(self, stream) -> None:
            if len(parser_classes) == 1:  # libyaml's parser (a C type) reads the stream itself
                parser_classes[0].__init__(self, stream)
            else:
                reader, scanner, parser = parser_classes
                reader.__init__(self, stream)
                scanner.__init__(self)
                parser.__init__(self)
            _StrictComposer.__init__(self)
            _CoreConstructor.__init__(self)
            _CoreResolver.__init__(self)

        def load_checked(self) -> Any:
            node = self.get_single_node()
            if node is None:
                return None
            self.check_graph(node)
            return self.construct_document(node)

    return _Loader


_PY_LOADER = _loader_class((yaml.reader.Reader, yaml.scanner.Scanner, yaml.parser.Parser))
_LOADER = _loader_class((_CParser,)) if _CParser is not None else _PY_LOADER


# ---- errors ---------------------------------------------------------------------------------
def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def _yaml_problem(exc: yaml.YAMLError) -> str:
    if isinstance(exc, yaml.MarkedYAMLError):
        mark = exc.problem_mark or exc.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        problem = exc.problem or exc.context or "syntax error"
        context = f" ({exc.context})" if exc.context and exc.problem else ""
        return f"not valid YAML: {where}{problem}{context}"
    if isinstance(exc, yaml.reader.ReaderError):
        return f"not valid YAML: {exc.reason} (character {exc.character!r} at position {exc.position})"
    return f"not valid YAML: {exc}"


# ---- files ----------------------------------------------------------------------------------
def read_text_file(path: str | Path, what: str = "config", max_bytes: int = CONFIG_MAX_BYTES) -> str:
    """The UTF-8 text of a file of at most ``max_bytes`` bytes (a byte-order mark is dropped).

    ``what`` names the kind of file in messages ("config" -> "config file not found").
    Raises InputError for a missing file, a folder, an unreadable, too large, empty or
    non-UTF-8 file.
    """
    path = Path(path)
    try:
        if path.is_dir():
            raise InputError(f"{path}: is a folder, not a {what} file")
        size = path.stat().st_size
        if size > max_bytes:
            raise InputError(f"{path}: {what} file is {size} bytes, more than the limit of {max_bytes} bytes")
        with path.open("rb") as fh:
            raw = fh.read(max_bytes + 1)
    except FileNotFoundError:
        raise InputError(f"{path}: {what} file not found") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read the {what} file: {exc.strerror or exc}") from None
    if len(raw) > max_bytes:
        raise InputError(f"{path}: {what} file is more than the limit of {max_bytes} bytes")
    if not raw.strip():
        raise InputError(f"{path}: {what} file is empty")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(
            f"{path}: {what} file is not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}); "
            "save it as UTF-8"
        ) from None
    return text.removeprefix("\ufeff")


def read_yaml_text(
    text: str, source: str, what: str = "config", max_bytes: int = CONFIG_MAX_BYTES, mapping: bool = True
) -> Any:
    """Parse YAML text strictly (see the module docstring); errors are ``InputError("<source>: ...")``.

    mapping=True: the document must be a mapping (an empty document is an error);
    mapping=False: any value, None for an empty document.
    """
    if not isinstance(text, str):
        raise InputError(f"{source}: expected YAML text, got {type(text).__name__}")
    if len(text) > max_bytes and len(text.encode("utf-8")) > max_bytes:
        raise InputError(f"{source}: {what} is more than the limit of {max_bytes} bytes")
    loader = None
    try:
        loader = _LOADER(text)
        data = loader.load_checked()
    except _LimitError as exc:
        raise InputError(_one_line(f"{source}: {exc}")) from None
    except yaml.YAMLError as exc:
        raise InputError(_one_line(f"{source}: {_yaml_problem(exc)}")) from None
    except RecursionError:  # only if the caller's stack is already deep
        raise InputError(f"{source}: nesting too deep to read") from None
    finally:
        if loader is not None:
            loader.dispose()
    if mapping:
        if data is None:
            raise InputError(f"{source}: {what} file is empty (no YAML content)")
        if not isinstance(data, dict):
            raise InputError(f"{source}: a {what} must be a mapping (key: value lines), got {_kind(data)}")
    return data


def read_yaml_file(
    path: str | Path, what: str = "config", max_bytes: int = CONFIG_MAX_BYTES, mapping: bool = True
) -> Any:
    """Read a YAML file strictly: :func:`read_text_file` then :func:`read_yaml_text`.

    Use ``max_bytes=DATA_MAX_BYTES`` for data files. Errors name the file.
    """
    text = read_text_file(path, what, max_bytes)
    return read_yaml_text(text, str(path), what, max_bytes, mapping)


def parse_override_value(text: str, source: str = "--set") -> Any:
    """The value of ``--set key=value`` in YAML syntax (``40``, ``1e-6``, ``[5, 10]``, ``true``, ``null``).

    Same rules and limits as config files; invalid YAML is an error (quote text that starts
    with a YAML indicator such as ``*``, ``&``, ``[`` or ``@``), an empty value is None.
    """
    try:
        return read_yaml_text(text, source, what="value", mapping=False)
    except InputError as exc:
        raise InputError(f"{exc} (quote the value if it is text)") from None


def _kind(value: Any) -> str:
    return {list: "a list", str: "a text", int: "an integer", float: "a number", bool: "a boolean"}.get(
        type(value), type(value).__name__
    )


# ---- writing --------------------------------------------------------------------------------
def _implicit_tag(table: dict, value: str) -> str | None:
    for tag, regexp in table.get(value[:1], []) + table.get(None, []):
        if regexp.match(value):
            return tag
    return None


class _Dumper(yaml.SafeDumper):
    """SafeDumper that quotes text which the YAML 1.2 core schema or YAML 1.1 would read as
    another type (``'1e5'``, ``'yes'``, ``'2024-01-01'``), and writes numbers both read alike."""

    def resolve(self, kind, value, implicit):
        if kind is ScalarNode and implicit[0]:
            for table in (_CoreResolver.yaml_implicit_resolvers, Resolver.yaml_implicit_resolvers):
                tag = _implicit_tag(table, value)
                if tag is not None:
                    return tag
        return super().resolve(kind, value, implicit)


def dump_yaml(data: Any) -> str:
    """YAML text of plain data (dict, list, str, int, float, bool, None) that :func:`read_yaml_text`
    and other YAML readers read back identically; keys keep their order."""
    return yaml.dump(data, Dumper=_Dumper, sort_keys=False)  # allow_unicode=True would write U+0085, U+2028 raw


# ---- CSV ------------------------------------------------------------------------------------
def read_csv_table(
    path: str | Path, what: str = "CSV", max_bytes: int = DATA_MAX_BYTES
) -> tuple[list[str], list[tuple[int, list[str]]]]:
    """Header and rows of a comma-separated UTF-8 file: ``(columns, [(line number, fields), ...])``.

    Strict: the delimiter is ``,`` (a header of one column holding ``;`` or a tab is refused), every row has
    exactly as many fields as the header (a decimal comma gives one field too many), column
    names are non-empty and distinct, quoting follows RFC 4180. Blank lines are skipped.
    Fields are returned as text; read numbers with :func:`parse_number`.
    """
    path = Path(path)
    text = read_text_file(path, what, max_bytes)
    source = str(path)
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)
    rows: list[tuple[int, list[str]]] = []
    header: list[str] | None = None
    try:
        for fields in reader:
            if not fields or all(not f.strip() for f in fields) and len(fields) == 1:
                continue
            if header is None:
                header = [f.strip() for f in fields]
                _check_header(header, f"{source}: line {reader.line_num}")
                continue
            if len(fields) != len(header):
                more = "more" if len(fields) > len(header) else "fewer"
                hint = " (a decimal comma? numbers use '.')" if more == "more" else ""
                raise InputError(
                    f"{source}: line {reader.line_num}: {len(fields)} fields, {more} than the "
                    f"{len(header)} columns of the header{hint}"
                )
            rows.append((reader.line_num, fields))
    except csv.Error as exc:
        raise InputError(f"{source}: line {reader.line_num}: not valid CSV: {exc}") from None
    if header is None:
        raise InputError(f"{source}: {what} file has no header line")
    return header, rows


def _check_header(header: list[str], where: str) -> None:
    for sep, name in ((";", "';'"), ("\t", "tabs")):
        if len(header) == 1 and sep in header[0]:
            raise InputError(
                f"{where}: columns separated by {name}? use ',' between columns and '.' in numbers"
            )
    if any(not h for h in header):
        raise InputError(f"{where}: empty column name in {header}")
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise InputError(f"{where}: repeated column(s) {dup}")


def parse_number(text: str, where: str) -> float:
    """A decimal number written in text (``3.58``, ``-1e-3``); anything else is an InputError naming
    ``where`` (the file, row and column). inf, nan, hex and ``1_000`` are refused."""
    value = text.strip()
    if not _DECIMAL_RE.match(value):
        hint = " (decimal comma? use '.')" if re.fullmatch(r"[-+]?[0-9]+,[0-9]+", value) else ""
        raise InputError(f"{where}: not numeric: {_clip(repr(text))}{hint}")
    number = float(value)
    if not math.isfinite(number):
        raise InputError(f"{where}: number {_clip(value)} is outside the double-precision range")
    if number == 0.0 and re.search("[1-9]", re.split("[eE]", value)[0]):
        raise InputError(f"{where}: number {_clip(value)} is too small: it would be read as 0")
    return number


def _clip(text: str, limit: int = 40) -> str:
    """``text`` shortened for a message: its start and its length."""
    return text if len(text) <= limit else f"{text[:limit - 3]}...({len(text)} characters)"

"""Command line: ``gomu run | report | validate | diagnose | bench``."""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path

# Small dense eigenproblems and process-level parallelism: one BLAS thread per process is
# much faster than a multi-threaded BLAS fighting for the same cores (measured up to 40x on
# a loaded 2-core machine). Set before numpy is imported; an explicit user setting wins.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from framework.core.errors import InputError  # noqa: E402


def _cmd_run(args) -> int:
    from framework.study.config import load
    from framework.study.runner import run_study, summary

    cfg = load(args.config, args.set)
    backend = "dask" if args.scheduler or args.dask else args.backend
    tables = run_study(
        cfg,
        resume=args.resume,
        figures=not args.no_figures,
        backend=backend,
        workers=args.workers,
        scheduler=args.scheduler,
        progress=False if args.quiet else None,
    )
    table = summary(tables)
    if not table.empty:
        with_pd = table.to_string(index=False, float_format=lambda v: f"{v:.4g}")
        sys.stdout.write(with_pd + "\n")
    sys.stdout.write(f"tables and figures in {cfg.output_dir()}\n")
    return 0


def _cmd_report(args) -> int:
    if args.reproduction:
        from framework.report.reproduction import write
        from framework.structures.registry import reproduction_providers

        if not Path(args.reproduction).is_dir():
            raise InputError(f"report --reproduction: results folder {args.reproduction!r} not found")
        sys.stdout.write(f"{write(args.reproduction, args.output, reproduction_providers())}\n")
        return 0
    if not args.results_dir:
        raise InputError("report: give a results folder, or --reproduction RESULTS")
    from framework.study.runner import report

    files = report(Path(args.results_dir), shapes=args.shapes)
    if args.html:
        from framework.report.figures.interactive import all_html

        files += all_html(Path(args.results_dir))
    for f in files:
        sys.stdout.write(f"{f}\n")
    return 0


def _cmd_validate(args) -> int:
    from framework.study.config import load
    from framework.study.plan import plan
    from framework.study.runner import preflight

    cfg = load(args.config, args.set)
    specs = plan(cfg)
    preflight(cfg, specs, build_references=args.build)
    named = _named_code(cfg.model_dump(mode="json"))
    note = "" if args.build or not named else (
        f" (code named in the config was not imported: {', '.join(sorted(named))}; --build to import it)")
    sys.stdout.write(f"{args.config}: OK - kind {cfg.kind!r}, {len(specs)} runs{note}\n")
    return 0


def _named_code(data: dict) -> set[str]:
    """The ``module:function`` references of a config (the only fields that may name code:
    structure.name, measured.builtin, validation[].measured.builtin; a diagnose config's
    structure)."""
    structure = data.get("structure")
    names = [structure.get("name") if isinstance(structure, dict) else structure]
    sections = [data.get("measured")] + [v.get("measured") for v in data.get("validation") or [] if isinstance(v, dict)]
    names += [m.get("builtin") for m in sections if isinstance(m, dict)]
    return {n for n in names if isinstance(n, str) and ":" in n}


def _cmd_diagnose(args) -> int:
    """``gomu diagnose CONFIG``: run a one-run study of kind ``diagnose`` and print the verdict.

    The config's ``kind`` may be left out; ``--output`` replaces the config's.
    """
    from framework.core.status import succeeded
    from framework.study.config import read_with_overrides, validate
    from framework.study.plan import plan
    from framework.study.runner import run_study

    path, output = args.config, args.output
    data = read_with_overrides(path, args.set, what="diagnose config")
    data.setdefault("kind", "diagnose")
    if data["kind"] != "diagnose":
        raise InputError(f"{path}: kind: gomu diagnose runs configs of kind 'diagnose', got {data['kind']!r}")
    if output:
        data["output"] = output
    cfg = validate(data, source=str(path), base_dir=Path(path).parent)
    n_runs = len(plan(cfg))
    if n_runs != 1:
        raise InputError(f"{path}: gomu diagnose runs one diagnosis, this config plans {n_runs}; "
                         f"use gomu run {path}")  # fmt: skip
    tables = run_study(cfg, progress=False)
    s = tables["summary"].iloc[0]
    out = cfg.output_dir()
    if not succeeded(s["status"]):
        sys.stderr.write(f"{cfg.study}: diagnosis failed: {s['error']}\ntables in {out}\n")
        return 1
    named = s["named_effect"]
    if isinstance(s.get("named_location"), str) and s["named_location"]:
        named += f" at {s['named_location']}"
    if s.get("partial"):
        named += " (partial explanation)"
    lines = [
        f"{cfg.study}: {s['conclusion']}",
        f"rounds: {s['headline']}",
        f"named effect(s): {named}",
        f"gap before: max |freq error| {s['max_freq_error_pct_before']:.2f} %, min MAC {s['min_mac_before']:.3f}, "
        f"unmatched {s['n_unmatched_before']} (chi2 {s['chi2_before']:.1f}, p {s['p_before']:.3g})",
        f"gap after:  max |freq error| {s['max_freq_error_pct_after']:.2f} %, min MAC {s['min_mac_after']:.3f}, "
        f"unmatched {s['n_unmatched_after']} (chi2 {s['chi2_after']:.1f}, p {s['p_after']:.3g})",
        f"tables and figure in {out}",
    ]
    if isinstance(s.get("flags"), str) and s["flags"]:
        lines.insert(3, f"flags: {s['flags']}")
    if isinstance(s.get("noise_warning"), str) and s["noise_warning"]:
        lines.insert(1, s["noise_warning"])
    sys.stdout.write("\n".join(lines) + "\n")
    return 0


def _cmd_bench(args) -> int:
    from framework.study.bench import main as bench_main

    return bench_main(args.structures, workers=args.workers, repeats=args.repeats)


class _Parser(argparse.ArgumentParser):
    """argparse with errors on one line (``gomu run: error: ...``, exit code 2), no usage dump."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {one_line(' '.join(message.split()))} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="gomu", description="Model updating of civil structures with global optimization"
    )
    p.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    r = sub.add_parser("run", help="run a study config")
    r.add_argument("config")
    r.add_argument(
        "--set", action="append", default=[], metavar="KEY.PATH=VALUE", help="override a config field"
    )
    r.add_argument("--resume", action="store_true", help="keep stored runs and run only the missing ones")
    r.add_argument("--backend", choices=["serial", "processes", "dask"], default=None)
    r.add_argument("--workers", type=_positive_int, default=None)
    r.add_argument("--scheduler", default=None, help="Dask scheduler address (implies --backend dask)")
    r.add_argument("--dask", action="store_true", help="start an embedded local Dask cluster")
    r.add_argument("--no-figures", action="store_true", help="no figures and no mode-shape tables")
    r.add_argument("--quiet", action="store_true", help="no progress bar")
    r.set_defaults(fn=_cmd_run)

    rep = sub.add_parser("report", help="regenerate all figures from a results folder's tables")
    rep.add_argument("results_dir", nargs="?")
    rep.add_argument("--shapes", action="store_true",
                     help="(re)compute the mode-shape tables first (builds the model; for folders of earlier versions)")
    rep.add_argument("--html", action="store_true",
                     help="also write interactive 3-D mode shapes (shapes_<state>.html; needs the viz extra, plotly)")
    rep.add_argument("--reproduction", metavar="RESULTS", default=None,
                     help="write the reproduction report (source vs ours) from the tables under RESULTS")
    rep.add_argument("--output", default="docs/reproduction.md", help="the reproduction report's file")
    rep.set_defaults(fn=_cmd_report)

    v = sub.add_parser("validate", help="check a config and its data without running anything")
    v.add_argument("config")
    v.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE")
    v.add_argument("--build", action="store_true",
                   help="also import and build models and data providers named as module:function")
    v.set_defaults(fn=_cmd_validate)

    d = sub.add_parser("diagnose", help="find, name and add the physical effect a model is missing")
    d.add_argument("config")
    d.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE")
    d.add_argument("--output", default=None, help="results folder (default from the config)")
    d.set_defaults(fn=_cmd_diagnose)

    b = sub.add_parser("bench", help="evaluations per second per structure and parallel speed-up")
    b.add_argument("structures", nargs="*", default=["lab_frame_3dof"])
    b.add_argument("--workers", type=_positive_int, default=2)
    b.add_argument("--repeats", type=_positive_int, default=3)
    b.set_defaults(fn=_cmd_bench)
    return p


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 1, got {text!r}")
    return value


def one_line(text: str) -> str:
    """``text`` as one printable line: line breaks and other non-printable characters (also
    those of keys and values quoted from a user's file, e.g. U+0085) written as escapes."""
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in text)


def main(argv: list[str] | None = None) -> int:
    # as `python -m` does: modules in the current folder (a user's build function) are importable
    if os.getcwd() not in sys.path and "" not in sys.path:
        sys.path.insert(0, os.getcwd())
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s"
    )
    try:
        return args.fn(args)
    except InputError as exc:
        sys.stderr.write(f"gomu: error: {one_line(str(exc))}\n")
        return 2
    except OSError as exc:  # the disk, not the input: one line, exit 1
        where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
        sys.stderr.write(f"gomu: error: {one_line(f'{where}{exc.strerror or exc}')}\n")
        return 1
    except KeyboardInterrupt:
        sys.stderr.write("gomu: interrupted; stored runs are kept - rerun with --resume\n")
        return 130


if __name__ == "__main__":
    raise SystemExit(main())

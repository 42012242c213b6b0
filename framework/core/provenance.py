"""Provenance of a results folder: which code, packages and machine produced it.

``provenance()`` returns a plain dict (JSON-able): the project's version and git commit (with
a flag for uncommitted changes), Python and platform, the versions of the numerical packages
the results depend on, and the command line. The study runner writes it to
``<results>/provenance.json`` next to the tables; ``gomu report`` writes one, marked as its
own, into a folder that has none (results of an earlier version).
"""

from __future__ import annotations

import json
import platform
import subprocess
import sys
from importlib import metadata
from pathlib import Path

from framework.core.io import atomic_write_text

PACKAGES = ("gomu", "numpy", "scipy", "pandas", "pyarrow", "pydantic", "pymoo", "pyswarms", "openseespy",
            "dask", "distributed", "matplotlib", "seaborn", "pyOMA-2", "pyuff")


def _version(name: str) -> str | None:
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return None


def git_commit(root: Path | None = None) -> dict:
    """{"commit": sha or None, "dirty": bool or None} of the project's checkout."""
    root = root or Path(__file__).resolve().parents[2]
    try:
        sha = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True, text=True, timeout=10)
        if sha.returncode != 0:
            return {"commit": None, "dirty": None}
        status = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", "framework"],
                                cwd=root, capture_output=True, text=True, timeout=10)
        return {"commit": sha.stdout.strip(), "dirty": bool(status.stdout.strip())}
    except (OSError, subprocess.SubprocessError):
        return {"commit": None, "dirty": None}


def provenance() -> dict:
    return {
        "git": git_commit(),
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "machine": platform.machine(),
        "packages": {name: v for name in PACKAGES if (v := _version(name)) is not None},
        "command": sys.argv,
    }


def write_provenance(folder: str | Path, by: str = "run") -> Path:
    """Write ``provenance.json``. ``by="report"`` (``gomu report`` of a folder without one)
    says so: it records the code that redrew the figures, not the one that ran the runs."""
    path = Path(folder) / "provenance.json"
    record = provenance()
    if by == "report":
        record["written_by"] = ("gomu report: the code that derived the figures and derived tables; the run "
                                "tables predate this record")
    atomic_write_text(path, json.dumps(record, indent=2, sort_keys=True) + "\n")
    return path

"""Write requirements.lock: every package gomu and its extras need, pinned to the installed version.

Run with the project's interpreter after installing the extras:
``.venv/bin/python scripts/lock.py [extra ...]`` (default: every extra in pyproject.toml).
The requirements are read from pyproject.toml, their dependencies from the installed
packages' metadata (importlib.metadata), so the lock pins the environment the tests passed in;
gomu itself is not pinned (installed editable from the checkout).
"""

from __future__ import annotations

import re
import sys
from importlib import metadata
from pathlib import Path

from packaging.markers import default_environment
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def closure(project: dict, extras: list[str]) -> dict[str, str]:
    """{distribution name: installed version} of everything gomu[extras] requires (the
    requirements read from pyproject.toml, their dependencies from installed metadata)."""
    env = default_environment()
    pinned: dict[str, str] = {}
    top = list(project.get("dependencies", []))
    for extra in extras:
        top += project.get("optional-dependencies", {}).get(extra, [])
    todo = [(Requirement(r), set()) for r in top]
    while todo:
        req, wanted = todo.pop()
        if req.marker is not None and not any(req.marker.evaluate({**env, "extra": e}) for e in wanted | {""}):
            continue
        name = _canonical(req.name)
        if name in pinned:
            continue
        try:
            dist = metadata.distribution(req.name)
        except metadata.PackageNotFoundError:
            sys.exit(f"lock: {req.name} is required but not installed; install the extras first")
        pinned[name] = dist.version
        for sub in dist.requires or []:
            todo.append((Requirement(sub), set(req.extras)))
    pinned.pop("gomu", None)
    return pinned


def main(argv: list[str]) -> None:
    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = argv or sorted(project.get("optional-dependencies", {}))
    pins = closure(project, extras)
    import platform

    lines = [f"# gomu[{','.join(extras)}] on Python {sys.version.split()[0]} ({platform.system()} "
             f"{platform.machine()}), written by scripts/lock.py",
             "# installed by scripts/_setup.sh before the project itself (pip install -r requirements.lock)"]
    lines += [f"{name}=={version}" for name, version in sorted(pins.items())]
    (ROOT / "requirements.lock").write_text("\n".join(lines) + "\n")
    print(f"requirements.lock: {len(pins)} packages")


if __name__ == "__main__":
    main(sys.argv[1:])

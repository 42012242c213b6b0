"""Deliberately faulty structures for fault-injection tests (importable as 'fault_models:...')."""

import os
from dataclasses import dataclass
from pathlib import Path

from framework.core.errors import ModelEvaluationError
from framework.structures.lab_frame.model import ThreeDofFrame


@dataclass(frozen=True)
class HoleyFrame(ThreeDofFrame):
    """The 3-DOF frame, but evaluations with kxx above a threshold do not converge."""

    kxx_limit: float = 22000.0

    def modal(self, theta):
        if theta.get("kxx", 0.0) > self.kxx_limit:
            raise ModelEvaluationError("not_converged", f"kxx={theta['kxx']:.0f} beyond the limit")
        return super().modal(theta)

    def modal_batch(self, thetas):
        from framework.models.base import safe_modal

        return [safe_modal(self, t) for t in thetas]


@dataclass(frozen=True)
class DyingFrame(ThreeDofFrame):
    """Kills its process (like a segfault in a native solver) the first time it runs."""

    marker: str = ""

    def modal(self, theta):
        path = Path(self.marker)
        if not path.exists():
            path.write_text("died once")
            os._exit(3)
        return super().modal(theta)

    modal_batch = None


def make_holey(kxx_limit: float = 22000.0):
    return HoleyFrame(kxx_limit=kxx_limit)


def make_dying(marker: str):
    return DyingFrame(marker=marker)

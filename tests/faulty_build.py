"""A deliberately faulty OpenSeesPy build function, for fault-injection tests and fault studies.

A two-storey shear frame as a 1-D spring-mass chain (like examples/own_model.py): storey
stiffnesses k1_n_per_m in [1, 4] MN/m and k2_n_per_m in [0.5, 3] MN/m, floor masses 1000 kg
and 800 kg. With u = (k - lower) / (upper - lower) the normalized coordinates, the build

- raises RuntimeError            for u1 > 1 - s and u2 > 1 - s   (reason "build_failed")
- calls sys.exit(3)              for u1 < s     and u2 > 1 - s   ("model_exit")
- segfaults (SIGSEGV to itself)  for u1 > 1 - s and u2 < s       ("worker_crashed"; kills an
                                                                  unisolated process)
- passes a NaN stiffness to OpenSees for |u1 - 0.5| < s/2 and u2 > 1 - s  ("non_finite_input":
  OpenSeesModel stops NaN at the ``ops`` call; with ``nan_reaches_opensees=True`` the NaN goes
  through a command captured before the guard, and OpenSees either reports undetermined
  eigenvalues ("eigen_failed") or corrupts its heap and aborts ("worker_crashed"), depending
  on the history of the process)
- sleeps ``hang_s`` seconds       for u1 < h     and u2 < h        ("timeout" with an evaluation
                                                                  timeout; hangs otherwise)

with s = ``fault_size`` and h = ``hang_size``, and is a normal model everywhere else. The
measured data are the model's modes at k1 = 2.6 MN/m, k2 = 1.2 MN/m (u = 0.53, 0.28), far from
every fault region, so an optimizer still finds the normal minimum.

In a config::

    structure: {name: "tests.faulty_build:make_model", options: {hang_s: 3600}}
    measured: {builtin: "tests.faulty_build:measured"}
    execution: {isolate: true, evaluation_timeout_s: 5}
"""

from __future__ import annotations

import faulthandler
import os
import signal
import sys
import time

from framework.core.parameters import Parameter, ParameterSet
from framework.measured.modes import MeasuredModes
from framework.models.opensees import OpenSeesModel, ops_module

#: uniaxialMaterial as imported, not the checking wrapper OpenSeesModel installs during a build.
_RAW_UNIAXIAL_MATERIAL = ops_module().uniaxialMaterial

PARAMETERS = ParameterSet([
    Parameter("k1_n_per_m", 2.0e6, 1.0e6, 4.0e6, "N/m", "storey 1 stiffness"),
    Parameter("k2_n_per_m", 1.5e6, 0.5e6, 3.0e6, "N/m", "storey 2 stiffness"),
])
MASSES_KG = (1000.0, 800.0)
TRUTH = {"k1_n_per_m": 2.6e6, "k2_n_per_m": 1.2e6}

#: The failure reason each fault region must produce when evaluated in an isolated worker.
EXPECTED_REASON = {
    "raise": "build_failed",
    "exit": "model_exit",
    "segfault": "worker_crashed",
    "nan": "non_finite_input",
    "hang": "timeout",
}


def normalized(values) -> tuple[float, float]:
    """(u1, u2) of a point in the default bounds."""
    p1, p2 = PARAMETERS
    return ((values["k1_n_per_m"] - p1.lower) / (p1.upper - p1.lower),
            (values["k2_n_per_m"] - p2.lower) / (p2.upper - p2.lower))


def fault_region(values, fault_size: float = 0.15, hang_size: float = 0.05) -> str | None:
    """Name of the fault region holding the point, or None where the model is normal."""
    u1, u2 = normalized(values)
    s = fault_size
    if u1 < hang_size and u2 < hang_size:
        return "hang"
    if u2 > 1 - s:
        if u1 > 1 - s:
            return "raise"
        if u1 < s:
            return "exit"
        if abs(u1 - 0.5) < s / 2:
            return "nan"
    if u1 > 1 - s and u2 < s:
        return "segfault"
    return None


def theta_in(region: str | None, fault_size: float = 0.15, hang_size: float = 0.05) -> dict[str, float]:
    """A point inside ``region`` (None: a normal point), in physical units."""
    s, h = fault_size, hang_size
    u = {"raise": (1 - s / 2, 1 - s / 2), "exit": (s / 2, 1 - s / 2), "segfault": (1 - s / 2, s / 2),
         "nan": (0.5, 1 - s / 2), "hang": (h / 2, h / 2), None: (0.53, 0.28)}[region]
    point = {p.name: p.lower + ui * (p.upper - p.lower) for p, ui in zip(PARAMETERS, u)}
    assert fault_region(point, s, h) == region
    return point


def build(values):
    """Build the chain in the OpenSees domain, misbehaving in the fault regions."""
    ops = ops_module()
    region = fault_region(values, values["fault_size"], values["hang_size"])
    k1, k2 = values["k1_n_per_m"], values["k2_n_per_m"]
    if region == "raise":
        raise RuntimeError(f"faulty build: cannot build with k1={k1:.4g}, k2={k2:.4g}")
    if region == "exit":
        sys.exit(3)
    if region == "segfault":
        faulthandler.disable()  # no traceback dump on stderr for this deliberate crash
        os.kill(os.getpid(), signal.SIGSEGV)
        time.sleep(10.0)  # the signal is delivered at once; never reached
    if region == "hang":
        time.sleep(values["hang_s"])
    material = ops.uniaxialMaterial
    if region == "nan":
        k1 = float("nan")
        if values["nan_reaches_opensees"]:
            faulthandler.disable()  # OpenSees may abort: no traceback dump for this deliberate fault
            material = _RAW_UNIAXIAL_MATERIAL
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    for tag in (0, 1, 2):
        ops.node(tag, 0.0)
    ops.fix(0, 1)
    material("Elastic", 1, k1)
    ops.uniaxialMaterial("Elastic", 2, k2)
    ops.element("zeroLength", 1, 0, 1, "-mat", 1, "-dir", 1)
    ops.element("zeroLength", 2, 1, 2, "-mat", 2, "-dir", 1)
    ops.mass(1, MASSES_KG[0])
    ops.mass(2, MASSES_KG[1])
    return region


def make_model(hang_s: float = 3600.0, fault_size: float = 0.15, hang_size: float = 0.05,
               nan_reaches_opensees: bool = False) -> OpenSeesModel:
    """The faulty chain as an OpenSeesModel (floors measured as 'floor1', 'floor2')."""
    return OpenSeesModel(build, PARAMETERS, measured_dofs={"floor1": (1, 1), "floor2": (2, 1)}, n_modes=2,
                         name="faulty_chain",
                         fixed={"hang_s": float(hang_s), "fault_size": float(fault_size),
                                "hang_size": float(hang_size), "nan_reaches_opensees": bool(nan_reaches_opensees)})


def measured(case: str = "base") -> MeasuredModes:
    """The model's own modes at TRUTH (evaluated in this process: a normal point)."""
    if case != "base":
        raise ValueError(f"unknown measured case {case!r}; only 'base'")
    truth = make_model().modal(TRUTH)
    return MeasuredModes(truth.frequencies_hz, ("floor1", "floor2"), truth.shapes, name="faulty_chain")

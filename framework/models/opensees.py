"""Bring-your-own OpenSeesPy model: a build function plus measured DOFs and analysis options.

The user writes ``build(values: dict[str, float]) -> object`` that creates the model in
the OpenSees domain (nodes, elements, masses and, for a gravity analysis, a load pattern)
from a dict of parameter values. :class:`OpenSeesModel` wipes the domain, calls the build
function, optionally runs a static (gravity) analysis and keeps its state, solves the
eigenproblem K phi = omega^2 M phi and reads the eigenvectors at the measured DOFs
(f = omega / 2 pi). Every built-in OpenSees structure of the framework uses this path.

Eigen solvers (``solver``):

- ``"scipy"`` (default): the tangent stiffness and the mass are extracted from OpenSees
  (:func:`framework.models.opensees_matrices.stiffness_and_mass`: dense ``printA`` of a
  FullGeneral system, Plain numberer, Transformation constraints) and solved with scipy
  (:func:`framework.models.eigen_solve.lowest_modes`: exact condensation of massless DOFs
  and dense eigh up to ``eigen_solve.DENSE_LIMIT`` equations, shift-invert Lanczos with a
  fixed start vector above). The modes are a deterministic, bit-reproducible function of
  theta in any process and whatever ran before; shapes are mass-normalized (phi' M phi = 1,
  kg^-1/2 for translations) with the largest-magnitude measured component positive.
  Frequencies agree with OpenSees' solvers to ~1e-10 (the lowest eigenvalue of a frame with
  stiff springs and light nodes is only determined to ~1e-10 in double precision; this
  solver is the more accurate, see :mod:`framework.models.eigen_solve`). The extraction
  costs O(n^2) memory and time per evaluation for n equations (two dense n x n matrices:
  0.8 MB each at n = 318, the detailed lab frame; 3 MB at n = 624, the bridge): ~5x the time
  of OpenSees' ARPACK for the detailed lab frame, about the same for the bridge's plain path
  (benchmarks/bench_opensees_eigen.py). ``linear_parameters`` removes it for parameters on
  which the stiffness depends linearly (:mod:`framework.models.opensees_linear`: matrices
  extracted once per process, no build per evaluation; ~1.3x ARPACK for the lab frame).
  Measured DOFs on nodes constrained by ``equalDOF``, ``rigidLink`` or ``rigidDiaphragm``
  are recovered from the retained node; for a measured DOF on a node constrained otherwise
  (``equalDOF_Mixed``, ``equationConstraint``, or a command imported by name, which the
  record of :func:`~framework.models.opensees_matrices.recording_constraints` misses) the
  evaluation falls back to OpenSees' deterministic ``-fullGenLapack`` (slow), with the same
  normalization. A ``postprocess`` receives an ``ops`` whose ``nodeEigenvector`` answers
  from these modes.
- an OpenSees eigen flag (``"-genBandArpack"``, ``"-fullGenLapack"``, ``"-symmBandLapack"``,
  or ``""`` for OpenSees' default): OpenSees solves, shapes as OpenSees returns them.
  ARPACK (``-genBandArpack``, the default of ``ops.eigen``) starts from a random vector whose
  generator state persists in the process, so its results differ at ~1e-15 with the history
  of the process; ``-fullGenLapack`` is deterministic but ~25x slower (and reports complex
  eigenvalues for the detailed lab frame at some points of its parameter box).

The build function must be importable at module level (for process and Dask workers).
A build that crashes the process (a segfault in native code, an abort after a NaN reached
OpenSees) or hangs can only be contained by evaluating in an isolated worker
(:mod:`framework.execution.isolation`); exceptions and ``sys.exit()`` in the build become recorded
failures ("build_failed", "model_exit") in any process.
"""

from __future__ import annotations

import contextlib
import logging
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from framework.core.errors import MissingDependencyError, ModelEvaluationError
from framework.core.parameters import ParameterSet
from framework.models.base import ModalResult, full_theta
from framework.models.eigen_solve import lowest_modes, sign_rule
from framework.models.opensees_linear import LinearOperators, extract_linear_operators
from framework.models.opensees_matrices import DofMap, DofRow, recording_constraints, stiffness_and_mass

log = logging.getLogger(__name__)

#: OpenSees direction numbers of a 3D node with 6 DOFs.
DIRECTIONS = {"ux": 1, "uy": 2, "uz": 3, "rx": 4, "ry": 5, "rz": 6}

#: The default solver: matrices extracted from OpenSees, modes from scipy (deterministic).
SCIPY_SOLVER = "scipy"

#: OpenSees solver used when a measured DOF cannot be mapped to equations (deterministic).
FALLBACK_SOLVER = "-fullGenLapack"

#: OpenSees' full generalized LAPACK solver reports an eigenvalue it cannot determine (e.g.
#: after a NaN stiffness reached the domain) as the largest double, not as inf or NaN.
UNDETERMINED_EIGENVALUE = float(np.finfo(float).max)


def ops_module():
    """The openseespy module, imported lazily (it prints a banner and loads a big library)."""
    try:
        import openseespy.opensees as ops
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise MissingDependencyError(
            "openseespy is required for OpenSees models: pip install openseespy (Python 3.12)"
        ) from exc
    return ops


@dataclass(frozen=True)
class GravityAnalysis:
    """Options of the static analysis run before the eigen analysis.

    The build function must define the loads (e.g. ``timeSeries('Constant', 1)``,
    ``pattern('Plain', 1, 1)`` and nodal or element loads). The analysis is load-controlled
    in ``steps`` increments with Newton iterations; the converged state is kept
    (``loadConst``) so that the eigen analysis sees the deformed, stressed structure.
    """

    steps: int = 1
    tolerance: float = 1e-8
    max_iterations: int = 50
    system: str = "UmfPack"
    numberer: str = "RCM"
    constraints: str = "Transformation"
    algorithm: str = "Newton"


@dataclass(frozen=True)
class OpenSeesModel:
    """A structural model defined by a user's OpenSeesPy build function.

    build: ``build(values) -> info``; values holds every parameter (initial values
    overridden by the evaluated point) plus ``fixed``. measured_dofs: {label: (node tag,
    direction)} with direction 1..6 or a name from :data:`DIRECTIONS`. n_modes: modes
    to compute. gravity: :class:`GravityAnalysis` or None. solver: "scipy" (default,
    deterministic) or an OpenSees eigen flag ("-genBandArpack", "-fullGenLapack",
    "-symmBandLapack", "" for OpenSees' default), see the module docstring. postprocess:
    optional ``postprocess(result, info, ops) -> ModalResult`` called while the domain is
    alive (e.g. to classify modes by kinetic energy); ``info`` is what build returned.
    dof_scale: optional {label: factor} applied to the shape rows (e.g. b/2 for a
    rotation compared with translations). linear_parameters: parameters on which the
    stiffness depends linearly and the mass not at all (solver "scipy", no gravity, no
    postprocess): matrices extracted once per process, no build for evaluations that change
    only these (:mod:`framework.models.opensees_linear`).
    """

    build: Callable[[dict[str, float]], Any]
    parameters: ParameterSet
    measured_dofs: Mapping[str, tuple[int, int | str]]
    n_modes: int = 10
    gravity: GravityAnalysis | None = None
    solver: str = SCIPY_SOLVER
    fixed: Mapping[str, Any] = field(default_factory=dict)
    postprocess: Callable[[ModalResult, Any, Any], ModalResult] | None = None
    dof_scale: Mapping[str, float] = field(default_factory=dict)
    name: str = "opensees"
    linear_parameters: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not callable(self.build):
            raise TypeError(f"build must be callable, got {self.build!r}")
        if self.n_modes < 1:
            raise ValueError(f"n_modes must be >= 1, got {self.n_modes}")
        if self.solver != SCIPY_SOLVER and self.solver and not self.solver.startswith("-"):
            raise ValueError(f"solver must be {SCIPY_SOLVER!r} or an OpenSees eigen flag such as '-genBandArpack', "
                             f"got {self.solver!r}")
        resolved = {}
        for label, (node, direction) in self.measured_dofs.items():
            if isinstance(direction, str):
                if direction not in DIRECTIONS:
                    raise ValueError(
                        f"measured DOF {label!r}: unknown direction {direction!r}; "
                        f"use 1..6 or one of {list(DIRECTIONS)}"
                    )
                direction = DIRECTIONS[direction]
            resolved[str(label)] = (int(node), int(direction))
        object.__setattr__(self, "measured_dofs", resolved)
        object.__setattr__(self, "linear_parameters", tuple(str(n) for n in self.linear_parameters))
        unknown = [n for n in self.linear_parameters if n not in self.parameters.names]
        if unknown:
            raise ValueError(f"linear_parameters: unknown parameter(s) {unknown}; known: {self.parameters.names}")
        if self.linear_parameters and (self.solver != SCIPY_SOLVER or self.gravity is not None or self.postprocess):
            raise ValueError("linear_parameters needs solver 'scipy', no gravity analysis and no postprocess")

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.pop("_linear", None)  # operators are extracted again in each process
        return state

    @property
    def dofs(self) -> tuple[str, ...]:
        return tuple(self.measured_dofs)

    def modal(self, theta: Mapping[str, float]) -> ModalResult:
        values: dict[str, Any] = dict(self.fixed)
        values.update(full_theta(self.parameters, theta))
        if self.linear_parameters:
            operators = self._linear_operators()
            if operators.covers(values):
                omega2, shapes, _ = self._solve(operators.stiffness(values), operators.mass, operators.rows)
                return self._result(omega2, shapes)
        ops = ops_module()
        try:
            info, constraints = self._build_domain(ops, values)
            if self.gravity is not None:
                run_static(ops, self.gravity)
            if self.solver == SCIPY_SOLVER:
                omega2, shapes, view = self._scipy_modes(ops, constraints)
            else:
                omega2 = eigen(ops, self.n_modes, self.solver)
                shapes = self._opensees_shapes(ops, omega2.size)
                view = ops
            result = self._result(omega2, shapes)
            if self.postprocess is not None:
                result = self.postprocess(result, info, view)
            return result
        finally:
            ops.wipe()

    def _result(self, omega2: np.ndarray, shapes: np.ndarray) -> ModalResult:
        freqs = np.sqrt(np.maximum(omega2, 0.0)) / (2.0 * math.pi)
        return ModalResult(freqs, shapes, self.dofs, meta={"omega2": omega2})

    def _build_domain(self, ops, values: dict[str, Any]) -> tuple[Any, list]:
        """Wipe the domain and run the build; (what build returned, recorded MP constraints)."""
        ops.wipe()
        try:
            with finite_arguments(ops), recording_constraints(ops) as constraints:
                info = self.build(values)
        except ModelEvaluationError:
            raise
        except SystemExit as exc:  # sys.exit() in a build must not end the study
            raise ModelEvaluationError("model_exit", f"the build function called sys.exit({exc.code!r})") from exc
        except Exception as exc:  # a user's build function can raise anything
            raise ModelEvaluationError("build_failed", f"{type(exc).__name__}: {exc}") from exc
        return info, constraints

    def _linear_operators(self) -> LinearOperators:
        """Operators of :mod:`framework.models.opensees_linear`, extracted on first use in a process."""
        cached = self.__dict__.get("_linear")
        if cached is None:
            base: dict[str, Any] = dict(self.fixed)
            base.update(full_theta(self.parameters, {}))
            steps = {}
            for p in self.parameters:
                if p.name in self.linear_parameters:
                    steps[p.name] = abs(float(base[p.name])) or float(p.upper - p.lower)
            try:
                cached = extract_linear_operators(self._extract_at, base, self.linear_parameters, steps)
            except ModelEvaluationError as exc:
                cached = exc  # every evaluation relying on it fails the same way, without re-extracting
            object.__setattr__(self, "_linear", cached)
        if isinstance(cached, ModelEvaluationError):
            raise ModelEvaluationError(cached.reason, cached.detail)
        return cached

    def _extract_at(self, values: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, list[DofRow]]:
        """(K, M, rows of the measured DOFs) of the model built at ``values``."""
        ops = ops_module()
        try:
            _, constraints = self._build_domain(ops, values)
            stiffness, mass = stiffness_and_mass(ops)
            dof_map = DofMap(ops, constraints)
            rows = [dof_map.row(node, direction) for node, direction in self.measured_dofs.values()]
        finally:
            ops.wipe()
        if any(row is None for row in rows):
            raise ModelEvaluationError(
                "unmapped_constraint", "a measured DOF lies on a node with an unrecorded multi-point constraint"
            )
        return stiffness, mass, rows

    def _solve(self, stiffness: np.ndarray, mass: np.ndarray, rows) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(omega^2, measured shapes, equation-space shapes): mass-normalized, largest measured component > 0."""
        omega2, phi = lowest_modes(stiffness, mass, self.n_modes)
        shapes = np.array([row.of(phi) for row in rows]).reshape(len(rows), -1) * self._scale()[:, None]
        signs = sign_rule(shapes, phi)
        return omega2, shapes * signs, phi * signs

    def _scale(self) -> np.ndarray:
        return np.array([float(self.dof_scale.get(label, 1.0)) for label in self.measured_dofs])

    def _opensees_shapes(self, ops, n_modes: int) -> np.ndarray:
        """Shapes at the measured DOFs as OpenSees' last eigen analysis left them."""
        shapes = np.empty((len(self.measured_dofs), n_modes))
        for i, (node, direction) in enumerate(self.measured_dofs.values()):
            for j in range(n_modes):
                shapes[i, j] = ops.nodeEigenvector(node, j + 1, direction)
        return shapes * self._scale()[:, None]

    def _scipy_modes(self, ops, constraints) -> tuple[np.ndarray, np.ndarray, Any]:
        """(omega^2, measured shapes, ops view for postprocess) from extracted K and M.

        Shapes are mass-normalized with the largest-magnitude measured component positive.
        """
        stiffness, mass = stiffness_and_mass(ops)
        dof_map = DofMap(ops, constraints)
        rows = [dof_map.row(node, direction) for node, direction in self.measured_dofs.values()]
        if any(row is None for row in rows):
            return self._fallback_modes(ops, dof_map, mass)
        omega2, shapes, phi = self._solve(stiffness, mass, rows)
        return omega2, shapes, ModeShapeOps(ops, dof_map, phi)

    def _fallback_modes(self, ops, dof_map: DofMap, mass: np.ndarray) -> tuple[np.ndarray, np.ndarray, Any]:
        """OpenSees' deterministic full LAPACK solver, normalized as :meth:`_scipy_modes`."""
        log.warning(
            "%s: a measured DOF lies on a node whose multi-point constraint is not known (not created "
            "through ops.equalDOF/rigidLink/rigidDiaphragm); solving with OpenSees' %s",
            self.name,
            FALLBACK_SOLVER,
        )
        omega2 = eigen(ops, self.n_modes, FALLBACK_SOLVER)
        phi = np.zeros((mass.shape[0], omega2.size))
        for node in ops.getNodeTags():
            rows = dof_map.node_rows(node)
            if rows is None:
                continue
            for dof, row in enumerate(rows, start=1):
                if row.equations.size == 1 and row.coefficients[0] == 1.0:
                    phi[row.equations[0]] = [ops.nodeEigenvector(node, j + 1, dof) for j in range(omega2.size)]
        norms = np.sqrt(np.einsum("ij,ij->j", phi, mass @ phi))
        shapes = self._opensees_shapes(ops, omega2.size) / norms
        signs = sign_rule(shapes, phi / norms)
        return omega2, shapes * signs, ops


class ModeShapeOps:
    """The ``ops`` module as a postprocess sees it after the scipy solution: every command is
    OpenSees' except ``nodeEigenvector(node, mode[, dof])``, answered from the scipy modes."""

    def __init__(self, ops, dof_map: DofMap, phi: np.ndarray):
        self._ops = ops
        self._dof_map = dof_map
        self._phi = phi

    def __getattr__(self, name: str):
        return getattr(self._ops, name)

    def nodeEigenvector(self, node: int, mode: int, dof: int | None = None):  # noqa: N802 - OpenSees' name
        if not 1 <= mode <= self._phi.shape[1]:
            raise ModelEvaluationError("postprocess_failed", f"nodeEigenvector: mode {mode} of {self._phi.shape[1]}")
        rows = self._dof_map.node_rows(node)
        if rows is None:
            raise ModelEvaluationError(
                "unmapped_constraint",
                f"nodeEigenvector: node {node} is constrained by a multi-point constraint that was not recorded; "
                "use an OpenSees solver flag",
            )
        q = self._phi[:, mode - 1]
        if dof is not None:
            return float(rows[dof - 1].of(q))
        return [float(row.of(q)) for row in rows]


_checked_commands: dict[str, Callable] = {}
_guard_depth = 0


def _non_finite(value) -> bool:
    if isinstance(value, float | np.floating):
        return not math.isfinite(value)
    if isinstance(value, list | tuple | np.ndarray):
        return any(_non_finite(v) for v in np.asarray(value, dtype=object).ravel())
    return False


def _checking(name: str, command: Callable) -> Callable:
    def checked(*args):
        for value in args:
            kind = type(value)
            if kind is float:  # the common case first: NaN fails both comparisons
                if -math.inf < value < math.inf:
                    continue
            elif kind is int or kind is str or not _non_finite(value):
                continue
            raise ModelEvaluationError("non_finite_input", f"ops.{name} got {value!r} in {args!r}")
        return command(*args)

    checked.__name__ = checked.__qualname__ = name
    checked.__doc__ = command.__doc__
    return checked


@contextlib.contextmanager
def finite_arguments(ops):
    """Within the block every command of the ``ops`` module rejects NaN and infinite numbers
    with ModelEvaluationError("non_finite_input").

    OpenSees does not reject them: given a NaN stiffness, its full LAPACK eigen solver reports
    undetermined eigenvalues and leaves a corrupted heap that aborts the process at once or at
    a later, valid evaluation. The module's commands are swapped for checking wrappers while a
    build function runs, so builds calling ``ops.command(...)`` are covered; commands imported
    by name (``from openseespy.opensees import node``) are not: evaluate such models in an
    isolated worker (:mod:`framework.execution.isolation`).
    """
    global _guard_depth
    if _guard_depth:  # already guarded (a build inside a build)
        yield
        return
    if not _checked_commands:
        for name in dir(ops):
            command = getattr(ops, name)
            if not name.startswith("_") and type(command).__name__ == "builtin_function_or_method":
                _checked_commands[name] = _checking(name, command)
    originals = {name: getattr(ops, name) for name in _checked_commands}
    for name, checked in _checked_commands.items():
        setattr(ops, name, checked)
    _guard_depth += 1
    try:
        yield
    finally:
        _guard_depth -= 1
        for name, command in originals.items():
            setattr(ops, name, command)


def run_static(ops, options: GravityAnalysis) -> None:
    """Load-controlled static analysis; raises ModelEvaluationError('not_converged')."""
    ops.system(options.system)
    ops.numberer(options.numberer)
    ops.constraints(options.constraints)
    ops.test("NormDispIncr", options.tolerance, options.max_iterations)
    ops.algorithm(options.algorithm)
    ops.integrator("LoadControl", 1.0 / options.steps)
    ops.analysis("Static")
    status = ops.analyze(options.steps)
    if status != 0:
        raise ModelEvaluationError(
            "not_converged", f"static analysis returned {status} ({options.steps} steps)"
        )
    ops.loadConst("-time", 0.0)


def eigen(ops, n_modes: int, solver: str = "-genBandArpack") -> np.ndarray:
    """Eigenvalues omega^2 of the current domain; raises on failure or missing modes."""
    try:
        values = ops.eigen(solver, n_modes) if solver else ops.eigen(n_modes)
    except Exception as exc:  # openseespy raises OpenSeesError
        raise ModelEvaluationError("eigen_failed", str(exc)) from exc
    values = np.atleast_1d(np.asarray(values, dtype=float))
    if values.size < n_modes:
        raise ModelEvaluationError("too_few_modes", f"got {values.size} of {n_modes} modes")
    if not np.all(np.isfinite(values)) or np.any(np.abs(values) >= UNDETERMINED_EIGENVALUE):
        raise ModelEvaluationError("eigen_failed", f"non-finite or undetermined eigenvalues {values.tolist()}")
    if np.any(values < -1e-6 * max(1.0, float(np.max(np.abs(values))))):
        raise ModelEvaluationError("indefinite_matrix", f"negative eigenvalue {values.min():.4g}")
    return values

"""The ``status`` column of result tables: one vocabulary for every run kind.

Every run kind writes one row per run into its first table (``runs``, ``points``,
``summary``), and some kinds one row per sub-result (the ``states`` of a damage run), each with
a ``status`` from :class:`Status` and an ``error`` text (empty unless the status is a failure).
A status says whether the row holds a usable result and, for an optimizer, why it stopped:

========================  ========================================================================
status                    meaning
========================  ========================================================================
``ok``                    finished with a usable result (kinds without a finer reason: an
                          analysis point, an identification, a damage procedure, a diagnosis, a
                          sampled posterior)
``target``                an optimizer stopped: best objective below ``budget.target_objective``
``stalled``               an optimizer stopped: best improved by less than ``stall_tolerance``
                          over ``stall_iterations`` iterations
``converged``             an optimizer stopped by its own convergence test (least squares'
                          tolerances, the pseudo-inverse step, annealing's end)
``budget``                an optimizer stopped: the next iteration would exceed
                          ``max_evaluations``
``max_iterations``        an optimizer stopped after ``budget.max_iterations`` iterations
``completed``             an optimizer did everything it was asked (SNT found ``n_minima`` minima,
                          a screening evaluated every point)
``max_generations``       NSGA-II ran all its ``n_generations`` generations
``not_converged``         the sensitivity method stopped without converging (least squares gave
                          up, or its last iterate failed); its best successful point is the result
``failed``                finished without a usable result: the model failed at every point, no
                          mode was identified, an optimizer of a procedure failed, the data or
                          calibration of a diagnosis failed (``error`` says why)
``error``                 an exception ended the run: the engine's failure row (``error`` and the
                          last frames in ``traceback``), or a kind that keeps its partial rows
========================  ========================================================================

Every status but ``failed`` and ``error`` is a success (:func:`succeeded`). Tables written
before this vocabulary used ``completed`` for a finished diagnosis or posterior; it reads as a
success too.
"""

from __future__ import annotations

from enum import StrEnum


class Status(StrEnum):
    """The status of a result row (module docstring: what each means)."""

    OK = "ok"
    TARGET = "target"
    STALLED = "stalled"
    CONVERGED = "converged"
    BUDGET = "budget"
    MAX_ITERATIONS = "max_iterations"
    COMPLETED = "completed"
    MAX_GENERATIONS = "max_generations"
    NOT_CONVERGED = "not_converged"
    FAILED = "failed"
    ERROR = "error"


#: the statuses of a row without a usable result
FAILURES: frozenset[str] = frozenset({Status.FAILED, Status.ERROR})


def succeeded(status) -> bool:
    """True when a row of this status holds a usable result (not ``failed`` or ``error``)."""
    return status not in FAILURES


def error_text(exc: BaseException) -> str:
    """The ``error`` text of a failure row: ``"<exception type>: <message>"``."""
    return f"{type(exc).__name__}: {exc}"

"""The one pymoo ``Problem`` wrapper of a run's evaluator, used by the GA and NSGA-II adapters.

pymoo evaluates a whole population at once: ``_evaluate(X)`` forwards it to the run's
:class:`~framework.updating.evaluator.Evaluator` in normalized coordinates [0, 1]^k, which counts
the evaluations. One objective: the scalar Pi (n, 1); several: the objective vectors
``evaluator.objectives(X)`` (n, n_obj).
"""

from __future__ import annotations

import numpy as np


def pymoo_problem(evaluator, n_obj: int = 1):
    """A pymoo Problem on [0, 1]^k whose evaluation goes through ``evaluator``."""
    from pymoo.core.problem import Problem

    k = evaluator.n_params

    class EvaluatorProblem(Problem):
        def __init__(self):
            super().__init__(n_var=k, n_obj=n_obj, xl=np.zeros(k), xu=np.ones(k))

        def _evaluate(self, X, out, *args, **kwargs):
            if n_obj == 1:
                out["F"] = evaluator.objective(X)[:, None]
            else:
                out["F"] = np.asarray(evaluator.objectives(X), dtype=float)

    return EvaluatorProblem()

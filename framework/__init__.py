"""gomu: dynamic model updating of civil structures with global optimization.

Entry points: :class:`framework.updating.problem.UpdatingProblem` (one problem, scalar / residual /
multi-objective views), :func:`framework.optimizers.run_optimizer` (pso, ga, annealing, sm,
snt, nsga2), :class:`framework.models.opensees.OpenSeesModel` (bring your own OpenSeesPy
model), :mod:`framework.study` (config-driven studies, ``gomu run``) and
:mod:`framework.diagnosis` (``gomu diagnose``).
"""

__version__ = "0.1.0"

"""Exceptions of the framework.

InputError: bad user input (config, data file, parameter); the message names the file,
field and offending value. ModelEvaluationError: one model evaluation failed (analysis
did not converge, singular matrix, too few modes); the problem turns it into a penalty
and records its reason, the study goes on.
"""


class InputError(ValueError):
    """Invalid user input; the message names the source, field and value."""


class ModelEvaluationError(RuntimeError):
    """A structural model could not be evaluated at a parameter point.

    reason: short machine-readable category ("not_converged", "singular_matrix",
    "too_few_modes", "eigen_failed", "worker_died", ...); the message adds detail.
    """

    def __init__(self, reason: str, message: str = ""):
        super().__init__(f"{reason}: {message}" if message else reason)
        self.reason = reason
        self.detail = message


class MissingDependencyError(ImportError):
    """An optional dependency is not installed; the message names the extra to install."""

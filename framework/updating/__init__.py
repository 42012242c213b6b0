"""The updating problem: objective formulations, the stateless problem, the per-run evaluator and
sensitivities."""

"""Inference from measured modes (below the updating layer: an updating problem is taken
duck-typed, nothing here imports :mod:`framework.updating`):

- :mod:`.noise`: the one noise model, the standard deviation of each datum and its source, the
  assumed defaults (defined once) and the chi-square noise test;
- :mod:`.gaussian`: whitened residuals of paired modes, one definition for a point and a population;
- :mod:`.likelihood`: the likelihood from a problem's residuals (each formulation scales its own)
  and the priors;
- :mod:`.linearized`: the linearized posterior and identifiability; :mod:`.sampling`: MCMC and
  nested sampling; :mod:`.evidence`: Laplace evidence; :mod:`.tables`: the linearized columns
  of an updating run;
- :mod:`.simulate`: the one simulator of noisy measured modes.

See docs/uncertainty.md and docs/noise.md."""

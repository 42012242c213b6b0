"""Where model evaluations and runs execute: isolated worker processes, process pools, Dask."""

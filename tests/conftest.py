"""Test configuration: single-threaded BLAS (small dense problems; tests run side by side)."""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")

try:  # numpy may already be imported by a plugin: limit the live thread pools too
    from threadpoolctl import threadpool_limits

    threadpool_limits(1)
except ImportError:  # pragma: no cover
    pass

import pytest  # noqa: E402


@pytest.fixture(autouse=True)
def _stored_rows_use_the_status_vocabulary(monkeypatch):
    """Every row a study of the test suite stores, of every kind and table, has a status of the
    one vocabulary (:class:`framework.core.status.Status`), checked as the run's part is written."""
    from framework.core.status import Status
    from framework.study.store import ResultStore

    write = ResultStore.write_run
    known = set(Status)

    def checked(self, run_id, tables, study="", kind=""):
        bad = {(name, row["status"]) for name, rows in tables.items() for row in rows
               if "status" in row and row["status"] not in known}
        assert not bad, f"run {run_id} of kind {kind!r}: statuses outside the vocabulary: {sorted(bad)}"
        return write(self, run_id, tables, study=study, kind=kind)

    monkeypatch.setattr(ResultStore, "write_run", checked)

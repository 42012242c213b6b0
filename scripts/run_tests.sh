#!/usr/bin/env bash
# Quick start 2: set up (first time) and run the default (fast) test suite.
# Extra arguments go to pytest, e.g. `-m slow` for the long tests.
source "$(dirname "$0")/_setup.sh"
.venv/bin/ruff check framework tests studies benchmarks examples
.venv/bin/python -m pytest -p no:cacheprovider "$@"

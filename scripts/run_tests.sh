#!/usr/bin/env bash
# Quick start 2: set up (first time), lint, build the docs site (strict) and run the default
# (fast) test suite.
# Extra arguments go to pytest, e.g. `-m slow` for the long tests.
source "$(dirname "$0")/_setup.sh"
.venv/bin/ruff check framework tests studies benchmarks examples scripts docs/hooks
# the documentation site, warnings as errors (mkdocs.yml: strict)
NO_MKDOCS_2_WARNING=1 .venv/bin/mkdocs build --strict --quiet --site-dir "$(mktemp -d)"
.venv/bin/python -m pytest -p no:cacheprovider "$@"

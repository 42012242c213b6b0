#!/usr/bin/env bash
# Quick start 1: set up (first time) and run the main job, the laboratory-frame study.
# Writes tables and figures to results/lab_frame/. Extra arguments go to `gomu run`.
source "$(dirname "$0")/_setup.sh"
.venv/bin/gomu run studies/lab_frame.yaml "$@"

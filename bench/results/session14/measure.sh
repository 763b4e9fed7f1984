#!/bin/bash
# The fourteenth session's runs: bench/measure_targets.sh with the floor in the thread runs.
# Run from the repository root; outputs go to the directory given (default: beside this script).
exec bash "$(dirname "$0")/../../measure_targets.sh" "${1:-$(dirname "$0")}"

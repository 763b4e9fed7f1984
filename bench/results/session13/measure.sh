#!/bin/bash
# The thirteenth session's runs: bench/measure_targets.sh without the floor in the thread runs
# (--no-floor there) and with one warm-up call in the CPU vs OpenCL run, as they ran. Run from
# the repository root; outputs go to the directory given (default: beside this script).
SCALING_FLOOR=0 BACKENDS_WARMUP=1 exec bash "$(dirname "$0")/../../measure_targets.sh" "${1:-$(dirname "$0")}"

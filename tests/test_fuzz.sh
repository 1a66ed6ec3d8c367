#!/usr/bin/env bash
# Script test (make test): a short bounded libFuzzer pass of every
# tests/fuzz/fuzz_*.c target under ASan/UBSan, 4 s each (FUZZ_TEST_SECONDS;
# five targets on two cores: 12 s in all, after their corpora; `make fuzz`
# runs them 60 s each), one target per core at once.
# Fails on any crash, sanitizer report or build failure.
set -euo pipefail
cd "$(dirname "$0")/.."
# Built at -O0: the corpora replayed and 4 s explored need no optimised
# build, and it compiles in half the CPU time (`make fuzz` builds at -O1).
FUZZ_OPT=${FUZZ_OPT:--O0} exec bash tests/fuzz/run.sh "${FUZZ_TEST_SECONDS:-4}"

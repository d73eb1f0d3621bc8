#!/usr/bin/env bash
# The test command: installs dependencies (apt), builds, and runs the whole test suite with ctest.
# Each phase prints its wall time, so that a CI log shows where the minutes go (docs/RELIABILITY.md).
set -euo pipefail
cd "$(dirname "$0")/.."
phase() { local start=$SECONDS; "$@"; echo "test.sh: '$*' took $((SECONDS - start)) s" >&2; }
phase bash scripts/setup.sh
phase bash scripts/build.sh
phase ctest --test-dir build --output-on-failure -j 2
# Sanitizers (ASan+UBSan tree: fast tests and the CLI on every bad input; TSan on Segmenters in threads)
# and every fuzzer for FUZZ_SECONDS (default 10): docs/RELIABILITY.md.
phase bash scripts/sanitize.sh

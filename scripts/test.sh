#!/usr/bin/env bash
# The test command: installs dependencies (apt), builds, and runs the whole test suite with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j 2
# Sanitizers (ASan+UBSan tree: fast tests and the CLI on every bad input; TSan on Segmenters in threads)
# and every fuzzer for FUZZ_SECONDS (default 10): docs/RELIABILITY.md.
bash scripts/sanitize.sh

#!/usr/bin/env bash
# The first-run command: installs dependencies (apt), builds, and segments the bundled example frame.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
./build/clutterseg segment examples/osd-test50 --out out/example
echo "Wrote out/example: label/, patch/, debug/test50/*.png and test50.json"

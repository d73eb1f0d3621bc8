#!/usr/bin/env bash
# The first-run command: installs dependencies (apt), builds, segments the bundled example frame, and
# installs the Python package into .venv.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
./build/clutterseg segment examples/osd-test50 --out out/example
echo "Wrote out/example: label/, patch/, debug/test50/*.png and test50.json"
bash scripts/install_python.sh .venv   # the Python package, into .venv (Debian's python3 and NumPy)

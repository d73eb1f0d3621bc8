#!/usr/bin/env bash
# Installs the Python package `clutterseg` into a virtual environment that also sees Debian's packages
# (NumPy, matplotlib): builds a wheel from the module scripts/build.sh compiled (build/python) and
# installs it offline. Debian's own pip refuses to install into the system python (PEP 668).
# Usage: scripts/install_python.sh [VENV]   (default .venv; then VENV/bin/python3 -c "import clutterseg")
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${1:-.venv}"
stage=build/python
if ! compgen -G "$stage/clutterseg/_clutterseg*.so" >/dev/null; then
  echo "install_python.sh: $stage/clutterseg has no compiled module; run scripts/setup.sh and scripts/build.sh first" >&2
  exit 1
fi
# The wheel is built from a copy, so nothing is written beside the module the tests import.
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cp -r "$stage/pyproject.toml" "$stage/setup.py" "$stage/clutterseg" "$tmp/"
rm -rf "$tmp/clutterseg/__pycache__"
/usr/bin/python3 -m build --no-isolation --wheel --outdir "$tmp/dist" "$tmp" >"$tmp/build.log" 2>&1 ||
  { cat "$tmp/build.log" >&2; exit 1; }
mkdir -p "$stage/dist"
rm -f "$stage"/dist/clutterseg-*.whl
cp "$tmp"/dist/clutterseg-*.whl "$stage/dist/"
[ -x "$venv/bin/python3" ] || /usr/bin/python3 -m venv --system-site-packages "$venv"
# --no-deps: NumPy comes from Debian (the environment sees the system's packages).
"$venv/bin/python3" -m pip install -q --disable-pip-version-check --no-index --no-build-isolation --no-deps --force-reinstall "$stage"/dist/clutterseg-*.whl
echo "Installed $(basename "$stage"/dist/clutterseg-*.whl) into $venv: $venv/bin/python3 -c 'import clutterseg'"

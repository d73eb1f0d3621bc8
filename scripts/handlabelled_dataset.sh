#!/usr/bin/env bash
# The hand-labelled regression set (data/handlabelled/, docs/RESULTS.md) as a dataset folder that
# `clutterseg eval` reads: the depth and colour frames of ../shared/data/dev/<set> beside our labels.
#   scripts/handlabelled_dataset.sh [OUT=out/handlabelled]          assemble OUT/<set>/
#   scripts/handlabelled_dataset.sh --relabel                       redraw data/handlabelled/*/label/ from the specs
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
shared=${CLUTTERSEG_SHARED:-$root/../shared/data/dev}
if [ "${1:-}" = "--relabel" ]; then
  for spec in "$root"/data/handlabelled/*/spec/*.json; do
    set_dir=$(dirname "$(dirname "$spec")"); set=$(basename "$set_dir"); name=$(basename "$spec" .json)
    /usr/bin/python3 "$root/scripts/label_frame.py" "$shared/$set" "$name" "$spec" "$set_dir/label/$name.png" \
      --preview "$root/out/handlabelled-previews/$set-$name.png"
  done
  exit 0
fi
out=${1:-$root/out/handlabelled}
for set_dir in "$root"/data/handlabelled/*/; do
  set=$(basename "$set_dir")
  rm -rf "$out/$set"; mkdir -p "$out/$set/depth" "$out/$set/color" "$out/$set/label"
  cp "$shared/$set/camera.json" "$out/$set/"
  for label in "$set_dir"/label/*.png; do
    name=$(basename "$label")
    cp "$label" "$out/$set/label/"
    ln -s "$shared/$set/depth/$name" "$out/$set/depth/$name"
    [ -f "$shared/$set/color/$name" ] && ln -s "$shared/$set/color/$name" "$out/$set/color/$name"
  done
  echo "Wrote $out/$set: $(ls "$out/$set/label" | wc -l) hand-labelled frames"
done

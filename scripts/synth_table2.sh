#!/usr/bin/env bash
# Writes the synthetic Table II families (paper Table II: boxes, stacked boxes, occluded, cylinders,
# mixed, complex) as one labelled dataset whose scenes.json names each frame's family, so that
# `clutterseg eval OUT` prints one row per family.
#   scripts/synth_table2.sh OUT [FRAMES=20] [SEED=11] [SENSOR=kinect-v1] [SIZE=640x480]
set -euo pipefail
out=${1:?usage: scripts/synth_table2.sh OUT [FRAMES] [SEED] [SENSOR] [SIZE]}
frames=${2:-20}; seed=${3:-11}; sensor=${4:-kinect-v1}; size=${5:-640x480}
cli=${CLUTTERSEG:-$(dirname "$0")/../build/clutterseg}
families="boxes stacked-boxes occluded cylinders mixed complex"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/all/depth" "$tmp/all/label" "$tmp/all/color"
entries=()
for f in $families; do
  "$cli" synth --preset "$f" --frames "$frames" --seed "$seed" --sensor "$sensor" --size "$size" --out "$tmp/$f" >/dev/null
  for d in "$tmp/$f"/depth/*.png; do
    n=$(basename "$d" .png)
    for k in depth label color; do
      [ -f "$tmp/$f/$k/$n.png" ] && mv "$tmp/$f/$k/$n.png" "$tmp/all/$k/$f-$n.png"
    done
    entries+=("{\"name\": \"$f-$n\", \"family\": \"$f\"}")
  done
  cp "$tmp/$f/camera.json" "$tmp/all/camera.json"
done
(IFS=,; echo "{\"frames\": [${entries[*]}]}") > "$tmp/all/scenes.json"
rm -rf "$out"; mkdir -p "$(dirname "$out")"; mv "$tmp/all" "$out"
echo "Wrote $out: $(ls "$out/depth" | wc -l) frames of $families"

#!/usr/bin/env bash
# Instructions per frame of the whole pipeline and of each stage, counted by callgrind: a speed measure
# that does not move with the load of a shared host (wall-clock runs here differ by up to 60 %).
#   scripts/count_instructions.sh [DATASET] [extra `clutterseg bench` flags, e.g. --subsample 2]
# Needs valgrind (apt-get install valgrind) and a build in build/. One core (taskset), so that bench times
# only its one-thread pass; the figures are averages over every call, the warm-up frame included.
set -euo pipefail
cd "$(dirname "$0")/.."
dataset=${1:-../shared/data/dev/osd-kinect}
shift || true
command -v valgrind >/dev/null || { echo "count_instructions.sh: valgrind not found (apt-get install valgrind)" >&2; exit 1; }
[ -x build/clutterseg ] || { echo "count_instructions.sh: build/clutterseg not found (build first)" >&2; exit 1; }
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
taskset -c 0 valgrind --tool=callgrind --callgrind-out-file="$out/cg.out" \
  build/clutterseg bench "$dataset" --repeat 1 "$@" >/dev/null 2>"$out/log" ||
  { echo "count_instructions.sh: valgrind run failed, see:" >&2; tail -5 "$out/log" >&2; exit 1; }
callgrind_annotate --inclusive=yes --tree=calling "$out/cg.out" 2>/dev/null | python3 -c '
import re, sys
# Inclusive cost of every stage function as called from the pipeline, divided by the pipeline calls.
stages = ["median_depth", "TemporalSmoother::push", "depth_to_points", "compute_normals", "normal_edge_value",
          "edge_mask", "extract_patches", "assign_edge_pixels", "cut_free_pairs", "coplanar_pairs",
          "curvature_links", "cut_graph", "assign_remaining", "describe_objects", "find_support_plane", "cut_off_table",
          "split_at_planes", "split_at_seams", "split_cut_patches", "release_from_table", "claim_enclosed_floors", "classify_junctions", "classify_objects", "support_of"]
cost, inside = {}, False
for line in sys.stdin:
    m = re.match(r"\s*([\d,]+) \([^)]*\)\s+(\*|>)\s+\S*?clutterseg::([\w:]+)\(.*?\((\d+)x\)", line)
    # The pipeline function itself, not the lambdas inside it (their names start with its own).
    star = re.match(r"\s*[\d,]+ \([^)]*\)\s+\*\s+\S*?clutterseg::Segmenter::segment\(", line) and "{lambda" not in line
    if re.match(r"\s*[\d,]+ \([^)]*\)\s+\*", line): inside = bool(star)
    if star:
        total = int(line.split()[0].replace(",", ""))
    if inside and m and m.group(2) == ">" and m.group(3) in stages:
        cost[m.group(3)] = (int(m.group(1).replace(",", "")), int(m.group(4)))
# Per frame: divided by the calls of compute_normals, which runs once per frame (extract_patches runs
# again after a split).
calls = cost["compute_normals"][1] if "compute_normals" in cost else max((c for _, c in cost.values()), default=1)
print("instructions per frame [million], mean over %d pipeline calls" % calls)
for s in stages:
    if s in cost: print("  %-24s %8.2f" % (s, cost[s][0] / calls / 1e6))
print("  %-24s %8.2f" % ("whole pipeline", total / calls / 1e6))
'

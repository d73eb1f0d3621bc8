#!/usr/bin/env bash
# Runs every libFuzzer harness for SECONDS each (default 30) from the seed corpus in fuzz/corpus/, with
# the ASan+UBSan tree of scripts/sanitize.sh (built first if missing). Prints executions per fuzzer;
# exits non-zero when one finds a crash, a sanitizer report, a leak or a timeout (its input is kept in
# build-san/fuzz-findings/). Usage: scripts/fuzz.sh [SECONDS] [FUZZER...]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-30}"
shift || true
tree=build-san
fuzzers=("$@")
[ ${#fuzzers[@]} -gt 0 ] || fuzzers=(fuzz_depth_png fuzz_label_png fuzz_camera_json fuzz_config_json fuzz_pcd fuzz_segmenter)
if [ ! -x "$tree/fuzz/${fuzzers[0]}" ]; then SANITIZE_ONLY_BUILD=1 bash scripts/sanitize.sh; fi
mkdir -p "$tree/fuzz-corpus" "$tree/fuzz-findings" "$tree/fuzz-logs"
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
export OMP_NUM_THREADS=1
# One fuzzer per core at a time (each is single-threaded); each writes its verdict to a file, printed in order.
run_one() {
  local f=$1 seeds="fuzz/corpus/${1#fuzz_}" work="$tree/fuzz-corpus/${1#fuzz_}" log="$tree/fuzz-logs/$1.log"
  mkdir -p "$work"
  # Inputs up to 64 KB (a frame of the segmenter harness is 64 x 64 pixels), 2 GB and 10 s per input.
  if "$tree/fuzz/$f" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
       -artifact_prefix="$tree/fuzz-findings/$f-" -print_final_stats=1 "$work" "$seeds" >"$log" 2>&1; then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
    echo "fuzz: $f: $runs executions in ${seconds} s, nothing found" >"$log.verdict"
  else
    { echo "fuzz: $f: FOUND A PROBLEM (log: $log, input in $tree/fuzz-findings/)"
      grep -m3 -E 'ERROR|runtime error|deadly signal|Timeout' "$log" || true; } >"$log.verdict"
    return 1
  fi
}
slots="${JOBS:-$(nproc)}"
ran=() running=0
for f in "${fuzzers[@]}"; do
  [ -x "$tree/fuzz/$f" ] || { echo "fuzz: $f not built (PCL missing?), skipped"; continue; }
  rm -f "$tree/fuzz-logs/$f.log.verdict"
  if [ "$running" -ge "$slots" ]; then wait -n || true; running=$((running - 1)); fi
  run_one "$f" &
  running=$((running + 1))
  ran+=("$f")
done
wait || true
failed=0
for f in "${ran[@]}"; do
  verdict="$tree/fuzz-logs/$f.log.verdict"
  if [ -f "$verdict" ]; then cat "$verdict"; else echo "fuzz: $f: no verdict (killed?)"; failed=1; fi
  grep -q 'FOUND A PROBLEM' "$verdict" 2>/dev/null && failed=1
done
exit $failed

#!/usr/bin/env bash
# Sanitizer runs (docs/RELIABILITY.md), called by scripts/test.sh:
#  1. build-san: clang with AddressSanitizer + UndefinedBehaviorSanitizer (and libFuzzer's coverage):
#     library, CLI, the fast tests, the fuzzers; runs those tests (the CLI they call is sanitized too).
#  2. build-tsan: clang with ThreadSanitizer: library and the several-Segmenters-in-threads test.
#  3. every fuzzer for FUZZ_SECONDS (default 10) from the seed corpus.
# SANITIZE_ONLY_BUILD=1 stops after building build-san (scripts/fuzz.sh uses it).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="${JOBS:-$(nproc)}"
CXX_SAN="clang++-14"
common=(-G Ninja -DCMAKE_CXX_COMPILER="$CXX_SAN" -DCMAKE_C_COMPILER=clang-14 -DCMAKE_BUILD_TYPE=Sanitize
        -DCLUTTERSEG_WITH_PYTHON=OFF -DCLUTTERSEG_WITH_ROS=OFF -DCLUTTERSEG_BUILD_BENCH=OFF)
# -O0 (the library and the PCD reader get -O1 from CMakeLists.txt): half the compile time of -O1.
# Line tables only: reports still name file and line, and each file compiles ~20 % faster than with -g.
# -Wno-pass-failed: at -O1 clang does not vectorize the `omp simd` loops, and says so for each.
quiet="-Wno-pass-failed"
asan="$quiet -O0 -gline-tables-only -fno-omit-frame-pointer -fsanitize=address,undefined -fno-sanitize-recover=undefined -fsanitize=fuzzer-no-link"
cmake -S . -B build-san "${common[@]}" -DCLUTTERSEG_FUZZ=ON -DCMAKE_CXX_FLAGS="$asan" >/dev/null
san_tests=(test_reliability test_io test_metrics test_threads)
[ -f tests/pcl/test_pcd.cpp ] && grep -q 'clutterseg_pcl' build-san/build.ninja && san_tests+=(test_pcd)
fuzzers=$(grep -o '^build fuzz/fuzz_[a-z_]*:' build-san/build.ninja | sed 's/^build fuzz\///; s/:$//' | tr '\n' ' ')
cmake --build build-san -j "$jobs" --target clutterseg_cli "${san_tests[@]}" $fuzzers
[ "${SANITIZE_ONLY_BUILD:-0}" = 1 ] && exit 0

export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
# Only the fast tests: the readers, the metrics, every bad input through the sanitized CLI, the threads.
ctest --test-dir build-san --output-on-failure -j "$jobs" -R '^(Reliability|Io|Config|Metrics|Hungarian|Threads|Pcd)\.'

cmake -S . -B build-tsan "${common[@]}" -DCLUTTERSEG_WITH_PCL=OFF -DCLUTTERSEG_TEST_CLI=OFF \
  -DCMAKE_CXX_FLAGS="$quiet -O0 -gline-tables-only -fsanitize=thread" >/dev/null
cmake --build build-tsan -j "$jobs" --target test_threads
TSAN_OPTIONS="halt_on_error=1 suppressions=$PWD/tests/tsan.supp" OMP_NUM_THREADS=1 build-tsan/tests/test_threads

bash scripts/fuzz.sh "${FUZZ_SECONDS:-10}"

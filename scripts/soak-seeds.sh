#!/usr/bin/env bash
# Soak randomized test groups over many seeds, with both trace kernels.
#
#   scripts/soak-seeds.sh BUILD_DIR SEEDS GROUP_OR_BINARY...
#
# SEEDS is a count (that many fresh random 64-bit seeds) or a file of seeds, one a line (to replay a soak).
# GROUP_OR_BINARY is a test group (watertightness runs BUILD_DIR/tests/vkas_test_watertightness) or a path to a test
# binary. Each binary runs once per seed with VKAS_TEST_SEED=<seed> (tests/support/vkas_test.cpp reads it with
# strtoull; every test of the binary then uses that seed), once with the default kernel and once with
# VKAS_TRACE_KERNEL=sse2. Environment:
#   SOAK_JOBS          parallel runs (default: nproc)
#   SOAK_GTEST_FILTER  --gtest_filter for every run (default: all tests; e.g. '-*pinned*' skips fixed-seed cases)
#   SOAK_TIMEOUT       seconds per run before it counts as a failure (default 900)
#   SOAK_OUT           directory for the seed list and the logs of failed runs (default: a new one in /tmp)
# Prints each failure as it happens and a summary with replay commands; exits 1 if any run failed.
set -euo pipefail

if [ $# -lt 3 ]; then
  sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
build=$(cd "$1" && pwd)
seeds_arg=$2
shift 2

binaries=()
for g in "$@"; do
  if [ -x "$g" ] && [ -f "$g" ]; then
    binaries+=("$(cd "$(dirname "$g")" && pwd)/$(basename "$g")")
  elif [ -x "$build/tests/vkas_test_$g" ]; then
    binaries+=("$build/tests/vkas_test_$g")
  else
    echo "soak-seeds: no test binary for '$g' (looked for $build/tests/vkas_test_$g)" >&2
    exit 2
  fi
done

out=${SOAK_OUT:-$(mktemp -d /tmp/vkas-soak.XXXXXX)}
mkdir -p "$out"
if [ -f "$seeds_arg" ]; then
  grep -E '^[0-9]+$' "$seeds_arg" >"$out/seeds.txt"
else
  : >"$out/seeds.txt"
  for ((i = 0; i < seeds_arg; ++i)); do
    od -An -N8 -tu8 /dev/urandom | tr -d ' ' >>"$out/seeds.txt"
  done
fi
nseeds=$(wc -l <"$out/seeds.txt")
jobs=${SOAK_JOBS:-$(nproc)}
export SOAK_GTEST_FILTER=${SOAK_GTEST_FILTER:-*} SOAK_TIMEOUT=${SOAK_TIMEOUT:-900} SOAK_LOGS="$out"

echo "soak: ${#binaries[@]} binaries x $nseeds seeds x 2 kernels, $jobs at a time; seeds in $out/seeds.txt"

# One run: binary, kernel (default | sse2), seed. Prints one line: "ok ..." or "FAIL ...".
run_one() {
  local bin=$1 kernel=$2 seed=$3
  local name log rc=0
  name=$(basename "$bin")
  log="$SOAK_LOGS/$name.$kernel.$seed.log"
  if [ "$kernel" = sse2 ]; then
    VKAS_TEST_SEED=$seed VKAS_TRACE_KERNEL=sse2 timeout "$SOAK_TIMEOUT" "$bin" --gtest_filter="$SOAK_GTEST_FILTER" \
      >"$log" 2>&1 || rc=$?
  else
    VKAS_TEST_SEED=$seed timeout "$SOAK_TIMEOUT" "$bin" --gtest_filter="$SOAK_GTEST_FILTER" >"$log" 2>&1 || rc=$?
  fi
  if [ "$rc" -eq 0 ]; then
    rm -f "$log"
    echo "ok $bin $kernel $seed"
  else
    local failed
    failed=$(grep -E '^\[  FAILED  \] [^ ]+' "$log" | grep -v ' listed below' | awk '{sub(/,$/, "", $4); print $4}' | sort -u |
      tr '\n' ' ' || true)
    echo "FAIL $bin $kernel $seed rc=$rc ${failed:-(no gtest failure line: crash or timeout)} log=$log"
  fi
}
export -f run_one

start=$(date +%s)
while read -r seed; do
  for bin in "${binaries[@]}"; do
    for kernel in default sse2; do
      printf '%s\0%s\0%s\0' "$bin" "$kernel" "$seed"
    done
  done
done <"$out/seeds.txt" | xargs -0 -n3 -P "$jobs" bash -c 'run_one "$@"' _ | tee "$out/results.txt" | grep --line-buffered '^FAIL' || true

total=$(wc -l <"$out/results.txt")
fails=$(grep -c '^FAIL' "$out/results.txt" || true)
echo "soak: $total runs, $fails failed, $(($(date +%s) - start)) s; results in $out/results.txt"
if [ "$fails" -gt 0 ]; then
  echo "replay:"
  grep '^FAIL' "$out/results.txt" | while read -r _ bin kernel seed _; do
    if [ "$kernel" = sse2 ]; then
      echo "  VKAS_TEST_SEED=$seed VKAS_TRACE_KERNEL=sse2 $bin"
    else
      echo "  VKAS_TEST_SEED=$seed $bin"
    fi
  done
  exit 1
fi

#!/usr/bin/env bash
# Runs vkas's libFuzzer targets (docs/FUZZING.md) for a bounded time each, on copies of their seed corpora (the
# repository is not modified).
#   Usage: scripts/run-fuzzers.sh BUILD_DIR [SECONDS]
# BUILD_DIR was configured with Clang and -DVKAS_BUILD_FUZZERS=ON and built; SECONDS per target (default 45).
# Fails when a target reports a crash, a failed check, a leak, a timeout (-timeout per input) or too much memory
# (-rss_limit_mb); the inputs that did it are kept in BUILD_DIR/fuzz-artifacts/. Prints the executions, the speed and
# the coverage of each target; the last line is "fuzz: ..." (scripts/run-tests.sh records it).
# Environment: VKAS_FUZZ_TARGETS (default "deserialize build micromap"), VKAS_FUZZ_ARGS (more libFuzzer flags, e.g. -seed=1).
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if (($# < 1)); then
  echo "usage: $0 BUILD_DIR [SECONDS]" >&2
  exit 2
fi
build=$(cd "$1" && pwd) || exit 2
seconds=${2:-45}
targets=${VKAS_FUZZ_TARGETS:-deserialize build micromap}
artifacts=$build/fuzz-artifacts
mkdir -p "$artifacts"
work=$(mktemp -d "${TMPDIR:-/tmp}/vkas-fuzz.XXXXXX")
trap 'rm -rf "$work"' EXIT

# Leaks are failures; UBSan stops at the first report (the build uses -fno-sanitize-recover=undefined).
export ASAN_OPTIONS=${VKAS_FUZZ_ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1

failed=0
summary=()
for t in $targets; do
  bin=$build/fuzz/vkas_fuzz_$t
  corpus=$root/fuzz/corpus/$t
  if [[ ! -x $bin ]]; then
    echo "run-fuzzers: no $bin (configure with Clang and -DVKAS_BUILD_FUZZERS=ON)"
    summary+=("$t: not built")
    failed=1
    continue
  fi
  mkdir -p "$work/$t"
  cp -r "$corpus/." "$work/$t/"
  log=$work/$t.log
  printf '==== fuzz %s: %ss on %s seed inputs\n' "$t" "$seconds" "$(ls "$corpus" | wc -l)"
  # -timeout: seconds per input; -rss_limit_mb: the process. Serialized structures may grow to 16 KiB (the seeds are
  # smaller); build inputs keep libFuzzer's default limit (4 KiB: an 88-byte spec and its payload).
  max_len=()
  [[ $t == deserialize ]] && max_len=(-max_len=16384)
  # shellcheck disable=SC2086
  "$bin" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2560 "${max_len[@]}" -print_final_stats=1 \
    -artifact_prefix="$artifacts/$t-" ${VKAS_FUZZ_ARGS:-} "$work/$t" >"$log" 2>&1
  status=$?
  execs=$(grep -Eo 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -Eo '[0-9]+$' | tail -1)
  rate=$(grep -Eo 'stat::average_exec_per_sec: *[0-9]+' "$log" | grep -Eo '[0-9]+$' | tail -1)
  cov=$(grep -Eo 'cov: [0-9]+ ft: [0-9]+' "$log" | tail -1)
  corp=$(grep -Eo 'corp: [0-9]+/[0-9]+[a-zA-Z]*' "$log" | tail -1)
  line="$t: ${execs:-0} execs (${rate:-0}/s), ${cov:-no coverage}, ${corp:-corp: ?}"
  grep -E '^INFO: Seed:' "$log"
  if ((status != 0)); then
    failed=1
    line+=", FAILED (exit $status)"
    echo "---- last lines of the $t log:"
    grep -vE '^#[0-9]+ +(NEW|REDUCE|pulse|RELOAD)' "$log" | tail -60
    echo "---- inputs kept: $(ls "$artifacts" | sed "s|^|$artifacts/|" | tr '\n' ' ')"
    echo "---- replay: $bin <input>   (VKAS_FUZZ_VERBOSE=1 prints vkas's validation messages)"
  fi
  echo "  $line"
  summary+=("$line")
done

joined=$(IFS=';'; echo "${summary[*]}")
joined=${joined//;/; }
if ((failed)); then
  echo "fuzz: FAILED: $joined"
  exit 1
fi
echo "fuzz: $joined"

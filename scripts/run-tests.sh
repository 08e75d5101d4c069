#!/usr/bin/env bash
# The README's second command (and CI's, through .ci/run): installs the build dependencies, checks the engine's
# include direction (scripts/check-layers.sh), then
#   1. builds RelWithDebInfo in build/ and runs the test suite (ctest) and a smoke run of the vkas tool;
#   2. builds with AddressSanitizer + UndefinedBehaviorSanitizer in build-asan/ (with Clang, and the libFuzzer targets)
#      and runs the same there, then runs each fuzz target for a bounded time (scripts/run-fuzzers.sh);
#   (between the two: installs Mesa's lavapipe from bookworm-backports for the differential-conformance tests)
#   tsan: builds the threaded tests and the stress program with ThreadSanitizer in build-tsan/ (Clang, VKAS_TSAN=ON)
#      and runs vkas_test_concurrency, vkas_test_host_threading and vkas_stress (${VKAS_TSAN_STRESS_SECONDS:-15} s);
#      any report fails the step (halt_on_error). `scripts/run-tests.sh --only tsan` runs this step alone;
#   3. installs build/ into a temporary prefix and builds the C package consumer against it
#      (find_package(vkas) and pkg-config vkas);
#   4. the Python package (python/, docs/PYTHON.md): a virtual environment over Debian's /usr/bin/python3 with its
#      system packages (build-python/venv), `pip install --no-build-isolation --no-index ./python` (offline, Debian's
#      scikit-build-core; not under the sanitizers), then its pytest suite (python/tests) and the example script.
# Every step runs even when an earlier one failed (except what needs a failed build); the last line is a
# summary and the exit status is non-zero when anything failed.
set -uo pipefail
only=
if [[ ${1:-} == --only ]]; then
  only=${2:-}
  [[ $only == tsan ]] || { echo "run-tests: --only takes: tsan" >&2; exit 2; }
fi
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
jobs=${VKAS_JOBS:-2}
start=$SECONDS
results=()
failed=0
logdir=$(mktemp -d "${TMPDIR:-/tmp}/vkas-tests.XXXXXX")
trap 'rm -rf "$logdir"' EXIT

record() {  # record NAME STATUS [DETAIL]
  local name=$1 status=$2 detail=${3:-}
  if [[ $status == 0 ]]; then
    results+=("$name ok${detail:+ ($detail)}")
  else
    results+=("$name FAILED${detail:+ ($detail)}")
    failed=1
  fi
}

banner() { printf '\n==== %s\n' "$*"; }

# ctest_in DIR NAME: runs the suite, records the pass count.
ctest_in() {
  local dir=$1 name=$2 log="$logdir/$2.log" status
  ctest --test-dir "$dir" --output-on-failure -j"$jobs" 2>&1 | tee "$log"
  status=${PIPESTATUS[0]}
  local counts
  counts=$(grep -Eo '[0-9]+ tests failed out of [0-9]+' "$log" | tail -1)
  if [[ -z $counts ]] && grep -q 'No tests were found' "$log"; then
    status=1
    counts="no tests found"
  fi
  record "$name" "$status" "$counts"
}

# tool_smoke DIR NAME: `vkas info` and a small `vkas render` with the tool of that build.
tool_smoke() {
  local tool="$1/tools/vkas/vkas" name=$2 status=0
  if [[ ! -x $tool ]]; then
    record "$name" 1 "no $tool"
    return
  fi
  "$tool" info >"$logdir/$name-info.log" 2>&1 || { cat "$logdir/$name-info.log"; status=1; }
  "$tool" render --width 160 --height 120 --spp 2 --instances 300 -o "$logdir/$name.png" \
    >"$logdir/$name-render.log" 2>&1 || { cat "$logdir/$name-render.log"; status=1; }
  [[ -s $logdir/$name.png ]] || status=1
  record "$name" "$status" "vkas info, vkas render 160x120"
}

# tsan_step: ThreadSanitizer (issue 20). Only the threaded programs: the whole suite under TSan would not fit CI's time.
tsan_step() {
  banner "build-tsan/ (ThreadSanitizer, Clang: vkas_test_concurrency, vkas_test_host_threading, vkas_stress)"
  local tsan_start=$SECONDS status=0 fresh=() log="$logdir/tsan.log"
  if [[ -f build-tsan/CMakeCache.txt ]] &&
     ! grep -Eq '^CMAKE_CXX_COMPILER:[A-Z]+=.*clang\+\+$' build-tsan/CMakeCache.txt; then
    fresh=(--fresh)
  fi
  if ! CC=clang CXX=clang++ cmake "${fresh[@]}" -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVKAS_TSAN=ON \
         -DVKAS_SANITIZE=OFF -DVKAS_BUILD_TESTS=ON -DVKAS_BUILD_BENCH=OFF -DVKAS_BUILD_TOOLS=OFF -DVKAS_BUILD_FUZZERS=OFF ||
     ! cmake --build build-tsan -j"$jobs" --target vkas_test_concurrency vkas_test_host_threading vkas_stress; then
    record "tsan" 1 "build-tsan/ did not build"
    return
  fi
  local built=$((SECONDS - tsan_start))
  # halt_on_error: the first report ends the program with a non-zero status.
  export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1 second_deadlock_stack=1}
  local program
  for program in vkas_test_concurrency vkas_test_host_threading; do
    build-tsan/tests/$program 2>&1 | tee -a "$log" | grep -E '^\[  (PASSED|FAILED) |WARNING: ThreadSanitizer|SEED'
    [[ ${PIPESTATUS[0]} == 0 ]] || status=1
  done
  build-tsan/tests/vkas_stress --seconds "${VKAS_TSAN_STRESS_SECONDS:-15}" --threads 4 2>&1 | tee -a "$log" |
    grep -Ev '^  '
  [[ ${PIPESTATUS[0]} == 0 ]] || status=1
  if grep -q 'WARNING: ThreadSanitizer' "$log"; then
    grep -A40 'WARNING: ThreadSanitizer' "$log" | head -80
    status=1
  elif ((status)); then
    tail -n 60 "$log"
  fi
  unset TSAN_OPTIONS
  record "tsan" "$status" "2 test programs and vkas_stress ${VKAS_TSAN_STRESS_SECONDS:-15}s; build ${built}s, total $((SECONDS - tsan_start))s"
}

summary_and_exit() {
  elapsed=$((SECONDS - start))
  banner "summary"
  printf '  %s\n' "${results[@]}"
  summary=$(IFS=';'; echo "${results[*]}")
  if ((failed)); then
    echo "run-tests: FAILED in ${elapsed}s: ${summary//;/, }"
    exit 1
  fi
  echo "run-tests: PASSED in ${elapsed}s: ${summary//;/, }"
  exit 0
}

if [[ $only == tsan ]]; then
  tsan_step
  summary_and_exit
fi

banner "dependencies"
if ! "$root/scripts/setup-deps.sh"; then
  echo "run-tests: FAILED: could not install the build dependencies"
  exit 1
fi

banner "layers (scripts/check-layers.sh)"
"$root/scripts/check-layers.sh"
record "layers" $? "util <- format <- input <- assemble, format <- builders <- assemble, format <- trace; api/validate/ includes no command; no command file names a VUID"

banner "lavapipe (the differential-conformance referee)"
# The differential tests skip, loudly, only when lavapipe cannot be installed; once it is, they must run.
if icd=$("$root/scripts/setup-lavapipe.sh" | tail -n 1) && [[ -f $icd ]]; then
  export VKAS_REQUIRE_LAVAPIPE=1
  record "lavapipe" 0 "$icd"
else
  export VKAS_REQUIRE_LAVAPIPE=0
  echo "run-tests: WARNING: lavapipe could not be installed; the differential-conformance tests will be SKIPPED"
  results+=("lavapipe UNAVAILABLE (differential tests skipped)")
fi

banner "build/ (RelWithDebInfo)"
if cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVKAS_BUILD_TESTS=ON -DVKAS_BUILD_TOOLS=ON \
     -DVKAS_SANITIZE=OFF && cmake --build build -j"$jobs"; then
  record "build" 0
  banner "ctest in build/"
  ctest_in build tests
  # With lavapipe installed, the differential-conformance tests must have been built and run.
  conformance=$(ctest --test-dir build -N -L conformance 2>/dev/null | grep -Eo 'Total Tests: [0-9]+' | grep -Eo '[0-9]+')
  if [[ $VKAS_REQUIRE_LAVAPIPE == 1 ]]; then
    [[ ${conformance:-0} -gt 0 ]]
    record "conformance" $? "${conformance:-0} differential-conformance tests (label conformance) in the run above"
  fi
  tool_smoke build tool
else
  record "build" 1
fi

banner "build-asan/ (AddressSanitizer + UndefinedBehaviorSanitizer, Clang, libFuzzer targets)"
export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:detect_leaks=1:detect_stack_use_after_return=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}
# Clang builds the sanitizer build so that the same library objects serve the tests and the fuzz targets
# (fuzz/CMakeLists.txt). A build-asan/ configured with another compiler is configured afresh.
asan_compiler=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DVKAS_BUILD_FUZZERS=ON)
asan_fresh=()
if [[ -f build-asan/CMakeCache.txt ]] &&
   ! grep -Eq '^CMAKE_CXX_COMPILER:[A-Z]+=.*clang\+\+$' build-asan/CMakeCache.txt; then
  asan_fresh=(--fresh)
fi
if cmake "${asan_fresh[@]}" -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVKAS_BUILD_TESTS=ON \
     -DVKAS_BUILD_TOOLS=ON -DVKAS_SANITIZE=ON "${asan_compiler[@]}" && cmake --build build-asan -j"$jobs"; then
  record "asan build" 0
  banner "ctest in build-asan/"
  ctest_in build-asan "asan tests"
  tool_smoke build-asan "asan tool"
  banner "fuzz targets in build-asan/ (scripts/run-fuzzers.sh, ${VKAS_FUZZ_SECONDS:-45}s each)"
  fuzz_start=$SECONDS
  "$root/scripts/run-fuzzers.sh" build-asan "${VKAS_FUZZ_SECONDS:-45}" 2>&1 | tee "$logdir/fuzz.log"
  fuzz_status=${PIPESTATUS[0]}
  fuzz_detail=$(grep -E '^fuzz: ' "$logdir/fuzz.log" | tail -1)
  fuzz_detail=${fuzz_detail#fuzz: }
  fuzz_detail=${fuzz_detail#FAILED: }
  record "fuzz" "$fuzz_status" "${fuzz_detail:-no summary}; $((SECONDS - fuzz_start))s"
else
  record "asan build" 1
fi
unset ASAN_OPTIONS UBSAN_OPTIONS

tsan_step

banner "package consumer (install, find_package, pkg-config)"
if [[ -f build/CMakeCache.txt ]] && grep -q '^build ok' <(printf '%s\n' "${results[@]}"); then
  "$root/scripts/check-package.sh" build
  record "package" $?
else
  record "package" 1 "skipped: build/ did not build"
fi

banner "python package (venv, pip install ./python, pytest python/tests)"
# Debian's interpreter, whatever python3 is first on PATH (a pyenv one lacks Debian's numpy, pybind11, pytest).
py_start=$SECONDS
py_venv="$root/build-python/venv"
py_log="$logdir/python.log"
if ! "$root/scripts/setup-python.sh"; then
  record "python" 1 "scripts/setup-python.sh could not install the Debian packages"
elif ! { [[ -x $py_venv/bin/python ]] || /usr/bin/python3 -m venv --system-site-packages "$py_venv"; }; then
  record "python" 1 "could not create $py_venv"
elif ! CMAKE_BUILD_PARALLEL_LEVEL=$jobs "$py_venv/bin/pip" install --no-build-isolation --no-index --no-deps \
       --force-reinstall "$root/python" 2>&1 | tee "$py_log" | tail -n 3; then
  record "python" 1 "pip install ./python failed"
else
  # From outside the source tree, so that the installed package is the one imported.
  (cd "$logdir" && "$py_venv/bin/python" -m pytest -q -p no:cacheprovider "$root/python/tests") 2>&1 | tee -a "$py_log"
  py_status=${PIPESTATUS[0]}
  py_counts=$(grep -Eo '[0-9]+ (passed|failed)[^=]*' "$py_log" | tail -1)
  if ((py_status == 0)); then
    (cd "$logdir" && "$py_venv/bin/python" "$root/python/examples/depth_normals.py" --width 160 --height 120 \
       -o "$logdir/bunny") >>"$py_log" 2>&1 && [[ -s $logdir/bunny-depth.png && -s $logdir/bunny-normals.png ]] ||
      { tail -n 20 "$py_log"; py_status=1; py_counts+="; examples/depth_normals.py FAILED"; }
  fi
  record "python" "$py_status" "${py_counts:-no pytest summary}; $((SECONDS - py_start))s"
fi

summary_and_exit

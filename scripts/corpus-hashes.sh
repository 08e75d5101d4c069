#!/usr/bin/env bash
# The corpus hashes (issue 14): builds vkas_corpus_hashes in a build directory (default build-release/, configured
# Release if it does not exist yet) and prints one hash per item of the fixed corpus (tests/corpus_hashes/), then
# the hash of all lines. A restructuring of the engine must print the same hashes.
#
#   scripts/corpus-hashes.sh [BUILD_DIR] [--check FILE] [-- PROGRAM_OPTIONS...]
#
# --check FILE compares with a recorded output (tests/data/corpus_hashes.txt is the recording), prints every item
# that differs, is missing or is new, and exits non-zero on any difference. PROGRAM_OPTIONS go to the program:
# --worker-threads N, --no-validation. Record a new output with
#   scripts/corpus-hashes.sh > tests/data/corpus_hashes.txt
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=""
check=""
options=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --check) check=$2; shift 2 ;;
    --) shift; options=("$@"); break ;;
    -h|--help) sed -n '2,12p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) build=$1; shift ;;
  esac
done
build=${build:-$root/build-release}
if [[ ! -f $build/CMakeCache.txt ]]; then
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >&2
fi
nice cmake --build "$build" -j"${VKAS_JOBS:-1}" --target vkas_corpus_hashes >&2
program=$build/tests/corpus_hashes/vkas_corpus_hashes
if [[ -n $check ]]; then
  exec "$program" "${options[@]}" --check "$check"
fi
exec "$program" "${options[@]}"

#!/usr/bin/env bash
# Runs vkas's libFuzzer targets (docs/FUZZING.md) for a bounded time each, on copies of their seed corpora (the
# repository is not modified).
#   Usage: scripts/run-fuzzers.sh BUILD_DIR [SECONDS]
# BUILD_DIR was configured with Clang and -DVKAS_BUILD_FUZZERS=ON and built; SECONDS per target (default 45).
# Fails when a target reports a crash, a failed check, a leak, a timeout (-timeout per input) or too much memory
# (-rss_limit_mb); the inputs that did it are kept in BUILD_DIR/fuzz-artifacts/. Prints the executions, the speed and
# the coverage of each target; the last line is "fuzz: ..." (scripts/run-tests.sh records it).
# Environment: VKAS_FUZZ_TARGETS (default "deserialize build micromap mesh_file"), VKAS_FUZZ_ARGS (more libFuzzer
# flags, e.g. -seed=1). The mesh_file target's seeds are its committed ones plus, at run time, small meshes of Debian's
# assimp-testmodels and glmark2-data (scripts/setup-deps.sh installs them), each behind its format byte.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
if (($# < 1)); then
  echo "usage: $0 BUILD_DIR [SECONDS]" >&2
  exit 2
fi
build=$(cd "$1" && pwd) || exit 2
seconds=${2:-45}
targets=${VKAS_FUZZ_TARGETS:-deserialize build micromap mesh_file}
artifacts=$build/fuzz-artifacts
mkdir -p "$artifacts"
work=$(mktemp -d "${TMPDIR:-/tmp}/vkas-fuzz.XXXXXX")
trap 'rm -rf "$work"' EXIT

# Leaks are failures; UBSan stops at the first report (the build uses -fno-sanitize-recover=undefined).
export ASAN_OPTIONS=${VKAS_FUZZ_ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=1}
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1

# mesh_file_seeds DIR: installed test meshes as vkas_fuzz_mesh_file inputs: the first byte picks the extension
# (0 obj, 1 ply, 2 stl, 3 off, 4 gltf, 5 glb, 6 3ds: fuzz/fuzz_mesh_file.cpp), the file follows. Missing files are skipped.
mesh_file_seeds() {
  local dir=$1 a=/usr/share/assimp/models g=/usr/share/glmark2/models entry byte file
  for entry in 0:$a/OBJ/box.obj 0:$a/OBJ/concave_polygon.obj 0:$a/OBJ/cube_usemtl.obj 1:$a/PLY/cube.ply \
               1:$a/PLY/cube_binary.ply 1:$a/PLY/cube_uv.ply 2:$a/STL/triangle_with_two_solids.stl \
               2:$a/STL/Spider_binary.stl 3:$a/OFF/Cube.off 4:$a/glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf \
               5:$a/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb 6:$g/cube.3ds 6:$a/3DS/RotatingCube.3DS; do
    byte=${entry%%:*}
    file=${entry#*:}
    [[ -f $file ]] || continue
    { printf "\\x0$byte"; cat "$file"; } >"$dir/installed-$(basename "$file")"
  done
}

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
  [[ $t == mesh_file ]] && mesh_file_seeds "$work/$t"
  log=$work/$t.log
  printf '==== fuzz %s: %ss on %s seed inputs\n' "$t" "$seconds" "$(ls "$work/$t" | wc -l)"
  # -timeout: seconds per input; -rss_limit_mb: the process. Serialized structures and mesh files may grow to 16 KiB
  # (larger seeds are read cut there); build inputs keep libFuzzer's default limit (4 KiB: an 88-byte spec and its payload).
  max_len=()
  [[ $t == deserialize || $t == mesh_file ]] && max_len=(-max_len=16384)
  # assimp leaks on its own error paths (fuzz/lsan-assimp.supp): not vkas's leaks.
  lsan=
  [[ $t == mesh_file ]] && lsan=suppressions=$root/fuzz/lsan-assimp.supp
  # shellcheck disable=SC2086
  LSAN_OPTIONS=${lsan:-${LSAN_OPTIONS:-}} "$bin" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=2560 "${max_len[@]}" -print_final_stats=1 \
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

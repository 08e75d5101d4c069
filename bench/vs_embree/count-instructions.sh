#!/usr/bin/env bash
# Instructions per ray, vkas against Embree, on the same rays (issue 36): timing on shared machines moves +-40%,
# instruction counts do not. Runs vkas_bench_tree_quality under callgrind once per engine, path and ray kind,
# counting only the measured call (--collect-atstart=no --toggle-collect=vb::measured*), one thread:
#   embree       rtcIntersect1 (camera, diffuse) / rtcOccluded1 (shadow), ROBUST scene of Embree's default quality
#   vkas         vkasTraceRays on the default device (validation on: what users get)
#   vkas-noval   vkasTraceRays with validation off
#   vkas-query   the vkasRayQuery* functions run to completion (validation on)
# and prints instructions per ray and each vkas path's ratio to Embree (the target: at most 0.8). The issue's
# scenes: bunny, bunny-1m (a million triangles) and instances (10,000 instances of the bunny).
# Valgrind emulates no AVX-512: on any CPU the counts are those of the AVX2 kernel (or SSE2 with VKAS_TRACE_KERNEL=sse2).
#
#   bench/vs_embree/count-instructions.sh BUILD_DIR [--scene bunny] [--rays 20000] [--kinds "camera diffuse shadow"]
#                                                   [--flags default]
set -euo pipefail

if [[ $# -lt 1 ]]; then
  sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
build=$1
shift
scene=bunny rays=20000 kinds="camera diffuse shadow" flags=default
while [[ $# -gt 0 ]]; do
  case $1 in
    --scene) scene=$2; shift 2 ;;
    --rays) rays=$2; shift 2 ;;
    --kinds) kinds=$2; shift 2 ;;
    --flags) flags=$2; shift 2 ;;
    *) echo "count-instructions: unknown argument $1" >&2; exit 2 ;;
  esac
done
bench=$build/bench/vs_embree/vkas_bench_tree_quality
[[ -x $bench ]] || { echo "count-instructions: no $bench (scripts/setup-bench.sh, then build it)" >&2; exit 2; }
command -v valgrind >/dev/null || { echo "count-instructions: valgrind is not installed" >&2; exit 2; }
work=$(mktemp -d /tmp/vkas-count.XXXXXX)
trap 'rm -rf "$work"' EXIT

# count KIND TOGGLE ARGS...: the instructions callgrind collected inside TOGGLE.
count() {
  local kind=$1 toggle=$2
  shift 2
  valgrind --tool=callgrind --collect-atstart=no --toggle-collect="$toggle" --callgrind-out-file="$work/out" \
    "$bench" --scene "$scene" --rays "$rays" --reps 1 --kind "$kind" "$@" >"$work/stdout" 2>"$work/stderr" ||
    { cat "$work/stderr" >&2; exit 1; }
  awk '/^summary:/ {print $2}' "$work/out"
}

echo "instructions per ray (callgrind), scene $scene, $rays rays of each kind, build preference $flags, one thread"
printf '%-8s %12s %12s %7s %12s %7s %12s %7s\n' kind embree vkas ratio vkas-noval ratio vkas-query ratio
for k in $kinds; do
  e=$(count "$k" 'vb::measuredEmbree*' --engine embree)
  v=$(count "$k" 'vb::measuredTrace*' --flags "$flags" --validation)
  n=$(count "$k" 'vb::measuredTrace*' --flags "$flags")
  q=$(count "$k" 'vb::measuredQuery*' --flags "$flags" --validation --ray-query)
  awk -v k="$k" -v e="$e" -v v="$v" -v n="$n" -v q="$q" -v r="$rays" 'BEGIN {
    printf "%-8s %12.0f %12.0f %6.2fx %12.0f %6.2fx %12.0f %6.2fx\n", k, e / r, v / r, v / e, n / r, n / e, q / r, q / e
  }'
done

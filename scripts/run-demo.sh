#!/usr/bin/env bash
# The README's first command: installs the build dependencies, builds vkas (Release) into build-release/ and runs
# `vkas render`, which builds the built-in scene on the host, traces it and writes vkas-render.png.
# Extra arguments go to `vkas render` (e.g. --width 1920 --height 1080 --spp 16).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$root"
jobs=${VKAS_JOBS:-2}

"$root/scripts/setup-deps.sh"

echo "== configure and build (Release) in build-release/"
cmake -S . -B build-release -DCMAKE_BUILD_TYPE=Release -DVKAS_BUILD_TESTS=OFF >/dev/null
cmake --build build-release --target vkas_tool -j"$jobs"

tool="$root/build-release/tools/vkas/vkas"
image="$root/vkas-render.png"
args=("$@")
for ((i = 0; i < ${#args[@]}; ++i)); do
  case "${args[i]}" in
    -o | --output) ((i + 1 < ${#args[@]})) && image=$(realpath -m "${args[i + 1]}") ;;
    --output=*) image=$(realpath -m "${args[i]#--output=}") ;;
  esac
done
echo "== build-release/tools/vkas/vkas render $*"
"$tool" render "$@"
echo "== the image is $image"

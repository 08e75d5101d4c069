#!/usr/bin/env bash
# Installs the Debian packages vkas needs to build, test and run its tools, only those that are missing.
# Usage: scripts/setup-deps.sh [extra-package ...]
set -euo pipefail

# clang + libclang-rt-14-dev (libFuzzer, the sanitizer runtimes): the sanitizer build and its fuzz targets.
# libassimp-dev: the vkas tool reads mesh files; glmark2-data, assimp-testmodels (OBJ, 3DS, OFF, PLY, STL, glTF) and
# python3: the tool's CLI tests (tests/cli/).
packages=(build-essential cmake pkg-config libvulkan-dev libxxhash-dev libgtest-dev libgmock-dev libcli11-dev libpng-dev
          glslang-tools clang libclang-rt-14-dev python3 libassimp-dev glmark2-data assimp-testmodels "$@")

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
  [[ "$status" == installed ]] || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "setup-deps: all build dependencies are installed"
  exit 0
fi

echo "setup-deps: installing ${missing[*]}"
sudo=()
if ((EUID != 0)); then
  command -v sudo >/dev/null || { echo "setup-deps: need root (or sudo) to install ${missing[*]}" >&2; exit 1; }
  sudo=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
apt_opts=(-q -o Dpkg::Use-Pty=0 -o DPkg::Lock::Timeout=600)
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! { "${sudo[@]}" apt-get "${apt_opts[@]}" update &&
       "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get "${apt_opts[@]}" install -y --no-install-recommends \
         "${missing[@]}"; } >"$log" 2>&1; then
  cat "$log" >&2
  echo "setup-deps: apt-get failed" >&2
  exit 1
fi
echo "setup-deps: done"

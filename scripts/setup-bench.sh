#!/usr/bin/env bash
# Installs what the Embree comparison benchmark (bench/vs_embree, `vkas_bench_embree`) needs, only what is missing:
# Embree 3 and assimp (libraries, found by CMake) and the Debian packages whose meshes it loads, then prints where
# the mesh files are.
#   libembree-dev  Embree 3.13 (the reference)          libassimp-dev  assimp 5 (mesh loading: .3ds, .off, .ac, .obj)
#   libtbb-dev     TBB (Embree's tasking: builds confined to N threads by a TBB arena)
#   glmark2-data   the Stanford bunny (69,666 triangles)  libcgal-demo   CGAL's demo meshes (.off)
#   torcs-data     TORCS race tracks (.ac): long thin triangles (about 330 MB download)
# CGAL's meshes are extracted from the package's data tarball to $VKAS_BENCH_DATA (default ~/.cache/vkas-bench),
# where vkas_bench_embree looks for them.
# Usage: scripts/setup-bench.sh [--no-torcs] [extra-package ...]
set -euo pipefail

packages=(libembree-dev libtbb-dev libassimp-dev glmark2-data libcgal-demo torcs-data)
if [[ "${1:-}" == --no-torcs ]]; then
  packages=("${packages[@]/torcs-data}")
  shift
fi
packages+=("$@")

missing=()
for p in "${packages[@]}"; do
  [[ -n "$p" ]] || continue
  status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
  [[ "$status" == installed ]] || missing+=("$p")
done
if ((${#missing[@]} > 0)); then
  echo "setup-bench: installing ${missing[*]}"
  sudo=()
  if ((EUID != 0)); then
    command -v sudo >/dev/null || { echo "setup-bench: need root (or sudo) to install ${missing[*]}" >&2; exit 1; }
    sudo=(sudo)
  fi
  apt_opts=(-q -o Dpkg::Use-Pty=0 -o DPkg::Lock::Timeout=600)
  log=$(mktemp)
  trap 'rm -f "$log"' EXIT
  if ! { "${sudo[@]}" apt-get "${apt_opts[@]}" update &&
         "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get "${apt_opts[@]}" install -y --no-install-recommends \
           "${missing[@]}"; } >"$log" 2>&1; then
    cat "$log" >&2
    echo "setup-bench: apt-get failed" >&2
    exit 1
  fi
else
  echo "setup-bench: all benchmark packages are installed"
fi

# Where the meshes are (the paths vkas_bench_embree's --scene names resolve to).
show() {  # show NAME PATH
  if [[ -e "$2" ]]; then printf '  %-14s %s\n' "$1" "$2"; else printf '  %-14s (missing: %s)\n' "$1" "$2"; fi
}
echo "setup-bench: meshes"
data=${VKAS_BENCH_DATA:-${XDG_CACHE_HOME:-$HOME/.cache}/vkas-bench}
cgal_tar=/usr/share/doc/libcgal-dev/data.tar.gz   # libcgal-demo ships CGAL's data as a tarball
if [[ -f "$cgal_tar" && ! -d "$data/cgal/data/meshes" ]]; then
  mkdir -p "$data/cgal"
  tar -xzf "$cgal_tar" -C "$data/cgal" data/meshes
fi
show bunny /usr/share/glmark2/models/bunny.obj
show cgal-elephant "$data/cgal/data/meshes/refined_elephant.off"
show cgal-armadillo "$data/cgal/data/meshes/armadillo.off"
show torcs-forza /usr/share/games/torcs/tracks/road/forza/forza.acc
echo "  (every CGAL mesh: $data/cgal/data/meshes/*.off; every TORCS track: /usr/share/games/torcs/tracks/*/*/*.ac*;"
echo "   any of them runs with: vkas_bench_embree --mesh PATH)"

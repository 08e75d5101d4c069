#!/usr/bin/env bash
# Installs what the Python package (python/, docs/PYTHON.md) needs to build and test, only what is missing:
# Debian bookworm's pybind11-dev, python3-numpy, python3-pytest, python3-venv and python3-pip, and
# python3-scikit-build-core, which bookworm has only in bookworm-backports (with the python3-packaging >= 25 it
# needs from there too). The backports apt source is derived from the machine's own Debian source, as
# scripts/setup-lavapipe.sh does (it adds the same file; either script may run first).
# With VKAS_TRIMESH_SRC set, also the Debian packages trimesh's tests need (below).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

say() { echo "setup-python: $*" >&2; }

# With VKAS_TRIMESH_SRC set (a trimesh checkout: python/tests/test_trimesh_suite.py runs trimesh's own tests with
# vkas's intersector), also what trimesh's tests need of Debian: scipy, networkx, rtree (trimesh's own intersector,
# which the suite compares with), shapely, PIL (the textured models of test_mesh.py).
trimesh_test_packages=()
if [[ -n ${VKAS_TRIMESH_SRC:-} ]]; then
  trimesh_test_packages=(python3-scipy python3-networkx python3-rtree python3-shapely python3-pil)
fi
"$root/scripts/setup-deps.sh" pybind11-dev python3-numpy python3-pytest python3-venv python3-pip \
  "${trimesh_test_packages[@]}"

installed() { [[ $(dpkg-query -W -f='${db:Status-Status}' "$1" 2>/dev/null || true) == installed ]]; }
if installed python3-scikit-build-core; then
  say "python3-scikit-build-core is installed"
  exit 0
fi

sudo=()
if ((EUID != 0)); then
  command -v sudo >/dev/null || { say "need root (or sudo) to install python3-scikit-build-core"; exit 1; }
  sudo=(sudo)
fi
suite=bookworm-backports
list=/etc/apt/sources.list.d/vkas-$suite.sources
export DEBIAN_FRONTEND=noninteractive
apt_opts=(-q -o Dpkg::Use-Pty=0 -o DPkg::Lock::Timeout=600)
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! apt-cache policy python3-scikit-build-core 2>/dev/null | grep -q "$suite"; then
  if [[ ! -f $list ]]; then
    # The same derivation as setup-lavapipe.sh: the first main-archive bookworm entry with its suite changed.
    stanza=$(sed -n '/^derive_source()/,/^}/p' "$root/scripts/setup-lavapipe.sh")
    eval "$stanza"
    source_text=$(derive_source)
    [[ -n $source_text ]] || { say "no Debian bookworm apt source found to derive $suite from"; exit 1; }
    say "adding $list"
    printf '%s\n' "$source_text" | "${sudo[@]}" tee "$list" >/dev/null
  fi
  "${sudo[@]}" apt-get "${apt_opts[@]}" update >"$log" 2>&1 || { cat "$log" >&2; say "apt-get update failed"; exit 1; }
fi
say "installing python3-scikit-build-core from $suite"
if ! "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get "${apt_opts[@]}" install -y --no-install-recommends \
     "python3-scikit-build-core/$suite" "python3-packaging/$suite" >"$log" 2>&1; then
  cat "$log" >&2
  say "apt-get failed"
  exit 1
fi
say "done"

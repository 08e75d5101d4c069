#!/usr/bin/env bash
# Installs Mesa's lavapipe (a conformant CPU Vulkan driver with VK_KHR_acceleration_structure, VK_KHR_ray_query and
# VK_KHR_ray_tracing_position_fetch) and the Vulkan loader from Debian's bookworm-backports suite: the
# differential-conformance tests use it as an independent referee (docs/CONFORMANCE.md).
#
# The backports apt source is derived from the machine's own Debian source (same mirror, suite changed), never a
# hard-coded mirror. Prints the ICD manifest path on its last line and exits 0 on success; exits non-zero with the
# reason on stderr when lavapipe cannot be installed.
set -euo pipefail

suite=bookworm-backports
min_mesa=25.0
icd=/usr/share/vulkan/icd.d/lvp_icd.json
list=/etc/apt/sources.list.d/vkas-$suite.sources

say() { echo "setup-lavapipe: $*" >&2; }

mesa_version() { dpkg-query -W -f='${db:Status-Status} ${Version}' mesa-vulkan-drivers 2>/dev/null | awk '$1 == "installed" {print $2}'; }

if [[ -f $icd ]] && dpkg --compare-versions "$(mesa_version || true)" ge "$min_mesa" 2>/dev/null; then
  say "lavapipe from mesa-vulkan-drivers $(mesa_version) is installed"
  echo "$icd"
  exit 0
fi

sudo=()
if ((EUID != 0)); then
  command -v sudo >/dev/null || { say "need root (or sudo) to install lavapipe"; exit 1; }
  sudo=(sudo)
fi

# The first entry of the main Debian archive for the bookworm suite, as a deb822 stanza with its suite changed.
derive_source() {
  local f found
  for f in /etc/apt/sources.list.d/*.sources; do
    [[ -f $f && $f != "$list" ]] || continue
    # deb822: stanzas separated by blank lines; pick one whose Suites list has "bookworm" and that is not security.
    found=$(awk -v suite="$suite" 'BEGIN { RS = ""; FS = "\n" }
      {
        uris = ""; suites = ""; has = 0
        for (i = 1; i <= NF; i++) {
          if ($i ~ /^URIs:/) uris = $i
          if ($i ~ /^Suites:/) { suites = $i; n = split(substr($i, 8), s, /[ \t]+/); for (j = 1; j <= n; j++) if (s[j] == "bookworm") has = 1 }
        }
        if (has && uris !~ /security/) {
          for (i = 1; i <= NF; i++) print ($i ~ /^Suites:/ ? "Suites: " suite : $i)
          exit
        }
      }' "$f")
    if [[ -n $found ]]; then echo "$found"; return 0; fi
  done
  # One-line format: "deb [options] URI bookworm components..."
  local line
  line=$(grep -hE '^[[:space:]]*deb[[:space:]]' /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null |
         grep -v security | awk '{ for (i = 2; i <= NF; i++) if ($i == "bookworm") { print; exit } }' || true)
  [[ -n $line ]] || return 0
  awk -v suite="$suite" '{
      opts = ""; i = 2
      if ($2 ~ /^\[/) { while (i <= NF) { opts = opts " " $i; if ($i ~ /\]$/) { i++; break } i++ } }
      uri = $i; comps = ""
      for (k = i + 2; k <= NF; k++) comps = comps " " $k
      print "Types: deb"; print "URIs: " uri; print "Suites: " suite; print "Components:" comps
      if (opts ~ /signed-by=/) { match(opts, /signed-by=[^] ]+/); print "Signed-By: " substr(opts, RSTART + 10, RLENGTH - 10) }
    }' <<<"$line"
}

stanza=$(derive_source)
if [[ -z $stanza ]]; then
  say "no Debian bookworm apt source found to derive $suite from"
  exit 1
fi
say "adding $list:"
sed 's/^/    /' <<<"$stanza" >&2
printf '%s\n' "$stanza" | "${sudo[@]}" tee "$list" >/dev/null

export DEBIAN_FRONTEND=noninteractive
apt_opts=(-q -o Dpkg::Use-Pty=0 -o DPkg::Lock::Timeout=600)
log=$(mktemp)
trap 'rm -f "$log"' EXIT
if ! { "${sudo[@]}" apt-get "${apt_opts[@]}" update &&
       "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get "${apt_opts[@]}" install -y --no-install-recommends \
         -t "$suite" mesa-vulkan-drivers libvulkan1; } >"$log" 2>&1; then
  tail -n 20 "$log" >&2
  say "apt-get could not install mesa-vulkan-drivers from $suite"
  exit 1
fi
version=$(mesa_version || true)
if [[ ! -f $icd ]] || ! dpkg --compare-versions "$version" ge "$min_mesa"; then
  say "mesa-vulkan-drivers ${version:-(none)} installed, but lavapipe >= $min_mesa ($icd) is needed"
  exit 1
fi
say "installed lavapipe from mesa-vulkan-drivers $version"
echo "$icd"

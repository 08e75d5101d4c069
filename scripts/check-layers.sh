#!/usr/bin/env bash
# The include direction (docs/ARCHITECTURE.md "Include direction"): in the engine util <- format <- input <- assemble,
# format <- builders <- assemble, format <- trace. A folder may include its own headers and those of the folders it
# depends on, never the others; the engine never includes the API layer. In the API layer, the valid-usage rules
# (src/api/validate/) read the objects (device, structures, micromaps, limits) and never a command's file
# (api/*_commands.hpp and the other command sources): the commands call the rules, not the reverse.
# Exits non-zero, naming every offending line, when a file breaks a rule.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../src/engine"

declare -A allowed=(
  [util]="util"
  [format]="util format"
  [input]="util format input"
  [builders]="util format builders"
  [assemble]="util format input builders assemble"
  [trace]="util format trace"
)

status=0
for folder in "${!allowed[@]}"; do
  [ -d "$folder" ] || { echo "check-layers: src/engine/$folder is missing" >&2; status=1; continue; }
  while IFS= read -r hit; do
    file=${hit%%:*}; rest=${hit#*:}; line=${rest%%:*}
    target=$(sed -E 's/.*#include "([^"]+)".*/\1/' <<<"${rest#*:}")
    case "$target" in
      engine/*)
        dep=${target#engine/}; dep=${dep%%/*}
        if [[ " ${allowed[$folder]} " != *" $dep "* ]]; then
          echo "src/engine/$file:$line: $folder/ may not include $target (allowed: ${allowed[$folder]})"
          status=1
        fi ;;
      api/*)
        echo "src/engine/$file:$line: the engine may not include the API layer ($target)"; status=1 ;;
    esac
  done < <(grep -rn '#include "' "$folder" | sed -E 's/^([^:]+):([0-9]+):/\1:\2:/')
done
# Every engine file lives in one of the folders.
for f in *; do
  [ -d "$f" ] || { echo "src/engine/$f: outside the engine's folders (${!allowed[*]})"; status=1; }
done
# The API layer: validate/ includes no command file.
commands='api/(.*_commands|batch_trace|ray_query_api|proc_table|entry_points|guarded_command)\.hpp'
while IFS= read -r hit; do
  echo "src/${hit%%:*}: api/validate/ may not include a command's file (${hit##*#include })"; status=1
done < <(cd .. && grep -rnE "#include \"$commands\"" api/validate | sed -E 's/^([^:]+):([0-9]+):/\1:\2:/')
# Valid usage lives in api/validate/ only: a command file names no VUID.
while IFS= read -r hit; do
  echo "src/${hit%%:*}: a valid-usage check in a command file (move it to api/validate/)"; status=1
done < <(cd .. && grep -n '"VUID-' api/*.cpp api/*.hpp | sed -E 's/^([^:]+):([0-9]+):.*/\1:\2/')
[ $status -eq 0 ] && echo "check-layers: the engine's includes follow util <- format <- input <- assemble, format <- builders <- assemble, format <- trace; api/validate/ includes no command; no command file names a VUID"
exit $status

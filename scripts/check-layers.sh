#!/usr/bin/env bash
# The engine's include direction (docs/ARCHITECTURE.md): util <- format <- input <- build, format <- trace.
# A folder may include its own headers and those of the folders it depends on, never the others; the engine never
# includes the API layer. Exits non-zero, naming every offending line, when a file breaks the rule.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/../src/engine"

declare -A allowed=(
  [util]="util"
  [format]="util format"
  [input]="util format input"
  [build]="util format input build"
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
[ $status -eq 0 ] && echo "check-layers: the engine's includes follow util <- format <- input <- build, format <- trace"
exit $status

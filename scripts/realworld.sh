#!/usr/bin/env bash
# Run `necklace loops` on every model of a folder (default ../shared/data/realworld) and
# print one TSV row per model: exit status, wall seconds, peak memory (MB), the error or
# the number of warnings, and per side (inside, outside) the surface's genus and the Z2
# rank of that side's loops as `genus:rank` (`-` for no genus; needs jq). A run over the
# time limit is ended and marked `timeout`.
#   bash scripts/realworld.sh [FOLDER] [SECONDS]      (defaults: realworld, 30)
set -uo pipefail
cd "$(dirname "$0")/.."
dir="${1:-../shared/data/realworld}"
limit="${2:-30}"
bin=target/release/necklace
[ -x "$bin" ] || cargo build --release -p necklace-cli >&2
printf 'model\tstatus\tseconds\tpeak_MB\tdetail\tgenus:rank\n'
for f in "$dir"/*; do
  case "$f" in *.obj|*.off|*.ply|*.stl|*.STL) ;; *) continue ;; esac
  err=$(mktemp)
  /usr/bin/time -f '%e %M' -o "$err.time" timeout "$limit" "$bin" loops "$f" -q --json \
    >"$err.json" 2>"$err"
  code=$?
  ranks=-
  if [ $code = 0 ] && command -v jq >/dev/null; then
    ranks=$(jq -r '[.sides[].homology | "\(.genus // "-"):\(.rank)"] | join(" ")' "$err.json")
  fi
  read -r secs kb < <(tail -1 "$err.time")
  case $code in
    0) status=ok; detail="$(grep -c 'warning' "$err") warnings" ;;
    124) status=timeout; detail="over ${limit} s" ;;
    *) status="exit $code"; detail="$(grep -v '^Command' "$err" | tail -1 | cut -c1-160)" ;;
  esac
  printf '%s\t%s\t%s\t%d\t%s\t%s\n' "$(basename "$f")" "$status" "$secs" "$((kb / 1024))" "$detail" "$ranks"
  rm -f "$err" "$err.time" "$err.json"
done

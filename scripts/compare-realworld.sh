#!/usr/bin/env bash
# `../shared/reference/compare.sh` over a folder, with a time limit on every run: per model,
# `necklace loops` (seconds, exit status, peak memory in MB, and per side `genus:rank`),
# then the reference on both sides (seconds for the two, and each side's exit status:
# 0 finished, 124 over the limit, else failed). One TSV row per model; the last row sums
# the seconds over the models the reference finished on both sides.
#   bash scripts/compare-realworld.sh [FOLDER] [SECONDS]   (defaults: realworld, 90)
set -uo pipefail
cd "$(dirname "$0")/.."
dir="${1:-../shared/data/realworld}"
limit="${2:-90}"
bin=${NECKLACE:-target/release/necklace}
here=../shared/reference
[ -x "$bin" ] || cargo build --release -p necklace-cli >&2
venv=${REFERENCE_VENV:-${TMPDIR:-/tmp}/necklace-reference-venv}
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv" >&2
  "$venv/bin/pip" install -q -r "$here/requirements.txt" >&2
fi
now() { date +%s.%N; }
out=$(mktemp)
printf 'model\tnecklace_s\tnecklace_status\tpeak_MB\tgenus:rank\treference_s\tref_inside\tref_outside\n'
tn=0; tr=0
for m in "$dir"/*; do
  case "$m" in *.obj|*.off|*.ply|*.stl|*.STL) ;; *) continue ;; esac
  a=$(now)
  /usr/bin/time -f '%M' -o "$out.mem" timeout "$limit" "$bin" loops "$m" --json -q >"$out" 2>/dev/null
  rn=$?
  b=$(now)
  ranks=-
  if [ $rn = 0 ] && command -v jq >/dev/null; then
    ranks=$(jq -r '[.sides[].homology | "\(.genus // "-"):\(.rank)"] | join(" ")' "$out")
  fi
  timeout "$limit" "$venv/bin/python" "$here/reference.py" "$m" --iters 10,20 >/dev/null 2>&1
  ri=$?
  timeout "$limit" "$venv/bin/python" "$here/reference.py" "$m" --iters 10,20 --exterior >/dev/null 2>&1
  ro=$?
  c=$(now)
  n=$(echo "$b - $a" | bc -l); r=$(echo "$c - $b" | bc -l)
  if [ $ri = 0 ] && [ $ro = 0 ]; then
    tn=$(echo "$tn + $n" | bc -l); tr=$(echo "$tr + $r" | bc -l)
  fi
  printf '%s\t%.2f\t%d\t%d\t%s\t%.2f\t%d\t%d\n' "$(basename "$m")" "$n" "$rn" \
    "$(( $(tail -1 "$out.mem") / 1024 ))" "$ranks" "$r" "$ri" "$ro"
done
printf 'total (reference finished)\t%.2f\t\t\t\t%.2f\t\t\n' "$tn" "$tr"
rm -f "$out" "$out.mem"

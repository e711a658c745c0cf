#!/usr/bin/env bash
# The accuracy check of issues #6 and #7 on fresh synthetic rows: generate rows
# with `orchard synth`, count each with `orchard yield --truth`, and tally the
# sides against the apples visible from them (goal: within 3%) and the merged
# rows against the apples visible from either side (goal: within 2%) with
# `orchard eval rows`.
#
#   scripts/synthetic_check.sh OUT_DIR FIRST_SEED COUNT [exact|default] [-- YIELD_OPTIONS...]
#
# exact (the default): the generator's instance masks (one apple per blob),
#   its true poses and ground planes: the 3D stage and the merge alone.
# default: what a user runs: the shipped U-Net and CNN counter, COLMAP poses
#   (about 5 minutes a row on one core).
# Every fourth row (seeds FIRST+3, FIRST+7, ...) has a flat canopy
# (`--canopy-thickness 0.5`, many apples seen from both sides), as in the
# batches reported in docs/side.md and docs/yield.md. SYNTH_OPTIONS (words
# split on spaces) go to every row's `orchard synth` instead, with no flat
# rows: SYNTH_OPTIONS="--canopy round --canopy-thickness 1.6 --row-spacing 4.5"
# gives the round canopies of docs/side.md. Rows run JOBS at a time
# (default 2, one thread each). Rerunning resumes: rows already generated are
# kept, runs already finished are not redone (other YIELD_OPTIONS need another
# OUT_DIR, or OUT_DIR/runs removed). Writes OUT_DIR/rows/rSEED (the
# generated rows), OUT_DIR/runs/SEED (the yield outputs, logs beside them) and
# OUT_DIR/tally/{rows.csv,summary.json}.
set -euo pipefail
if [[ $# -lt 3 ]]; then
  echo "usage: $0 OUT_DIR FIRST_SEED COUNT [exact|default] [-- YIELD_OPTIONS...]" >&2
  exit 2
fi
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=$(mkdir -p "$1" && cd "$1" && pwd)
FIRST=$2
COUNT=$3
shift 3
MODE=exact
if [[ $# -gt 0 && $1 != "--" ]]; then MODE=$1; shift; fi
if [[ $# -gt 0 && $1 == "--" ]]; then shift; fi
EXTRA=("$@")
[[ $MODE == exact || $MODE == default ]] || { echo "$0: mode must be exact or default, got '$MODE'" >&2; exit 2; }
[[ $FIRST =~ ^[0-9]+$ && $COUNT =~ ^[0-9]+$ && $COUNT -ge 1 ]] ||
  { echo "$0: FIRST_SEED and COUNT must be whole numbers, COUNT at least 1" >&2; exit 2; }
ORCHARD=${ORCHARD:-$ROOT/build/orchard}
[[ -x $ORCHARD ]] || { echo "$0: $ORCHARD not found: build first (bash scripts/run.sh build)" >&2; exit 1; }
JOBS=${JOBS:-2}
mkdir -p "$OUT/rows" "$OUT/runs"

one_row() {
  local seed=$1 row=$OUT/rows/r$1 run=$OUT/runs/$1 synth_args=()
  if [[ -n ${SYNTH_OPTIONS:-} ]]; then
    read -r -a synth_args <<< "$SYNTH_OPTIONS"
  elif (( (seed - FIRST) % 4 == 3 )); then
    synth_args=(--canopy-thickness 0.5)
  fi
  if [[ ! -f $row/truth.json ]]; then
    rm -rf "$row"
    "$ORCHARD" synth --out "$row" --seed "$seed" --patch-every 0 "${synth_args[@]}" > "$OUT/rows/synth$seed.log" 2>&1 ||
      { echo "seed $seed: synth failed, see $OUT/rows/synth$seed.log" >&2; return 1; }
  fi
  [[ -f $run/yield.json ]] && return 0
  local args=(--front "$row/front/images" --back "$row/back/images" --truth "$row/truth.json" --out "$run" --threads 1)
  if [[ $MODE == exact ]]; then
    args+=(--detector masks --counter blob --masks-front "$row/front/masks" --masks-back "$row/back/masks"
           --poses-front "$row/front/sparse" --poses-back "$row/back/sparse" --ground-front "$row/front/scene.json"
           --ground-back "$row/back/scene.json" --no-triangulate-poses)
  else
    # The generator's camera is a pinhole (docs/synth.md), as in the runs the docs report.
    args+=(--camera-model PINHOLE)
  fi
  "$ORCHARD" yield "${args[@]}" "${EXTRA[@]}" > "$run.log" 2>&1 ||
    { echo "seed $seed: orchard yield failed, see $run.log" >&2; return 1; }
  echo "seed $seed: done"
}

failed=0
pids=()
for ((seed = FIRST; seed < FIRST + COUNT; ++seed)); do
  one_row "$seed" &
  pids+=($!)
  if (( ${#pids[@]} >= JOBS )); then wait "${pids[0]}" || failed=1; pids=("${pids[@]:1}"); fi
done
for pid in "${pids[@]}"; do wait "$pid" || failed=1; done

runs=()
for ((seed = FIRST; seed < FIRST + COUNT; ++seed)); do
  [[ -f $OUT/runs/$seed/yield.json ]] && runs+=("$OUT/runs/$seed")
done
(( ${#runs[@]} > 0 )) || { echo "$0: no row was counted" >&2; exit 1; }
"$ORCHARD" eval rows "${runs[@]}" --out "$OUT/tally"
exit $failed

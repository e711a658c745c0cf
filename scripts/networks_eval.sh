#!/usr/bin/env bash
# Held-out evaluation of the shipped networks (numbers in docs/networks.md and the model cards):
# the test photos of AppleBBCH81/76 (--test-fraction 0.25 --split-seed 1, never seen in training)
# and a synthetic row whose seed no training used.
#   bash scripts/networks_eval.sh OUTDIR        (ORCHARD=path/to/orchard, DATA=path/to/shared/data)
set -euo pipefail
out="${1:?usage: scripts/networks_eval.sh OUTDIR}"
orchard="${ORCHARD:-build/orchard}"
data="${DATA:-../shared/data}"
models="${MODELS:-models}"
mkdir -p "$out"
for set in applebbch81 applebbch76; do
  d="$out/$set"
  "$orchard" split --data "$data/$set" --test-fraction 0.25 --split-seed 1 --out "$d/split"
  # Counter on real cluster patches of the test photos.
  "$orchard" patches --data "$data/$set" --test-fraction 0.25 --split-seed 1 --subset test --out "$d/patches"
  "$orchard" count --method cnn --model "$models/counter.pt" --in "$d/patches" --out "$d/cnn/counts.csv"
  "$orchard" eval count --gt "$d/patches/counts.csv" --pred "$d/cnn/counts.csv" --out "$d/eval_count"
  # RetinaNet, U-Net and colour detector on the test photos, against the boxes (the RetinaNet
  # twice: every box scoring 0.05 or more for AP, its default threshold 0.5 for F1).
  "$orchard" detect --method retinanet --model "$models/retinanet.pt" --threshold 0.05 --in "$d/split/test/images" --out "$d/retinanet05"
  "$orchard" detect --method retinanet --model "$models/retinanet.pt" --in "$d/split/test/images" --out "$d/retinanet"
  "$orchard" detect --method unet --model "$models/unet.pt" --in "$d/split/test/images" --out "$d/unet"
  "$orchard" detect --method gmm --model "$models/gmm_red.json" --in "$d/split/test/images" --out "$d/gmm"
  "$orchard" eval detect --gt "$d/split/test" \
    --pred retinanet05="$d/retinanet05/detections.csv" --pred retinanet="$d/retinanet/detections.csv" \
    --pred unet="$d/unet/detections.csv" --pred gmm="$d/gmm/detections.csv" --out "$d/eval_detect"
done
# Segmentation against exact masks: a synthetic row no model was trained on.
"$orchard" synth --out "$out/synth202" --seed 202 --trees 2 --sides front --patch-every 0
"$orchard" detect --method unet --model "$models/unet.pt" --in "$out/synth202/front/images" --out "$out/synth202/unet"
"$orchard" detect --method gmm --model "$models/gmm_red.json" --in "$out/synth202/front/images" --out "$out/synth202/gmm"
"$orchard" eval segment --gt "$out/synth202/front/masks" --pred "$out/synth202/unet/masks" --out "$out/synth202/eval_segment_unet"
"$orchard" eval segment --gt "$out/synth202/front/masks" --pred "$out/synth202/gmm/masks" --out "$out/synth202/eval_segment_gmm"

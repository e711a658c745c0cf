#!/bin/bash
# Does pretraining help the counter? One GPU run, all networks at once (CUDA MPS when available):
#  phase 1: per seed 0-3, pretrain.py --mode synth (synthetic rows) and --mode ssl (contrastive
#           on the training photos' crops), PRE_MIN minutes each
#  phase 2: train.py fine-tunes each pretrained network and trains the control from scratch, the
#           same recipe and seeds, balance full and none (24 networks side by side), EPOCHS epochs
#           each (MAX_MIN minutes at most: a safety stop; on one H200 30 epochs took 68-79 s)
# then pretrain_summary.py. Writes summary.md and results.tgz (json, logs, test probabilities; no
# weights) to $OUT.
# Usage: D=.gpu5 OUT=dir bash scripts/counter_sweep/pretrain.sh
# (a CPU smoke test: PRE_EXTRA="--max-steps 2 --batch 16" EVAL=" " EXTRA="--samples 64" EPOCHS=2)
D=${D:-.gpu5}; PRE_MIN=${PRE_MIN:-2.5}; MAX_MIN=${MAX_MIN:-3.5}; EPOCHS=${EPOCHS:-30}
PRE_TO=${PRE_TO:-220}; FIT_TO=${FIT_TO:-270}  # hard limits per process, seconds
R=/tmp/pretrain; mkdir -p $R $OUT; S=scripts/counter_sweep; PY=${PY:-python3}
T0=$(date +%s); el() { echo "[$(( $(date +%s) - T0 ))s] $*"; }
nvidia-smi --query-gpu=name,memory.used --format=csv,noheader
export CUDA_MPS_PIPE_DIRECTORY=/tmp/mps CUDA_MPS_LOG_DIRECTORY=/tmp/mpslog; mkdir -p /tmp/mps /tmp/mpslog
nvidia-cuda-mps-control -d 2>&1 && echo "MPS on" || echo "MPS off"
export OMP_NUM_THREADS=1 PYTHONUNBUFFERED=1
ls -la $D
el "phase 1"
for s in 0 1 2 3; do
  timeout $PRE_TO $PY $S/pretrain.py --mode synth --data $D/synthpre.npz ${EVAL:---eval $D/data.npz} $PRE_EXTRA --seed $s --minutes $PRE_MIN --out $R/psyn$s.pt > $R/psyn$s.log 2>&1 &
  timeout $PRE_TO $PY $S/pretrain.py --mode ssl --data $D/ssl.npz ${EVAL:---eval $D/data.npz} $PRE_EXTRA --seed $s --minutes $PRE_MIN --out $R/pssl$s.pt > $R/pssl$s.log 2>&1 &
done
wait
for f in $R/p*.log; do echo "== $f"; tail -4 $f; done
(cd $R && tar czf $OUT/pretrain.tgz p*.json p*.log)  # one file: the device tool returns few files
el "phase 2"
F="--data $D/data.npz --width 16 --input 96 --epochs $EPOCHS --ema 0.998 --cosine --final --train-on-val --max-minutes $MAX_MIN $EXTRA"
for s in 0 1 2 3; do for b in full none; do
  timeout $FIT_TO $PY $S/train.py $F --balance $b --seed $s --out $R/ctl_${b}_s$s > $R/ctl_${b}_s$s.log 2>&1 &
  for m in syn ssl; do
    [ -f $R/p$m$s.pt ] && timeout $FIT_TO $PY $S/train.py $F --balance $b --seed $s --init $R/p$m$s.pt --out $R/${m}_${b}_s$s > $R/${m}_${b}_s$s.log 2>&1 &
  done
done; done
wait
el "done"
echo quit | nvidia-cuda-mps-control 2>/dev/null
for f in $R/*_s?.log; do echo "== $f"; grep -v "^epoch" $f | tail -2 | cut -c1-300; grep "^epoch" $f | tail -1; done
(cd $R && tar czf $OUT/results.tgz *.json *.log *_testprobs.npy)
$PY $S/pretrain_summary.py $R $D/data.npz | tee $OUT/summary.md
el "end"

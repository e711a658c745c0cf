#!/bin/bash
# Trains every line of CONFIGS ("name train.py-options") at once, each process at most
# MAX_MINUTES, on one GPU (CUDA MPS when available), prints validation and held-out
# accuracy, and writes results.tar (json, logs, probabilities) and weights*.tar to $OUT.
# Usage: DATA=data.npz OUT=dir bash scripts/counter_sweep/sweep.sh CONFIGS MAX_MINUTES
CONF=$1; FIT=$2; R=/tmp/sweep; mkdir -p $R
nvidia-smi --query-gpu=name,memory.used --format=csv,noheader
export CUDA_MPS_PIPE_DIRECTORY=/tmp/mps CUDA_MPS_LOG_DIRECTORY=/tmp/mpslog; mkdir -p /tmp/mps /tmp/mpslog
nvidia-cuda-mps-control -d 2>&1 && echo "MPS on" || echo "MPS off"
export OMP_NUM_THREADS=1 PYTHONUNBUFFERED=1
while read name args; do
  [ -z "$name" ] && continue
  ${PY:-python3} scripts/counter_sweep/train.py --data ${DATA:-.gpu/data.npz} --out $R/$name $args --max-minutes $FIT > $R/$name.log 2>&1 &
done < $CONF
wait
echo quit | nvidia-cuda-mps-control 2>/dev/null
for f in $R/*.log; do echo "== $f"; grep -v "^epoch" $f | tail -3; grep "^epoch" $f | tail -1; done
${PY:-python3} - <<'PY'
import json, glob, os, tarfile
R = '/tmp/sweep'; out = os.environ['OUT']
res = sorted((json.load(open(f)) for f in glob.glob(R + '/*.json')), key=lambda r: -r['best_val'])
for r in res:
    print(f"{os.path.basename(r['args']['out']):10s} val {r['best_val']:.4f}@{r['best_epoch']}/{r['epochs_run']} valflip {r['val_flip']:.4f} test {r['test']:.4f} (81 {r['test81']:.4f} 76 {r['test76']:.4f}) {r['seconds']:.0f}s")
with tarfile.open(out + '/results.tar', 'w') as t:
    for f in glob.glob(R + '/*.json') + glob.glob(R + '/*.npy') + glob.glob(R + '/*.log'): t.add(f, os.path.basename(f))
# Weights of the best shippable (width <= 32) models, one tar of at most ~15 MB each.
k = 6 if os.environ.get("NOWEIGHTS") else 0; cur = None; size = 0
for r in res:
    w = r['args']['out'] + '.weights'
    if r['args']['width'] > 32 or not os.path.exists(w): continue
    s = os.path.getsize(w)
    if cur is None or size + s > 15e6:
        if cur: cur.close()
        if k >= 6: break
        k += 1; cur = tarfile.open(f"{out}/weights{k}.tar", 'w'); size = 0
    cur.add(w, os.path.basename(w)); size += s
if cur: cur.close()
PY
ls -la $OUT

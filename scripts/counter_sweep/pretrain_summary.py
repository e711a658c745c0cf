# Tables of a pretraining run (pretrain.sh): every fine-tuned network (train.py json +
# flip-averaged test probabilities) and the ensemble of each configuration's seeds (softmax
# outputs averaged, as orchard's ensembles do), held-out accuracy per test set and apples
# counted; then the pretrained networks' own numbers (pretrain.py json).
# Usage: pretrain_summary.py RESULTS_DIR DATA.npz   (networks named CONFIG_sSEED)
import sys, os, glob, json, re, numpy as np
R, data = sys.argv[1], np.load(sys.argv[2])
y81, y76 = data['test81_labels'], data['test76_labels']; y = np.concatenate([y81, y76]); n81 = len(y81)
def score(pr):
    p = pr.argmax(1)
    return {'test': (p == y).mean(), 'test81': (p[:n81] == y81).mean(), 'test76': (p[n81:] == y76).mean(), 'apples': int(p.sum()),
            'per_count': [round(float((p[y == c] == c).mean()), 2) for c in range(7)]}
nets = {}
for f in sorted(glob.glob(os.path.join(R, '*.json'))):
    name = os.path.splitext(os.path.basename(f))[0]
    m = re.match(r'(.+)_s(\d+)$', name); pf = os.path.join(R, name + '_testprobs.npy')
    if not m or not os.path.exists(pf): continue
    nets.setdefault(m.group(1), []).append((int(m.group(2)), json.load(open(f)), np.load(pf)))
print(f'true apples {int(y.sum())}, patches {len(y)} ({n81} + {len(y) - n81})')
print('| config | seed | epochs | held-out | AppleBBCH81 | AppleBBCH76 | apples | per true count 0..6 |')
print('|---|---|---|---|---|---|---|---|')
summary = {}
for cfg in sorted(nets):
    rows = sorted(nets[cfg], key=lambda r: r[0])
    for seed, js, pr in rows:
        s = score(pr)
        assert abs(s['test'] - js['test']) < 1e-3, (cfg, seed, s['test'], js['test'])
        print(f"| {cfg} | {seed} | {js['epochs_run']} | {s['test']:.3f} | {s['test81']:.3f} | {s['test76']:.3f} | {s['apples']} | {s['per_count']} |")
    mean = {k: np.mean([score(pr)[k] for _, _, pr in rows]) for k in ('test', 'test81', 'test76', 'apples')}
    ens = score(np.mean([pr for _, _, pr in rows], 0))
    print(f"| {cfg} | mean of {len(rows)} | | {mean['test']:.3f} | {mean['test81']:.3f} | {mean['test76']:.3f} | {mean['apples']:.0f} | |")
    print(f"| {cfg} | **ensemble** | | **{ens['test']:.3f}** | {ens['test81']:.3f} | {ens['test76']:.3f} | {ens['apples']} | {ens['per_count']} |")
    summary[cfg] = {'seeds': [r[0] for r in rows], 'mean': mean, 'ensemble': ens}
print()
for f in sorted(glob.glob(os.path.join(R, 'p*.json'))):
    js = json.load(open(f))
    if 'steps' not in js: continue
    print(os.path.basename(f), {k: v for k, v in js.items() if k in ('steps', 'train_seconds', 'final_loss') or k.startswith(('knn', 'cls'))})
json.dump(summary, open(os.path.join(R, 'summary.json'), 'w'), default=float)

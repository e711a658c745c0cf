# PyTorch mirror of `orchard train counter` (same ResNet, names, input, augmentation,
# balancing, Adam, validation split) for a recipe sweep on a GPU. Writes the best
# (by validation accuracy) weights as raw float32 tensors that the C++ side imports,
# and held-out accuracy on the test sets (flip-averaged, as orchard count does).
import argparse, json, math, os, sys, time
import cv2, numpy as np, torch, torch.nn as nn, torch.nn.functional as F
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from nets import letterbox, ResNet, gauss_blur

p = argparse.ArgumentParser()
p.add_argument('--data', default='.gpu/data.npz')
p.add_argument('--out', required=True)
p.add_argument('--depth', type=int, default=18)
p.add_argument('--width', type=int, default=16)
p.add_argument('--input', type=int, default=64)
p.add_argument('--epochs', type=int, default=30)
p.add_argument('--samples', type=int, default=4000)
p.add_argument('--batch', type=int, default=32)
p.add_argument('--lr', type=float, default=1e-3)
p.add_argument('--wd', type=float, default=0.0)
p.add_argument('--seed', type=int, default=0)
p.add_argument('--ema', type=float, default=0.0)
p.add_argument('--cosine', action='store_true')
p.add_argument('--smooth', type=float, default=0.0)
p.add_argument('--balance', default='full', choices=['full', 'sqrt', 'none'])
p.add_argument('--rot', type=float, default=5.0)
p.add_argument('--blur', type=float, default=1.0)
p.add_argument('--scale', type=float, default=0.0, help='zoom jitter: scale in [1-s, 1+s]')
p.add_argument('--shift', type=float, default=0.0, help='translation jitter, fraction of the side')
p.add_argument('--color', type=float, default=0.0, help='brightness/contrast/saturation jitter')
p.add_argument('--vflip', action='store_true')
p.add_argument('--mixup', type=float, default=0.0)
p.add_argument('--no-synth', action='store_true')
p.add_argument('--train-on-val', action='store_true')
p.add_argument('--final', action='store_true', help='keep the last epoch, not the best on validation')
p.add_argument('--dump-aug', default='')
p.add_argument('--init', default='', help='start from these weights (pretrain.py output; tensors it lacks keep their initialisation)')
p.add_argument('--max-minutes', type=float, default=1e9)
p.add_argument('--fit-minutes', type=float, default=0, help='cut epochs after the first so the run fits')
a = p.parse_args()
torch.manual_seed(a.seed); np.random.seed(a.seed)
dev = torch.device('cuda' if torch.cuda.is_available() else 'cpu')
torch.backends.cudnn.benchmark = True
torch.backends.cuda.matmul.allow_tf32 = True; torch.backends.cudnn.allow_tf32 = True
if dev.type == 'cpu': torch.set_num_threads(2)

D = np.load(a.data)
def load(key):
    data, off = D[key + '_data'], D[key + '_offsets']
    ims = [letterbox(cv2.imdecode(data[off[i]:off[i + 1]], cv2.IMREAD_COLOR), a.input) for i in range(len(off) - 1)]
    x = torch.from_numpy(np.stack(ims)[..., ::-1].copy()).permute(0, 3, 1, 2).float().div_(127.5).sub_(1)
    return x, torch.from_numpy(D[key + '_labels']), D[key + '_val'], D[key + '_names']
xa, ya, va, names = load('train')
synth = np.array([not n.startswith('DSC') for n in names])
keep = ~synth if a.no_synth else np.ones(len(ya), bool)
tr = np.where((~va | a.train_on_val) & keep)[0]; vl = np.where(va)[0]
xt, yt = xa[tr].to(dev), ya[tr].to(dev)
xv, yv = xa[vl].to(dev), ya[vl].to(dev)
tests = {k: load(k)[:2] for k in ('test81', 'test76')}
tests = {k: (x.to(dev), y.to(dev)) for k, (x, y) in tests.items()}

# Class-balanced sampling weights (full: the study's up-sampling; sqrt: halfway).
cc = np.bincount(yt.cpu().numpy(), minlength=7).astype(float)
power = {'full': 1.0, 'sqrt': 0.5, 'none': 0.0}[a.balance]
w = (1.0 / np.maximum(cc, 1) ** power)[yt.cpu().numpy()]
w = torch.tensor(w / w.sum(), dtype=torch.float, device=dev)

net = ResNet(a.depth, a.width).to(dev).to(memory_format=torch.channels_last)
if a.init:
    sd0 = net.state_dict(); pre = torch.load(a.init, map_location='cpu')
    pre = {k: v for k, v in pre.items() if k in sd0 and sd0[k].shape == v.shape}
    net.load_state_dict(pre, strict=False)
    print(f'init {a.init}: {len(pre)} of {len(sd0)} tensors', flush=True)
ema = None
if a.ema > 0:
    ema = ResNet(a.depth, a.width).to(dev).to(memory_format=torch.channels_last); ema.load_state_dict(net.state_dict())
    for q in ema.parameters(): q.requires_grad_(False)
opt = torch.optim.Adam(net.parameters(), lr=a.lr, betas=(0.9, 0.999), weight_decay=a.wd)

def augment(x):
    n = x.shape[0]; d = x.device
    flip = torch.rand(n, device=d) < 0.5
    x = torch.where(flip[:, None, None, None], x.flip(3), x)
    if a.vflip:
        vf = torch.rand(n, device=d) < 0.5
        x = torch.where(vf[:, None, None, None], x.flip(2), x)
    ang = (torch.rand(n, device=d) * 2 - 1) * math.radians(a.rot)
    sc = 1 + (torch.rand(n, device=d) * 2 - 1) * a.scale
    tx = (torch.rand(n, device=d) * 2 - 1) * a.shift * 2; ty = (torch.rand(n, device=d) * 2 - 1) * a.shift * 2
    cos, sin = torch.cos(ang) / sc, torch.sin(ang) / sc
    theta = torch.stack([torch.stack([cos, -sin, tx], 1), torch.stack([sin, cos, ty], 1)], 1)
    grid = F.affine_grid(theta, list(x.shape), align_corners=False)
    x = F.grid_sample(x + 1, grid, mode='bilinear', padding_mode='zeros', align_corners=False) - 1
    if a.blur > 0:
        sig = torch.rand(n, device=d) * a.blur * (torch.rand(n, device=d) < 0.5)
        x = gauss_blur(x, sig)
    if a.color > 0:
        u = (x + 1) / 2
        b = 1 + (torch.rand(n, 1, 1, 1, device=d) * 2 - 1) * a.color
        c = 1 + (torch.rand(n, 1, 1, 1, device=d) * 2 - 1) * a.color
        s_ = 1 + (torch.rand(n, 1, 1, 1, device=d) * 2 - 1) * a.color
        m = u.mean((1, 2, 3), keepdim=True); gray = u.mean(1, keepdim=True)
        u = ((u - m) * c + m) * b
        u = (u - gray) * s_ + gray
        x = u.clamp(0, 1) * 2 - 1
    return x

@torch.no_grad()
def probs(model, x, flip=True):
    model.eval(); out = []
    for i in range(0, len(x), 512):
        b = x[i:i + 512].contiguous(memory_format=torch.channels_last)
        pr = F.softmax(model(b), 1)
        if flip: pr = (pr + F.softmax(model(b.flip(3)), 1)) / 2
        out.append(pr)
    return torch.cat(out)
def acc(model, x, y, flip=False): return (probs(model, x, flip).argmax(1) == y).float().mean().item()

@torch.no_grad()
def ema_update(decay):
    pe = list(ema.parameters()) + [b for b in ema.buffers() if b.dtype.is_floating_point]
    pn = [q.detach() for q in net.parameters()] + [b for b in net.buffers() if b.dtype.is_floating_point]
    torch._foreach_mul_(pe, decay); torch._foreach_add_(pe, pn, alpha=1 - decay)
    for be, bn in zip(ema.buffers(), net.buffers()):
        if not be.dtype.is_floating_point: be.copy_(bn)

if a.dump_aug:
    x = xt[:64]; rows = [x, augment(x), augment(x)]
    im = torch.cat([torch.cat(list(r[:16]), 2) for r in rows], 1)
    cv2.imwrite(a.dump_aug, ((im.permute(1, 2, 0).cpu().numpy()[..., ::-1] + 1) * 127.5).clip(0, 255).astype(np.uint8)); sys.exit(0)
t0 = time.time(); best = (-1, 0); best_state = None; hist = []
steps = max(1, a.samples // a.batch)
for ep in range(1, 100000):
    if a.cosine:
        for gp in opt.param_groups: gp['lr'] = a.lr * 0.5 * (1 + math.cos(math.pi * (ep - 1) / a.epochs))
    net.train()
    idx = torch.multinomial(w, steps * a.batch, replacement=True)
    tl = 0.0
    for s in range(steps):
        bi = idx[s * a.batch:(s + 1) * a.batch]
        x = augment(xt[bi]).contiguous(memory_format=torch.channels_last); y = yt[bi]
        if a.mixup > 0:
            lam = float(np.random.beta(a.mixup, a.mixup)); perm = torch.randperm(len(y), device=dev)
            x = lam * x + (1 - lam) * x[perm]
            logits = net(x)
            loss = lam * F.cross_entropy(logits, y, label_smoothing=a.smooth) + (1 - lam) * F.cross_entropy(logits, y[perm], label_smoothing=a.smooth)
        else:
            loss = F.cross_entropy(net(x), y, label_smoothing=a.smooth)
        opt.zero_grad(set_to_none=True); loss.backward(); opt.step()
        if ema is not None: ema_update(a.ema)
        tl += loss.item() if s % 20 == 0 else 0
    model = ema if ema is not None else net
    v = acc(model, xv, yv)
    hist.append(round(v, 4))
    if v > best[0] or a.final:
        best = (v, ep); best_state = {k: t.detach().cpu().clone() for k, t in model.state_dict().items()}
    el = time.time() - t0
    print(f'epoch {ep}/{a.epochs} loss {tl / max(1, (steps + 19) // 20):.3f} val {v:.4f} {el:.0f}s', flush=True)
    if ep == 1 and a.fit_minutes > 0: a.epochs = max(2, min(a.epochs, int(a.fit_minutes * 60 / el)))
    if el / 60 > a.max_minutes or ep >= a.epochs: break
model = ema if ema is not None else net
model.load_state_dict({k: t.to(dev) for k, t in best_state.items()})
res = {'args': vars(a), 'best_val': best[0], 'best_epoch': best[1], 'epochs_run': ep, 'seconds': round(time.time() - t0, 1), 'val_hist': hist}
allp, ally = [], []
for k, (x, y) in tests.items():
    pr = probs(model, x, True); allp.append(pr); ally.append(y)
    res[k] = round((pr.argmax(1) == y).float().mean().item(), 4)
    res[k + '_noflip'] = round(acc(model, x, y, False), 4)
pr = torch.cat(allp); y = torch.cat(ally)
res['test'] = round((pr.argmax(1) == y).float().mean().item(), 4)
res['val_flip'] = round(acc(model, xv, yv, True), 4)
cm = torch.zeros(7, 7, dtype=torch.long)
for t_, p_ in zip(y.cpu(), pr.argmax(1).cpu()): cm[t_, p_] += 1
res['confusion'] = cm.tolist()
os.makedirs(os.path.dirname(a.out) or '.', exist_ok=True)
np.save(a.out + '_testprobs.npy', pr.cpu().numpy())
np.save(a.out + '_valprobs.npy', probs(model, xv, True).cpu().numpy())
# Raw weights: index lines "name shape..." then float32 data in that order.
with open(a.out + '.weights', 'wb') as f:
    sd = model.state_dict()
    index = [k + ' ' + ' '.join(map(str, t.shape)) for k, t in sd.items()]
    head = ('\n'.join(index) + '\n').encode()
    f.write(len(head).to_bytes(8, 'little')); f.write(head)
    for k, t in sd.items(): f.write(t.detach().cpu().float().contiguous().numpy().tobytes())
json.dump(res, open(a.out + '.json', 'w'))
print(json.dumps({k: res[k] for k in ('best_val', 'best_epoch', 'epochs_run', 'seconds', 'test81', 'test76', 'test', 'val_flip')}), a.out)

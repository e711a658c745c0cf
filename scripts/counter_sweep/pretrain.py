# Pretrains the counter's ResNet (the same network and parameter names as train.py) for a
# fixed wall-clock time, then saves its weights for `train.py --init`:
#   --mode synth  supervised counts (0..6) on synthetic patches (pack_pretrain.py synth);
#                 saves every tensor, the count head included
#   --mode ssl    SimCLR-style contrastive learning on crops of the training photos
#                 (pack_pretrain.py ssl): two letterboxed views of one random region of a photo
#                 are the positive pair, every other view in the batch a negative (NT-Xent);
#                 saves the stem and stages (no head)
# The learning rate follows a half cosine over the time budget (--minutes), so the schedule ends
# whatever the machine's speed. With --eval DATA.npz (pack_pretrain.py data) it reports, for the
# pretrained network before any fine-tuning, a k-nearest-neighbour count accuracy (features of the
# real training patches, cosine, k=20) on the test sets, and in synth mode its own classifier's.
import argparse, json, math, os, sys, time
import cv2, numpy as np, torch, torch.nn as nn, torch.nn.functional as F
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from nets import letterbox, ResNet, gauss_blur  # as train.py

p = argparse.ArgumentParser()
p.add_argument('--mode', required=True, choices=['synth', 'ssl'])
p.add_argument('--data', required=True)
p.add_argument('--eval', default='')
p.add_argument('--out', required=True)
p.add_argument('--width', type=int, default=16)
p.add_argument('--input', type=int, default=96)
p.add_argument('--seed', type=int, default=0)
p.add_argument('--minutes', type=float, default=2.5)
p.add_argument('--max-steps', type=int, default=10 ** 9)
p.add_argument('--batch', type=int, default=0, help='0: 128 (synth), 256 (ssl; images per batch, two views each)')
p.add_argument('--lr', type=float, default=1e-3)
p.add_argument('--wd', type=float, default=1e-6)
p.add_argument('--balance', default='sqrt', choices=['full', 'sqrt', 'none'])
p.add_argument('--color', type=float, default=0.2, help='synth: brightness/contrast/saturation jitter')
p.add_argument('--temp', type=float, default=0.2, help='ssl: NT-Xent temperature')
p.add_argument('--region', default='32,96', help='ssl: side of the region both views come from, stored pixels')
p.add_argument('--dump', default='', help='write a sheet of training inputs to this PNG and stop')
a = p.parse_args()
if a.batch == 0: a.batch = 128 if a.mode == 'synth' else 256
torch.manual_seed(a.seed); np.random.seed(a.seed)
dev = torch.device('cuda' if torch.cuda.is_available() else 'cpu')
torch.backends.cudnn.benchmark = True
torch.backends.cuda.matmul.allow_tf32 = True; torch.backends.cudnn.allow_tf32 = True
if dev.type == 'cpu': torch.set_num_threads(1)
t_start = time.time()

def decode(D, key, size=None):
    data, off = D[key + '_data'], D[key + '_offsets']
    ims = [cv2.imdecode(data[off[i]:off[i + 1]], cv2.IMREAD_COLOR) for i in range(len(off) - 1)]
    if size: ims = [letterbox(im, size) for im in ims]
    return torch.from_numpy(np.stack(ims)[..., ::-1].copy()).permute(0, 3, 1, 2).contiguous()  # uint8 RGB NCHW
def to_float(x): return x.float().div_(127.5).sub_(1)

def color_jitter(x, amount, gray_p=0.0):
    n = x.shape[0]; d = x.device
    u = (x + 1) / 2
    b = 1 + (torch.rand(n, 1, 1, 1, device=d) * 2 - 1) * amount
    c = 1 + (torch.rand(n, 1, 1, 1, device=d) * 2 - 1) * amount
    s_ = 1 + (torch.rand(n, 1, 1, 1, device=d) * 2 - 1) * amount
    if gray_p > 0: s_ = torch.where(torch.rand(n, 1, 1, 1, device=d) < gray_p, torch.zeros_like(s_), s_)
    m = u.mean((1, 2, 3), keepdim=True); gray = u.mean(1, keepdim=True)
    u = ((u - m) * c + m) * b
    u = (u - gray) * s_ + gray
    return u.clamp(0, 1) * 2 - 1
def augment_patch(x):  # train.py's flip, +-5 degrees, blur; plus colour jitter
    n = x.shape[0]; d = x.device
    flip = torch.rand(n, device=d) < 0.5
    x = torch.where(flip[:, None, None, None], x.flip(3), x)
    ang = (torch.rand(n, device=d) * 2 - 1) * math.radians(5.0)
    cos, sin, z = torch.cos(ang), torch.sin(ang), torch.zeros(n, device=d)
    theta = torch.stack([torch.stack([cos, -sin, z], 1), torch.stack([sin, cos, z], 1)], 1)
    grid = F.affine_grid(theta, list(x.shape), align_corners=False)
    x = F.grid_sample(x + 1, grid, mode='bilinear', padding_mode='zeros', align_corners=False) - 1
    x = gauss_blur(x, torch.rand(n, device=d) * (torch.rand(n, device=d) < 0.5))
    return color_jitter(x, a.color) if a.color > 0 else x

def ssl_views(src, cx, cy, side):
    # One letterboxed view per image: a crop of 30-100% of the region's area, aspect 1:2..2:1,
    # anywhere inside the region (centre cx, cy, side `side`, stored pixels), resized so its longer
    # side fills the input, zero-padded as the patches are; random flip, colour, grey, blur.
    n, _, H, W = src.shape; d = src.device; S = a.input
    area = torch.empty(n, device=d).uniform_(0.3, 1.0)
    asp = torch.exp(torch.empty(n, device=d).uniform_(math.log(0.5), math.log(2.0)))
    w = (side * torch.sqrt(area * asp)).clamp(max=side); h = (side * torch.sqrt(area / asp)).clamp(max=side)
    vx = cx + (torch.rand(n, device=d) - 0.5) * (side - w); vy = cy + (torch.rand(n, device=d) - 0.5) * (side - h)
    fx = torch.where(w >= h, torch.ones_like(w), w / h); fy = torch.where(h >= w, torch.ones_like(h), h / w)
    t = (torch.arange(S, device=d, dtype=torch.float) + 0.5) / S * 2 - 1  # output pixel centres in [-1, 1]
    sgn = torch.where(torch.rand(n, device=d) < 0.5, -1.0, 1.0)
    u = t[None, None, :] * sgn[:, None, None]; v = t[None, :, None]
    xs = vx[:, None, None] + u / fx[:, None, None] * w[:, None, None] / 2   # source, edge coordinates
    ys = vy[:, None, None] + v / fy[:, None, None] * h[:, None, None] / 2
    grid = torch.stack([(2 * xs / W - 1).expand(n, S, S), (2 * ys / H - 1).expand(n, S, S)], -1)
    x = F.grid_sample(src, grid, mode='bilinear', padding_mode='border', align_corners=False)
    inside = ((t[None, None, :].abs() <= fx[:, None, None]) & (t[None, :, None].abs() <= fy[:, None, None]))[:, None]
    jit = torch.rand(n, device=d) < 0.8
    x = torch.where(jit[:, None, None, None], color_jitter(x, 0.4, 0.2), x)
    x = gauss_blur(x, torch.rand(n, device=d) * 1.5 * (torch.rand(n, device=d) < 0.5))
    return torch.where(inside, x, torch.full_like(x, -1.0))

D = np.load(a.data)
net = ResNet(18, a.width).to(dev).to(memory_format=torch.channels_last)
if a.mode == 'synth':
    xs_u8 = decode(D, 'synth', a.input).to(dev); ys = torch.from_numpy(D['synth_labels']).to(dev)
    cc = np.bincount(ys.cpu().numpy(), minlength=7).astype(float)
    power = {'full': 1.0, 'sqrt': 0.5, 'none': 0.0}[a.balance]
    wts = torch.tensor((1.0 / np.maximum(cc, 1) ** power)[ys.cpu().numpy()], dtype=torch.float, device=dev)
    params = list(net.parameters())
    print(f'synth patches {len(ys)} counts {cc.astype(int).tolist()}', flush=True)
else:
    src_u8 = decode(D, 'ssl').to(dev)
    proj = nn.Sequential(nn.Linear(net.features, 256), nn.BatchNorm1d(256), nn.ReLU(True), nn.Linear(256, 64)).to(dev)
    params = list(net.stem.parameters()) + list(net.stages.parameters()) + list(proj.parameters())
    r0, r1 = map(float, a.region.split(','))
    print(f'ssl photo crops {src_u8.shape[0]} of {tuple(src_u8.shape[2:])}', flush=True)
opt = torch.optim.Adam(params, lr=a.lr, weight_decay=a.wd)

def batch():
    if a.mode == 'synth':
        i = torch.multinomial(wts, a.batch, replacement=True)
        return augment_patch(to_float(xs_u8[i])), ys[i]
    n = a.batch; i = torch.randint(0, src_u8.shape[0], (n,), device=dev)
    src = to_float(src_u8[i]); H, W = src.shape[2:]
    side = torch.empty(n, device=dev).uniform_(r0, r1)
    cx = side / 2 + torch.rand(n, device=dev) * (W - side); cy = side / 2 + torch.rand(n, device=dev) * (H - side)
    return torch.cat([ssl_views(src, cx, cy, side), ssl_views(src, cx, cy, side)]), None

if a.dump:
    x, _ = batch(); k = 16 if a.mode == 'synth' else min(16, a.batch)
    rows = [x[:k]] if a.mode == 'synth' else [x[:k], x[a.batch:a.batch + k]]
    im = torch.cat([torch.cat(list(r), 2) for r in rows], 1)
    cv2.imwrite(a.dump, ((im.permute(1, 2, 0).cpu().numpy()[..., ::-1] + 1) * 127.5).clip(0, 255).astype(np.uint8)); sys.exit(0)

T = a.minutes * 60; t0 = time.time(); step = 0; last = t0; losses = []
print(f'setup {t0 - t_start:.1f}s', flush=True)
while True:
    el = time.time() - t0
    if el >= T or step >= a.max_steps: break
    f = el / T
    for g in opt.param_groups: g['lr'] = a.lr * min(1.0, f / 0.03) * 0.5 * (1 + math.cos(math.pi * f))
    net.train()
    x, y = batch(); x = x.contiguous(memory_format=torch.channels_last)
    if a.mode == 'synth':
        loss = F.cross_entropy(net(x), y)
    else:
        proj.train()
        z = F.normalize(proj(net.embed(x)), dim=1); n = a.batch
        sim = z @ z.t() / a.temp
        sim = sim.masked_fill(torch.eye(2 * n, device=dev, dtype=torch.bool), float('-inf'))
        target = torch.cat([torch.arange(n, 2 * n), torch.arange(0, n)]).to(dev)
        loss = F.cross_entropy(sim, target)
    opt.zero_grad(set_to_none=True); loss.backward(); opt.step(); step += 1
    if step % 25 == 1: losses.append(loss.item())
    if time.time() - last > 20:
        last = time.time(); print(f'step {step} loss {np.mean(losses[-8:]):.3f} {last - t0:.0f}s', flush=True)
train_s = time.time() - t0
sd = {k: v.detach().cpu() for k, v in net.state_dict().items() if a.mode == 'synth' or not k.startswith('head.')}
os.makedirs(os.path.dirname(a.out) or '.', exist_ok=True)
torch.save(sd, a.out)
res = {'args': vars(a), 'steps': step, 'train_seconds': round(train_s, 1), 'loss_hist': [round(l, 4) for l in losses[::4]],
       'final_loss': round(float(np.mean(losses[-8:])), 4) if losses else None}
print(f'saved {a.out}: {step} steps in {train_s:.0f}s, loss {res["final_loss"]}', flush=True)

if a.eval:
    @torch.no_grad()
    def run(fn, x):
        net.eval(); return torch.cat([fn(to_float(x[i:i + 512].to(dev)).contiguous(memory_format=torch.channels_last)) for i in range(0, len(x), 512)])
    E = np.load(a.eval)
    xtr = decode(E, 'train', a.input); ytr = torch.from_numpy(E['train_labels']).to(dev)
    real = torch.from_numpy(np.array([n.startswith('DSC') for n in E['train_names']])).to(dev)
    ftr = F.normalize(run(net.embed, xtr), dim=1)[real]; ltr = ytr[real]
    allk, ally, allc = [], [], []
    for key in ('test81', 'test76'):
        xt = decode(E, key, a.input); yt = torch.from_numpy(E[key + '_labels']).to(dev)
        ft = F.normalize(run(net.embed, xt), dim=1)
        sim, idx = (ft @ ftr.t()).topk(20, dim=1)
        votes = torch.zeros(len(yt), 7, device=dev).scatter_add_(1, ltr[idx], torch.exp(sim / 0.1))
        pk = votes.argmax(1); res['knn_' + key] = round((pk == yt).float().mean().item(), 4)
        allk.append(pk); ally.append(yt)
        if a.mode == 'synth':
            pc = run(net, xt).argmax(1); allc.append(pc)
            res['cls_' + key] = round((pc == yt).float().mean().item(), 4)
    y = torch.cat(ally); res['knn_test'] = round((torch.cat(allk) == y).float().mean().item(), 4)
    if allc:
        pc = torch.cat(allc); res['cls_test'] = round((pc == y).float().mean().item(), 4); res['cls_apples'] = int(pc.sum().item())
    print(json.dumps({k: v for k, v in res.items() if k.startswith(('knn', 'cls'))}), flush=True)
json.dump(res, open(os.path.splitext(a.out)[0] + '.json', 'w'))
print(f'done {time.time() - t_start:.0f}s', flush=True)

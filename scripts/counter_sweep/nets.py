# The counter's pieces shared by train.py and pretrain.py: letterboxing as `LetterboxPatch`,
# the ResNet of src/orchard/nn/models.cc (same parameter names) and the per-sample blur.
import math
import cv2, numpy as np, torch, torch.nn as nn, torch.nn.functional as F

def letterbox(im, size):
    s = size / max(im.shape[:2])
    w = min(max(int(math.floor(im.shape[1] * s + 0.5)), 1), size)
    h = min(max(int(math.floor(im.shape[0] * s + 0.5)), 1), size)
    r = cv2.resize(im, (w, h), interpolation=cv2.INTER_AREA if s < 1 else cv2.INTER_LINEAR)
    out = np.zeros((size, size, 3), np.uint8)
    y0, x0 = (size - h) // 2, (size - w) // 2
    out[y0:y0 + h, x0:x0 + w] = r
    return out

class Block(nn.Module):
    def __init__(s, i, o, st):
        super().__init__()
        s.conv1 = nn.Conv2d(i, o, 3, st, 1, bias=False); s.bn1 = nn.BatchNorm2d(o)
        s.conv2 = nn.Conv2d(o, o, 3, 1, 1, bias=False); s.bn2 = nn.BatchNorm2d(o)
        s.shortcut = nn.Sequential(nn.Conv2d(i, o, 1, st, bias=False), nn.BatchNorm2d(o)) if st != 1 or i != o else None
    def forward(s, x):
        y = s.bn2(s.conv2(F.relu(s.bn1(s.conv1(x)))))
        return F.relu(y + (s.shortcut(x) if s.shortcut is not None else x))
class Bottle(nn.Module):
    def __init__(s, i, wd, st):
        super().__init__(); o = wd * 4
        s.conv1 = nn.Conv2d(i, wd, 1, bias=False); s.bn1 = nn.BatchNorm2d(wd)
        s.conv2 = nn.Conv2d(wd, wd, 3, st, 1, bias=False); s.bn2 = nn.BatchNorm2d(wd)
        s.conv3 = nn.Conv2d(wd, o, 1, bias=False); s.bn3 = nn.BatchNorm2d(o)
        s.shortcut = nn.Sequential(nn.Conv2d(i, o, 1, st, bias=False), nn.BatchNorm2d(o)) if st != 1 or i != o else None
    def forward(s, x):
        y = F.relu(s.bn1(s.conv1(x))); y = F.relu(s.bn2(s.conv2(y))); y = s.bn3(s.conv3(y))
        return F.relu(y + (s.shortcut(x) if s.shortcut is not None else x))
class ResNet(nn.Module):
    def __init__(s, depth, wd):
        super().__init__()
        s.stem = nn.Sequential(nn.Conv2d(3, wd, 7, 2, 3, bias=False), nn.BatchNorm2d(wd), nn.ReLU(True), nn.MaxPool2d(3, 2, 1))
        blocks = {18: [2, 2, 2, 2], 34: [3, 4, 6, 3], 50: [3, 4, 6, 3]}[depth]
        layers, i = [], wd
        for st_i, n in enumerate(blocks):
            width = wd << st_i
            for b in range(n):
                stride = 2 if b == 0 and st_i > 0 else 1
                if depth >= 50: layers.append(Bottle(i, width, stride)); i = width * 4
                else: layers.append(Block(i, width, stride)); i = width
        s.stages = nn.Sequential(*layers)
        s.head = nn.Linear(i, 7); s.features = i
    def embed(s, x): return F.adaptive_avg_pool2d(s.stages(s.stem(x)), 1).flatten(1)
    def forward(s, x): return s.head(s.embed(x))

def gauss_blur(x, sigma):
    # Per-sample Gaussian blur (sigma tensor [N]); sigma <= 0.1 leaves the sample unchanged.
    k = 7; r = torch.arange(k, device=x.device, dtype=x.dtype) - k // 2
    s = sigma.clamp(min=1e-3)[:, None]
    g = torch.exp(-0.5 * (r[None] / s) ** 2); g = g / g.sum(1, keepdim=True)
    g = torch.where((sigma > 0.1)[:, None], g, (r == 0).to(x.dtype)[None].expand_as(g))
    n, c, h, wd = x.shape
    y = x.reshape(1, n * c, h, wd)
    gx = g.repeat_interleave(c, 0)[:, None, None, :]
    gy = g.repeat_interleave(c, 0)[:, None, :, None]
    y = F.conv2d(F.pad(y, (k // 2, k // 2, 0, 0), mode='replicate'), gx, groups=n * c)
    y = F.conv2d(F.pad(y, (0, 0, k // 2, k // 2), mode='replicate'), gy, groups=n * c)
    return y.reshape(n, c, h, wd)

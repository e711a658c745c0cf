# Packs counter patch folders (`orchard patches`, `orchard synth`) into one npz for
# train.py: patches capped at 128 px on the longer side, training patches as JPEG
# (quality 95) and test patches as PNG so the file travels to a GPU machine; the
# validation photos are those `orchard train counter` holds out (--val-fraction 0.2,
# --split-seed 1: the same mt19937_64 shuffle as ChooseTestPhotos).
# Usage: pack.py OUT.npz train=DIR,DIR,... test81=DIR test76=DIR
import sys, csv, os, re, cv2, numpy as np
MASK = (1 << 64) - 1
class MT64:
    def __init__(s, seed):
        s.mt = [0] * 312; s.mt[0] = seed & MASK
        for i in range(1, 312):
            s.mt[i] = (6364136223846793005 * (s.mt[i-1] ^ (s.mt[i-1] >> 62)) + i) & MASK
        s.i = 312
    def __call__(s):
        if s.i >= 312:
            for i in range(312):
                x = (s.mt[i] & 0xFFFFFFFF80000000) | (s.mt[(i+1) % 312] & 0x7FFFFFFF)
                xa = x >> 1
                if x & 1: xa ^= 0xB5026F5AA96619E9
                s.mt[i] = s.mt[(i + 156) % 312] ^ xa
            s.i = 0
        y = s.mt[s.i]; s.i += 1
        y ^= (y >> 29) & 0x5555555555555555
        y ^= (y << 17) & 0x71D67FFFEDA60000
        y ^= (y << 37) & 0xFFF7EEE000000000
        y ^= y >> 43
        return y & MASK
def image_stem(name):  # patch file -> the 640x640 crop it was cut from
    return re.sub(r"_p[0-9]+$", "", os.path.splitext(os.path.basename(name))[0])
def photo_id(name):
    stem = image_stem(name)
    u = stem.rfind('_')
    if u < 0 or u + 1 == len(stem): return stem
    return stem[:u] if stem[u+1:].isdigit() else stem
def choose(photos, frac, seed):
    p = sorted(set(photos)); rng = MT64(seed)
    for i in range(len(p), 1, -1):
        j = rng() % i; p[i-1], p[j] = p[j], p[i-1]
    n = int(np.floor(frac * len(p) + 0.5)); n = min(max(n, 1), len(p) - 1)
    return sorted(p[:n])
def read(d):
    out = []
    for name, count in csv.reader(open(os.path.join(d, 'counts.csv'))):
        path = os.path.join(d, name)
        if not os.path.exists(path): path = os.path.join(d, 'images', name)
        im = cv2.imread(path, cv2.IMREAD_COLOR)
        s = 128.0 / max(im.shape[:2])
        if s < 1:
            im = cv2.resize(im, (max(1, round(im.shape[1]*s)), max(1, round(im.shape[0]*s))), interpolation=cv2.INTER_AREA)
        out.append((im, int(count), photo_id(name), name))
    return out
def main():
    sets = {}
    for arg in sys.argv[2:]:
        key, dirs = arg.split('=')
        sets[key] = sum((read(d) for d in dirs.split(',')), [])
    train_photos = [p for _, _, p, _ in sets['train']]
    val = set(choose(train_photos, 0.2, 1))
    print('val photos', len(val), 'of', len(set(train_photos)), sorted(val)[:5])
    arrays = {}
    for key, items in sets.items():
        enc = [cv2.imencode('.png' if key.startswith('test') else '.jpg', im, [cv2.IMWRITE_JPEG_QUALITY, 95])[1].reshape(-1) for im, *_ in items]
        arrays[key + '_data'] = np.concatenate(enc)
        arrays[key + '_offsets'] = np.cumsum([0] + [len(e) for e in enc])
        arrays[key + '_labels'] = np.array([c for _, c, _, _ in items], np.int64)
        arrays[key + '_val'] = np.array([p in val for _, _, p, _ in items])
        arrays[key + '_names'] = np.array([n for *_, n in items])
        print(key, len(items), 'val', int(arrays[key + '_val'].sum()), np.bincount(arrays[key + '_labels'], minlength=7))
    np.savez(sys.argv[1], **arrays)


if __name__ == '__main__':
    main()

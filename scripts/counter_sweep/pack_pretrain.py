# Packs the data of the pretraining experiment (pretrain.py) small enough to travel to a GPU
# machine (the device tool carries at most 64 MiB with the repository):
#   data   OUT/data.npz      as pack.py, but patches capped at 96 px (the input size) and
#                            training patches as JPEG quality 90; test patches stay PNG
#   synth  OUT/synthpre.npz  counted synthetic patches (key 'synth'), a random subset of at most
#                            --max-synth patches of the given rows, JPEG quality 85, capped at 96 px
#   ssl    OUT/ssl.npz       the training photos' 640x640 crops (key 'ssl'), resized by --ssl-scale,
#                            JPEG --quality (85); only crops that the train patch folders name, and the
#                            script stops if any of their photos has a patch in a test folder
# Usage:
#   pack_pretrain.py data OUT.npz train=DIR,DIR,... test81=DIR test76=DIR
#   pack_pretrain.py synth OUT.npz --max-synth N DIR DIR ...
#   pack_pretrain.py ssl OUT.npz --ssl-scale 0.6 --quality 85 --train DIR,DIR --test DIR,DIR --images DIR,DIR
import sys, csv, os, glob, argparse, cv2, numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pack import choose, image_stem, photo_id  # the same photo split as pack.py and orchard
def cap(im, side):
    s = side / max(im.shape[:2])
    if s < 1:
        im = cv2.resize(im, (max(1, round(im.shape[1]*s)), max(1, round(im.shape[0]*s))), interpolation=cv2.INTER_AREA)
    return im
def read(d, side):
    out = []
    for name, count in csv.reader(open(os.path.join(d, 'counts.csv'))):
        path = os.path.join(d, name)
        if not os.path.exists(path): path = os.path.join(d, 'images', name)
        im = cv2.imread(path, cv2.IMREAD_COLOR)
        assert im is not None, path
        out.append((cap(im, side), int(count), photo_id(name), name))
    return out
def names(d):
    return [row[0] for row in csv.reader(open(os.path.join(d, 'counts.csv')))]
def encode(ims, ext, q):
    enc = [cv2.imencode(ext, im, [cv2.IMWRITE_JPEG_QUALITY, q] if ext == '.jpg' else [cv2.IMWRITE_PNG_COMPRESSION, 9])[1].reshape(-1) for im in ims]
    return np.concatenate(enc), np.cumsum([0] + [len(e) for e in enc])

mode, out = sys.argv[1], sys.argv[2]
if mode == 'data':
    sets = {}
    for arg in sys.argv[3:]:
        key, dirs = arg.split('=')
        sets[key] = sum((read(d, 96) for d in dirs.split(',')), [])
    val = set(choose([p for _, _, p, _ in sets['train']], 0.2, 1))
    arrays = {}
    for key, items in sets.items():
        test = key.startswith('test')
        arrays[key + '_data'], arrays[key + '_offsets'] = encode([im for im, *_ in items], '.png' if test else '.jpg', 90)
        arrays[key + '_labels'] = np.array([c for _, c, _, _ in items], np.int64)
        arrays[key + '_val'] = np.array([p in val for _, _, p, _ in items])
        arrays[key + '_names'] = np.array([n for *_, n in items])
        print(key, len(items), 'val', int(arrays[key + '_val'].sum()), np.bincount(arrays[key + '_labels'], minlength=7),
              f"{arrays[key + '_data'].nbytes / 1e6:.1f} MB")
    np.savez(out, **arrays)
elif mode == 'synth':
    p = argparse.ArgumentParser(); p.add_argument('--max-synth', type=int, default=12000); p.add_argument('--seed', type=int, default=0)
    p.add_argument('dirs', nargs='+'); a = p.parse_args(sys.argv[3:])
    rows = [(d, n, int(c)) for d in a.dirs for n, c in csv.reader(open(os.path.join(d, 'counts.csv')))]
    rng = np.random.default_rng(a.seed)
    pick = sorted(rng.choice(len(rows), min(a.max_synth, len(rows)), replace=False))
    ims = []
    for i in pick:
        d, n, _ = rows[i]
        path = os.path.join(d, n) if os.path.exists(os.path.join(d, n)) else os.path.join(d, 'images', n)
        ims.append(cap(cv2.imread(path, cv2.IMREAD_COLOR), 96))
    data, off = encode(ims, '.jpg', 85)
    labels = np.array([rows[i][2] for i in pick], np.int64)
    print('synth', len(pick), 'of', len(rows), 'rows', len(a.dirs), np.bincount(labels, minlength=7), f'{data.nbytes / 1e6:.1f} MB')
    np.savez(out, synth_data=data, synth_offsets=off, synth_labels=labels)
elif mode == 'ssl':
    p = argparse.ArgumentParser(); p.add_argument('--ssl-scale', type=float, default=0.6); p.add_argument('--quality', type=int, default=85)
    p.add_argument('--train', required=True); p.add_argument('--test', required=True); p.add_argument('--images', required=True)
    a = p.parse_args(sys.argv[3:])
    train_stems = {image_stem(n) for d in a.train.split(',') for n in names(d)}
    test_photos = {photo_id(n) for d in a.test.split(',') for n in names(d)}
    train_photos = {photo_id(s + '.png') for s in train_stems}
    assert not (train_photos & test_photos), 'a training photo has test patches'
    files = sorted(f for d in a.images.split(',') for f in glob.glob(os.path.join(d, '*')) if image_stem(f) in train_stems)
    assert len(files) == len(train_stems), (len(files), len(train_stems))
    assert all(photo_id(f) not in test_photos for f in files)
    ims = []
    for f in files:
        im = cv2.imread(f, cv2.IMREAD_COLOR)
        ims.append(cv2.resize(im, (round(im.shape[1] * a.ssl_scale), round(im.shape[0] * a.ssl_scale)), interpolation=cv2.INTER_AREA))
    data, off = encode(ims, '.jpg', a.quality)
    print('ssl', len(files), 'crops of', len(train_photos), 'training photos;', len(test_photos), 'test photos excluded;',
          ims[0].shape, f'{data.nbytes / 1e6:.1f} MB')
    np.savez(out, ssl_data=data, ssl_offsets=off, ssl_names=np.array([os.path.basename(f) for f in files]))

"""Image helpers for the report: PFM reading, per-pixel error, crops, crop frames.

Metrics are never computed here (imgtool does that); this module only picks
crop regions and cuts and scales the preview PNGs written by imgtool.
"""

import numpy as np


def read_pfm(path):
    """Float image (H, W, C) from a PFM file, top row first."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        if kind not in (b"PF", b"Pf"):
            raise ValueError("%s: not a PFM file" % path)
        dims = f.readline().split()
        while len(dims) < 2:
            dims += f.readline().split()
        w, h = int(dims[0]), int(dims[1])
        scale = float(f.readline().strip())
        dtype = "<f4" if scale < 0 else ">f4"
        c = 3 if kind == b"PF" else 1
        data = np.frombuffer(f.read(w * h * c * 4), dtype=dtype).astype(np.float64)
    return data.reshape(h, w, c)[::-1]


def relmse_map(image, reference, eps=0.001):
    """Per-pixel relMSE, averaged over channels (the papers' formula; used only to pick crops)."""
    d = (image - reference) ** 2 / (reference ** 2 + eps)
    d = np.where(np.isfinite(d), d, 0.0)
    return d.mean(axis=2)


def pick_crops(err, count=2, frac=0.25):
    """Crop boxes [x0, y0, x1, y1] (fractions) where the per-pixel error is highest.

    A box is about `frac` of the smaller image side; boxes do not overlap."""
    h, w = err.shape
    side = max(4, int(round(min(h, w) * frac)))
    side = min(side, h, w)
    # Box sums via an integral image, on a half-box stride.
    ii = np.zeros((h + 1, w + 1))
    ii[1:, 1:] = np.cumsum(np.cumsum(err, axis=0), axis=1)
    step = max(1, side // 2)
    cands = []
    for y in range(0, h - side + 1, step):
        for x in range(0, w - side + 1, step):
            s = ii[y + side, x + side] - ii[y, x + side] - ii[y + side, x] + ii[y, x]
            cands.append((s, x, y))
    cands.sort(reverse=True)
    chosen = []
    for s, x, y in cands:
        if all(abs(x - cx) >= side or abs(y - cy) >= side for cx, cy in chosen):
            chosen.append((x, y))
        if len(chosen) == count:
            break
    return [[x / w, y / h, (x + side) / w, (y + side) / h] for x, y in chosen]


def crop_pixels(box, w, h):
    x0 = int(np.floor(box[0] * w))
    y0 = int(np.floor(box[1] * h))
    x1 = max(x0 + 1, int(np.ceil(box[2] * w)))
    y1 = max(y0 + 1, int(np.ceil(box[3] * h)))
    return x0, y0, min(x1, w), min(y1, h)


CROP_COLOURS = [(1.0, 0.85, 0.0), (0.0, 0.9, 1.0), (1.0, 0.3, 0.9), (0.4, 1.0, 0.3)]


def _load_png(path):
    import matplotlib.image as mpimg
    img = mpimg.imread(path)
    if img.dtype != np.float32 and img.dtype != np.float64:
        img = img.astype(np.float64) / 255.0
    return img[:, :, :3]


def _save_png(path, img):
    import matplotlib.image as mpimg
    mpimg.imsave(path, np.clip(img, 0.0, 1.0))


def upscale(img, min_width):
    k = max(1, int(np.ceil(min_width / img.shape[1])))
    return np.repeat(np.repeat(img, k, axis=0), k, axis=1)


def framed_copy(src_png, dst_png, boxes, min_width=320):
    """The preview scaled up (nearest) with a coloured frame around each crop box."""
    img = _load_png(src_png)
    h, w = img.shape[:2]
    big = upscale(img, min_width).copy()
    k = big.shape[0] // h
    t = max(1, k // 2)
    for i, box in enumerate(boxes):
        x0, y0, x1, y1 = crop_pixels(box, w, h)
        x0, y0, x1, y1 = x0 * k, y0 * k, x1 * k, y1 * k
        c = CROP_COLOURS[i % len(CROP_COLOURS)]
        big[y0:y0 + t, x0:x1] = c
        big[y1 - t:y1, x0:x1] = c
        big[y0:y1, x0:x0 + t] = c
        big[y0:y1, x1 - t:x1] = c
    _save_png(dst_png, big)


def crop_png(src_png, dst_png, box, min_width=160):
    img = _load_png(src_png)
    h, w = img.shape[:2]
    x0, y0, x1, y1 = crop_pixels(box, w, h)
    _save_png(dst_png, upscale(img[y0:y1, x0:x1], min_width))


def scaled_copy(src_png, dst_png, min_width=320):
    _save_png(dst_png, upscale(_load_png(src_png), min_width))

#!/usr/bin/env python3
"""The errors of an animation's frames against per-frame ground truths, beside bench's relMSE.

Usage: lab/frame-errors.py FRAMES_DIR TRUTH_DIR [MATCH]
  FRAMES_DIR: `bounce render … --frames N --out-dir FRAMES_DIR` (frame_0000.exr, …), rendered with the
              component of the truths (bench's are `--component indirect`);
  TRUTH_DIR:  a `bounce bench --animate … --out DIR` folder: its reference-…-frameNNNN.exr, one a frame
              (MATCH, a substring of the names, picks one path's where the folder holds several).
Prints, over the frames: relMSE (mean of (t − r)² / (r² + 0.01), as bench), the same without the pixels
whose truth is 0, the energy-weighted error ΣΣ (t − r)² / ΣΣ r² (scale-free and not ruled by a dark
pixel), flicker (bench's) and its energy-weighted form, and the mean ratio Σ t / Σ r.
Reads scan-line EXRs of float channels, uncompressed or ZIP (what bounce writes); no other packages.
"""
import glob
import re
import struct
import sys
import zlib


def read_exr(path):
    """The R, G and B channels of a scan-line float EXR, as flat lists (row-major)."""
    d = open(path, 'rb').read()
    i, attrs = 8, {}
    while d[i] != 0:
        j = d.index(b'\0', i)
        k = d.index(b'\0', j + 1)
        size = int.from_bytes(d[k + 1:k + 5], 'little')
        attrs[d[i:j].decode()] = d[k + 5:k + 5 + size]
        i = k + 5 + size
    i += 1
    x0, y0, x1, y1 = struct.unpack('<4i', attrs['dataWindow'])
    w, h = x1 - x0 + 1, y1 - y0 + 1
    chl, chans, p = attrs['channels'], [], 0
    while chl[p] != 0:
        e = chl.index(b'\0', p)
        if struct.unpack('<i', chl[e + 1:e + 5])[0] != 2:
            sys.exit(f'error: {path}: only float channels are read')
        chans.append(chl[p:e].decode())
        p = e + 17
    comp = attrs['compression'][0]
    if comp not in (0, 3):
        sys.exit(f'error: {path}: compression {comp} (only none and ZIP are read)')
    lines = 16 if comp == 3 else 1
    chunks = (h + lines - 1) // lines
    img = {c: [0.0] * (w * h) for c in chans}
    for offset in struct.unpack(f'<{chunks}Q', d[i:i + 8 * chunks]):
        y, size = struct.unpack('<ii', d[offset:offset + 8])
        data = d[offset + 8:offset + 8 + size]
        n = min(lines, y1 + 1 - y)
        if comp == 3 and size < n * w * 4 * len(chans):
            t = bytearray(zlib.decompress(data))
            for k in range(1, len(t)):
                t[k] = (t[k - 1] + t[k] - 128) & 255
            half, out = (len(t) + 1) // 2, bytearray(len(t))
            out[0::2], out[1::2] = t[:half], t[half:]
            data = bytes(out)
        q = 0
        for row in range(n):
            for c in chans:
                img[c][(y - y0 + row) * w:(y - y0 + row + 1) * w] = struct.unpack(f'<{w}f', data[q:q + 4 * w])
                q += 4 * w
    return [v for c in 'RGB' for v in img[c]]


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit('usage: lab/frame-errors.py FRAMES_DIR TRUTH_DIR [MATCH]')
    frames_dir, truth_dir = sys.argv[1], sys.argv[2]
    match = sys.argv[3] if len(sys.argv) == 4 else ''
    frames = sorted(glob.glob(f'{frames_dir}/frame_*.exr'))
    if len(frames) < 2:
        sys.exit(f'error: {frames_dir}: fewer than two frames')
    rel = rel_lit = flicker = 0.0
    se = sr2 = sf = st = sr = 0.0
    prev = None
    for k, frame in enumerate(frames):
        truths = [t for t in glob.glob(f'{truth_dir}/*frame{k:04d}.exr') if match in t]
        if len(truths) != 1:
            sys.exit(f'error: {truth_dir}: {len(truths)} truths for frame {k} (give MATCH)')
        r, t = read_exr(truths[0]), read_exr(frame)
        n = len(r)
        e2 = [(a - b) ** 2 for a, b in zip(t, r)]
        rel += sum(e / (b * b + 0.01) for e, b in zip(e2, r)) / n
        rel_lit += sum(e / (b * b + 0.01) for e, b in zip(e2, r) if b != 0.0) / n
        se += sum(e2)
        sr2 += sum(b * b for b in r)
        st += sum(t)
        sr += sum(r)
        if prev:
            pt, pr = prev
            d = [(a - pa) - (b - pb) for a, pa, b, pb in zip(t, pt, r, pr)]
            flicker += sum(v * v / (b * b + 0.01) for v, b in zip(d, r)) / n
            sf += sum(v * v for v in d)
        prev = (t, r)
    m = len(frames)
    print(f'relMSE {rel / m:.6g}  without truth-0 pixels {rel_lit / m:.6g}  energy-weighted {se / sr2:.6g}  '
          f'flicker {flicker / (m - 1):.6g}  energy-weighted {sf / sr2:.6g}  mean ratio {st / sr:.5f}')


if __name__ == '__main__':
    main()

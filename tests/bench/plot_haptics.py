#!/usr/bin/env python3
"""Force and torque per axis over time from haptic loop logs (HapticLoop::writeLog CSV), as a PNG.

    python3 tests/bench/plot_haptics.py LOG.csv OUT.png "title"

Pure standard library (zlib PNG writer, a 5x7 pixel font) because matplotlib is not a
dependency. Six panels, one per axis: fx fy fz (N), tx ty tz (N m) of the wrench written to the
device, with the Figure 6.7 phase boundaries every 20 s.
"""
import csv
import struct
import sys
import zlib

FONT = {  # 5x7 glyphs, rows top to bottom, 5 bits each
    '0': [14, 17, 19, 21, 25, 17, 14], '1': [4, 12, 4, 4, 4, 4, 14], '2': [14, 17, 1, 2, 4, 8, 31],
    '3': [31, 2, 4, 2, 1, 17, 14], '4': [2, 6, 10, 18, 31, 2, 2], '5': [31, 16, 30, 1, 1, 17, 14],
    '6': [6, 8, 16, 30, 17, 17, 14], '7': [31, 1, 2, 4, 8, 8, 8], '8': [14, 17, 17, 14, 17, 17, 14],
    '9': [14, 17, 17, 15, 1, 2, 12], '-': [0, 0, 0, 31, 0, 0, 0], '.': [0, 0, 0, 0, 0, 12, 12],
    ' ': [0] * 7, '(': [2, 4, 8, 8, 8, 4, 2], ')': [8, 4, 2, 2, 2, 4, 8], '/': [1, 1, 2, 4, 8, 16, 16],
    ',': [0, 0, 0, 0, 12, 4, 8], ':': [0, 12, 12, 0, 12, 12, 0], '_': [0, 0, 0, 0, 0, 0, 31],
}
LOWER = {
    'a': [0, 0, 14, 1, 15, 17, 15], 'b': [16, 16, 22, 25, 17, 17, 30], 'c': [0, 0, 14, 16, 16, 17, 14],
    'd': [1, 1, 13, 19, 17, 17, 15], 'e': [0, 0, 14, 17, 31, 16, 14], 'f': [6, 9, 8, 28, 8, 8, 8],
    'g': [0, 15, 17, 15, 1, 17, 14], 'h': [16, 16, 22, 25, 17, 17, 17], 'i': [4, 0, 12, 4, 4, 4, 14],
    'k': [16, 16, 18, 20, 24, 20, 18], 'l': [12, 4, 4, 4, 4, 4, 14], 'm': [0, 0, 26, 21, 21, 17, 17],
    'n': [0, 0, 22, 25, 17, 17, 17], 'o': [0, 0, 14, 17, 17, 17, 14], 'p': [0, 0, 30, 17, 30, 16, 16],
    'q': [0, 0, 13, 19, 15, 1, 1], 'r': [0, 0, 22, 25, 16, 16, 16], 's': [0, 0, 14, 16, 14, 1, 30],
    't': [8, 8, 28, 8, 8, 9, 6], 'u': [0, 0, 17, 17, 17, 19, 13], 'v': [0, 0, 17, 17, 17, 10, 4],
    'w': [0, 0, 17, 17, 21, 21, 10], 'x': [0, 0, 17, 10, 4, 10, 17], 'y': [0, 0, 17, 17, 15, 1, 14],
    'z': [0, 0, 31, 2, 4, 8, 31], 'N': [17, 25, 21, 19, 17, 17, 17], 'F': [31, 16, 16, 30, 16, 16, 16],
    'T': [31, 4, 4, 4, 4, 4, 4],
}
FONT.update(LOWER)


class Canvas:
    def __init__(self, w, h):
        self.w, self.h = w, h
        self.px = bytearray([255] * (w * h * 3))

    def set(self, x, y, c):
        if 0 <= x < self.w and 0 <= y < self.h:
            i = 3 * (y * self.w + x)
            self.px[i:i + 3] = bytes(c)

    def line(self, x0, y0, x1, y1, c):
        dx, dy = abs(x1 - x0), -abs(y1 - y0)
        sx, sy = (1 if x0 < x1 else -1), (1 if y0 < y1 else -1)
        err = dx + dy
        while True:
            self.set(x0, y0, c)
            if x0 == x1 and y0 == y1:
                return
            e2 = 2 * err
            if e2 >= dy:
                err += dy
                x0 += sx
            if e2 <= dx:
                err += dx
                y0 += sy

    def text(self, x, y, s, c=(0, 0, 0)):
        for ch in s:
            for r, bits in enumerate(FONT.get(ch, FONT[' '])):
                for b in range(5):
                    if bits & (16 >> b):
                        self.set(x + b, y + r, c)
            x += 6

    def png(self, path):
        raw = b''.join(b'\x00' + bytes(self.px[3 * y * self.w:3 * (y + 1) * self.w])
                       for y in range(self.h))

        def chunk(kind, data):
            return struct.pack('>I', len(data)) + kind + data + struct.pack(
                '>I', zlib.crc32(kind + data) & 0xffffffff)
        with open(path, 'wb') as f:
            f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', self.w, self.h, 8, 2, 0, 0, 0))
                    + chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b''))


def fmt(v):
    return ('%.3g' % v).replace('e+0', 'e').replace('e-0', 'e-')


def main():
    log, out, title = sys.argv[1], sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else ''
    with open(log) as f:
        rows = list(csv.DictReader(f))
    t0 = float(rows[0]['time'])
    t = [float(r['time']) - t0 for r in rows]
    keys = [('fx', 'fx (N)'), ('fy', 'fy (N)'), ('fz', 'fz (N)'),
            ('tx', 'tx (N m)'), ('ty', 'ty (N m)'), ('tz', 'tz (N m)')]
    W, panel_h, left, top = 900, 110, 80, 24
    c = Canvas(W, top + 6 * panel_h + 30)
    c.text(left, 6, title)
    tmax = max(t[-1], 1e-9)
    colours = [(200, 30, 30), (30, 140, 30), (30, 60, 200)] * 2
    for p, (key, label) in enumerate(keys):
        y0 = top + p * panel_h
        h = panel_h - 16
        v = [float(r[key]) for r in rows]
        lo, hi = min(v + [0.0]), max(v + [0.0])
        if hi - lo < 1e-12:
            hi, lo = hi + 1, lo - 1
        ys = lambda val: y0 + int((hi - val) / (hi - lo) * (h - 1))
        xs = lambda tt: left + int(tt / tmax * (W - left - 20))
        c.line(left, y0, left, y0 + h, (0, 0, 0))
        c.line(left, ys(0.0), W - 20, ys(0.0), (160, 160, 160))
        for phase in range(0, int(tmax) + 1, 20):
            for yy in range(y0, y0 + h, 3):
                c.set(xs(phase), yy, (190, 190, 190))
        c.text(4, y0 + h // 2 - 3, label)
        c.text(left - 6 * len(fmt(hi)) - 3, y0, fmt(hi))
        c.text(left - 6 * len(fmt(lo)) - 3, y0 + h - 7, fmt(lo))
        step = max(1, len(t) // (4 * (W - left)))
        prev = None
        for k in range(0, len(t), step):
            pt = (xs(t[k]), ys(v[k]))
            if prev:
                c.line(prev[0], prev[1], pt[0], pt[1], colours[p])
            prev = pt
    yb = top + 6 * panel_h
    for phase in range(0, int(tmax) + 1, 20):
        c.text(xs(phase) - 6, yb, str(phase))
    c.text(W // 2 - 30, yb + 12, 'time (s)')
    c.png(out)


if __name__ == '__main__':
    main()

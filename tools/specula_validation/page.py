"""Pages: PNG pictures (pure-Python writer), tone mapping, false-colour error maps with a colour bar (viridis, 3x5
digit font), Markdown tables and the generated blocks of docs/validation/*.md."""
import math
import struct
import zlib


VIRIDIS = [(68, 1, 84), (71, 44, 122), (59, 81, 139), (44, 113, 142), (33, 144, 141), (39, 173, 129), (92, 200, 99),
           (170, 220, 50), (253, 231, 37)]
FONT = {"0": "111101101101111", "1": "010110010010111", "2": "111001111100111", "3": "111001111001111",
        "4": "101101111001001", "5": "111100111001111", "6": "111100111101111", "7": "111001001001001",
        "8": "111101111101111", "9": "111101111001111", ".": "000000000000010", "e": "000111111100111",
        "-": "000000111000000", "+": "000010111010000", " ": "000000000000000"}


def viridis(t):
    t = min(max(t, 0.0), 1.0) * (len(VIRIDIS) - 1)
    i = min(int(t), len(VIRIDIS) - 2)
    f = t - i
    a, b = VIRIDIS[i], VIRIDIS[i + 1]
    return tuple(int(round(a[k] + (b[k] - a[k]) * f)) for k in range(3))


def srgb8(x):
    x = min(max(x, 0.0), 1.0)
    y = 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055
    return int(round(255 * y))


class Canvas:
    def __init__(self, w, h, bg=(24, 24, 24)):
        self.w, self.h = w, h
        self.px = [list(bg) for _ in range(w * h)]

    def put(self, x, y, c):
        if 0 <= x < self.w and 0 <= y < self.h:
            self.px[y * self.w + x] = list(c)

    def blit(self, rgb, w, h, x0, y0, scale):
        for y in range(h * scale):
            for x in range(w * scale):
                self.put(x0 + x, y0 + y, rgb[(y // scale) * w + x // scale])

    def text(self, s, x0, y0, scale=2, color=(230, 230, 230)):
        x = x0
        for ch in s:
            g = FONT.get(ch, FONT[" "])
            for j in range(5):
                for i in range(3):
                    if g[j * 3 + i] == "1":
                        for a in range(scale):
                            for b in range(scale):
                                self.put(x + i * scale + a, y0 + j * scale + b, color)
            x += 4 * scale

    def save(self, path):
        return write_png(path, self.w, self.h, [bytes(v for p in self.px[y * self.w:(y + 1) * self.w] for v in p)
                                                for y in range(self.h)])


def tonemap(img, exposure):
    """Specular AOV -> sRGB 8-bit with exposure and Reinhard x/(1+x) per channel."""
    n = len(img[0])
    return [tuple(srgb8((v := img[c][i] * exposure) / (1 + v)) for c in range(3)) for i in range(n)]


def percentile(vals, q):
    s = sorted(vals)
    return s[min(len(s) - 1, int(q * (len(s) - 1)))] if s else 0.0


def errmap(test, ref, scale):
    n = len(ref[0])
    return [viridis((sum(abs(test[c][i] - ref[c][i]) for c in range(3)) / 3) / scale) for i in range(n)]


def fmt_num(x):
    return f"{x:.3g}" if x >= 0.001 else f"{x:.1e}"


def colorbar(cv, x0, y0, w, h, scale):
    for x in range(w):
        c = viridis(x / (w - 1))
        for y in range(h):
            cv.put(x0 + x, y0 + y, c)
    cv.text("0", x0, y0 + h + 3)
    s = fmt_num(scale)
    cv.text(s, x0 + w - 8 * len(s), y0 + h + 3)


def write_png(path, w, h, rows):
    """Writes 8-bit RGB rows (bytes of 3*w each, top row first) as a PNG."""
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + r for r in rows)
    data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(data)
    return len(data)


def table(header, rows):
    """A Markdown table (list of lines) from a header list and rows of cells."""
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)] + \
        ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]


def with_command_log(lines, log, intro="Commands run for this page:\n"):
    """A page's text: its lines, then the commands that made it (intro, then the log in a code block)."""
    return "\n".join(list(lines) + [intro, "```"] + list(log) + ["```"]) + "\n"


def replace_block(text, begin, end, body):
    """Replaces what lies between the marker lines 'begin' and 'end' (kept) of a page with 'body'."""
    if begin not in text or end not in text:
        raise SystemExit(f"page markers {begin!r} / {end!r} are missing")
    a, b = text.index(begin) + len(begin), text.index(end)
    return text[:a] + "\n" + body.rstrip() + "\n" + text[b:]


def temporal_std_map(tests, refs):
    """Per pixel, the standard deviation over t of test_t - ref_t, mean over the channels (the picture of the
    flicker that `specula compare --frames` reports as one number). tests, refs: lists of [channel][pixel]."""
    K, C, n = len(tests), len(tests[0]), len(tests[0][0])
    out = [0.0] * n
    for i in range(n):
        s = 0.0
        for c in range(C):
            es = [tests[t][c][i] - refs[t][c][i] for t in range(K)]
            mu = sum(es) / K
            s += math.sqrt(sum((e - mu) ** 2 for e in es) / K)
        out[i] = s / C
    return out

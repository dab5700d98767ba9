#!/usr/bin/env python3
"""Writes the showcase environment maps (examples/showcase/*.hdr): equirectangular, z-up, Blender's column convention
(docs/scene-format.md, environment). Deterministic and procedural, so the repository ships no third-party HDRIs:
  studio.hdr  a dark photo studio: a large overhead softbox, two vertical strip boxes, a warm kicker, a floor bounce.
  sky.hdr     a clear winter sky for a low sun (the sun itself is a directional light in the scenes): zenith blue,
              bright hazy horizon, a warm glow around the sun's azimuth, a grey-white snow ground below the horizon.
Usage: python3 tools/make_showcase_env.py [--out examples/showcase]"""
import argparse
import math
import os
import struct

W, H = 512, 256


def direction(i, j):
    """Pixel centre (i, j) -> unit direction. Row 0 looks along +z; u = 1/2 - atan2(y, -x)/(2 pi)."""
    u, v = (i + 0.5) / W, (j + 0.5) / H
    theta = v * math.pi  # from +z
    phi = (0.5 - u) * 2.0 * math.pi  # atan2(y, -x)
    s = math.sin(theta)
    return (-s * math.cos(phi), s * math.sin(phi), math.cos(theta))


def smooth_box(d, centre, half_w, half_h, soft):
    """A rectangular softbox seen from the origin: centre direction, half extents as angles (radians)."""
    cx, cy, cz = centre
    dot = d[0] * cx + d[1] * cy + d[2] * cz
    if dot <= 0.0:
        return 0.0
    # Tangent frame of the box: 'right' horizontal (or along x for a box overhead), 'up' completes it.
    ref = (0.0, 0.0, 1.0) if abs(cz) < 0.9 else (1.0, 0.0, 0.0)
    rx, ry, rz = normalise((ref[1] * cz - ref[2] * cy, ref[2] * cx - ref[0] * cz, ref[0] * cy - ref[1] * cx))
    ux, uy, uz = cy * rz - cz * ry, cz * rx - cx * rz, cx * ry - cy * rx
    a = math.atan2(d[0] * rx + d[1] * ry + d[2] * rz, dot)
    b = math.atan2(d[0] * ux + d[1] * uy + d[2] * uz, dot)

    def edge(x, h):
        return min(1.0, max(0.0, (h - abs(x)) / soft + 0.5))

    return edge(a, half_w) * edge(b, half_h)


def normalise(v):
    n = math.sqrt(sum(c * c for c in v))
    return tuple(c / n for c in v)


def studio(d):
    z = d[2]
    base = 0.015 + 0.03 * max(z, 0.0)  # dark walls, slightly brighter ceiling
    if z < 0.0:
        base = 0.02 + 0.02 * (1.0 + z)  # floor bounce, brightest near the horizon
    r = g = b = base
    top = smooth_box(d, normalise((0.0, 0.0, 1.0)), 0.35, 0.25, 0.06)
    left = smooth_box(d, normalise((-1.0, 0.35, 0.25)), 0.09, 0.5, 0.03)
    right = smooth_box(d, normalise((1.0, 0.5, 0.15)), 0.09, 0.5, 0.03)
    kick = smooth_box(d, normalise((0.3, 1.0, 0.35)), 0.25, 0.12, 0.05)
    r += 6.0 * top + 9.0 * left + 7.0 * right + 5.0 * kick
    g += 6.0 * top + 9.0 * left + 7.5 * right + 3.6 * kick
    b += 6.2 * top + 9.5 * left + 8.5 * right + 2.2 * kick
    return r, g, b


def sky(d, sun_azimuth=math.radians(111.0)):
    z = d[2]
    if z < 0.0:  # snow-covered ground, lit by the sky
        k = 0.55 + 0.15 * math.exp(8.0 * z)
        return 0.55 * k, 0.58 * k, 0.65 * k
    horizon = math.exp(-6.0 * z)
    zen = (0.12, 0.25, 0.62)
    haze = (0.75, 0.82, 0.95)
    r, g, b = (zen[c] * (1.0 - horizon) + haze[c] * horizon for c in range(3))
    sd = (math.cos(sun_azimuth) * 0.97, math.sin(sun_azimuth) * 0.97, 0.24)
    cosg = max(0.0, d[0] * sd[0] + d[1] * sd[1] + d[2] * sd[2])
    glow = 1.2 * cosg ** 24 + 0.3 * cosg ** 4
    return r + glow * 1.0, g + glow * 0.75, b + glow * 0.45


def rgbe(r, g, b):
    m = max(r, g, b)
    if m < 1e-32:
        return b"\0\0\0\0"
    mant, e = math.frexp(m)
    s = mant * 256.0 / m
    return bytes((min(255, int(r * s)), min(255, int(g * s)), min(255, int(b * s)), e + 128))


def write_hdr(path, fn):
    rows = []
    for j in range(H):
        rows.append(b"".join(rgbe(*fn(direction(i, j))) for i in range(W)))
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
        f.write(("-Y %d +X %d\n" % (H, W)).encode())
        for row in rows:  # flat (uncompressed) scanlines
            f.write(row)
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "examples", "showcase"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    write_hdr(os.path.join(a.out, "studio.hdr"), studio)
    write_hdr(os.path.join(a.out, "sky.hdr"), sky)
    print("wrote studio.hdr and sky.hdr to", os.path.abspath(a.out))


if __name__ == "__main__":
    main()

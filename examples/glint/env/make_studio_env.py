#!/usr/bin/env python3
"""Writes studio_env.hdr: a procedural equirectangular (z-up, Blender column convention) studio environment for the
glint environment-lighting scene (examples/glint/env_sphere.json): a dim sky gradient, a grey floor, three large soft
boxes and a small warm key. Broad, bright regions are what a glinty surface reflects in many narrow lobes, the case
where sampling the limiting Beckmann lobe finds the sparkles by chance (issue 11 item 3).
Pure Python (no numpy): flat RGBE scanlines. Convert with `oiiotool studio_env.hdr -d half -o studio_env.exr`."""
import math, struct, sys

W, H = 256, 128

def direction(px, py):
    u, v = (px + 0.5) / W, (py + 0.5) / H
    theta = v * math.pi                       # 0 = +z (top row)
    phi = (0.5 - u) * 2 * math.pi             # u = 1/2 - atan2(y, -x) / (2 pi)  =>  atan2(y, -x) = phi
    s = math.sin(theta)
    return (-s * math.cos(phi), s * math.sin(phi), math.cos(theta))

def box(d, centre_az, centre_el, half_az, half_el):
    az = math.degrees(math.atan2(d[1], d[0]))
    el = math.degrees(math.asin(max(-1.0, min(1.0, d[2]))))
    da = (az - centre_az + 180) % 360 - 180
    # soft edges (2 degrees) so the map has no aliasing at 256 x 128
    ea = max(0.0, min(1.0, (half_az - abs(da)) / 2 + 0.5))
    ee = max(0.0, min(1.0, (half_el - abs(el - centre_el)) / 2 + 0.5))
    return ea * ee

def radiance(d):
    z = d[2]
    if z > 0:
        r, g, b = 0.10 + 0.10 * z, 0.12 + 0.12 * z, 0.16 + 0.20 * z
    else:
        r = g = b = 0.06
    for az, el, ha, he, L in ((-60, 35, 25, 18, (5.0, 5.0, 4.8)), (70, 25, 20, 14, (3.0, 3.2, 3.6)),
                              (175, 55, 30, 12, (2.0, 2.0, 2.0))):
        w = box(d, az, el, ha, he)
        r, g, b = r + w * L[0], g + w * L[1], b + w * L[2]
    w = box(d, 20, 12, 4, 4)  # warm key
    r, g, b = r + w * 30.0, g + w * 26.0, b + w * 20.0
    return r, g, b

def rgbe(c):
    m = max(c)
    if m < 1e-32:
        return b"\0\0\0\0"
    e = math.frexp(m)[1]
    s = 256.0 / 2.0 ** e
    return bytes([min(255, int(c[0] * s)), min(255, int(c[1] * s)), min(255, int(c[2] * s)), e + 128])

out = sys.argv[1] if len(sys.argv) > 1 else "studio_env.hdr"
with open(out, "wb") as f:
    f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (H, W))
    for py in range(H):
        f.write(b"".join(rgbe(radiance(direction(px, py))) for px in range(W)))

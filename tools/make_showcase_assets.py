#!/usr/bin/env python3
"""Writes the showcase assets of examples/showcase/: environment maps (*.hdr: equirectangular, z-up, Blender's column
convention, docs/scene-format.md) and a mesh. Deterministic and procedural, so the repository ships no third-party
HDRIs or models:
  studio.hdr  a dark photo studio: a large overhead softbox, two vertical strip boxes, a warm kicker, a floor bounce.
  sky.hdr     a clear winter sky for a low sun (the sun itself is a directional light in the scenes): zenith blue,
              bright hazy horizon, a warm glow around the sun's azimuth, a grey-white snow ground below the horizon.
  body.obj    a smooth car-body-like superellipsoid (2.4 x 1.2 x 0.7, flat-ish top and sides, rounded edges) with
              analytic normals and (u, v) = (azimuth, polar) parameters, for the car-paint showcase.
  kettle.obj  a kettle-like surface of revolution (a bulbous body, shoulder, lid and knob; 1.6 wide, 1.3 high) with
              analytic normals, u = azimuth / 2 pi and v = arc length along the profile / (2 pi x mean radius), so a
              texel is about square everywhere, for the brushed-metal P-NDF showcase.
Usage: python3 tools/make_showcase_assets.py [--out examples/showcase]"""

import argparse
import math
import os


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


def sky(d, sun_azimuth=math.radians(105.0)):
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


def write_grid_obj(path, name, verts, norms, uvs, nu, nv, digits):
    """An OBJ of a (nu + 1) x (nv + 1) vertex grid (rows of constant v) as quads, written atomically."""
    fmt = "%%.%df" % digits
    lines = ["# Specula showcase %s (tools/make_showcase_assets.py)" % name]
    lines += ["v " + " ".join(fmt % c for c in p) for p in verts]
    lines += ["vn %.4f %.4f %.4f" % p for p in norms]
    lines += ["vt " + " ".join(fmt % c for c in p) for p in uvs]
    w = nu + 1
    for j in range(nv):
        for i in range(nu):
            q = [j * w + i + 1, j * w + i + 2, (j + 1) * w + i + 2, (j + 1) * w + i + 1]
            lines.append("f " + " ".join("%d/%d/%d" % (k, k, k) for k in q))
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, path)


def write_body(path, nu=96, nv=48, size=(1.2, 0.6, 0.35), e_long=0.45, e_lat=0.6):
    """Superellipsoid x = a c(v)^e1 c(u)^e2 ...: signed powers of cos/sin. Normals from the implicit function's gradient
    F = ((x/a)^(2/e2) + (y/b)^(2/e2))^(e2/e1) + (z/c)^(2/e1)."""
    a, b, c = size

    def spow(x, e):
        return math.copysign(abs(x) ** e, x)

    verts, norms, uvs = [], [], []
    for j in range(nv + 1):
        v = j / nv
        th = -0.5 * math.pi + v * math.pi
        for i in range(nu + 1):
            u = i / nu
            ph = -math.pi + u * 2.0 * math.pi
            x = a * spow(math.cos(th), e_lat) * spow(math.cos(ph), e_long)
            y = b * spow(math.cos(th), e_lat) * spow(math.sin(ph), e_long)
            z = c * spow(math.sin(th), e_lat)
            # gradient of F (up to a positive factor per point)
            gx = spow(x / a, 2.0 / e_long - 1.0) / a
            gy = spow(y / b, 2.0 / e_long - 1.0) / b
            r = (abs(x / a) ** (2.0 / e_long) + abs(y / b) ** (2.0 / e_long))
            k = (r ** (e_long / e_lat - 1.0)) if r > 0 else 0.0
            gx, gy = gx * k, gy * k
            gz = spow(z / c, 2.0 / e_lat - 1.0) / c
            n = math.sqrt(gx * gx + gy * gy + gz * gz)
            if n < 1e-12:
                gx, gy, gz, n = 0.0, 0.0, math.copysign(1.0, z if z else th), 1.0
            verts.append((x, y, z + c))
            norms.append((gx / n, gy / n, gz / n))
            uvs.append((u, v))
    write_grid_obj(path, "body", verts, norms, uvs, nu, nv, digits=5)


def catmull_rom(points, t):
    """Centripetal-free (uniform) Catmull-Rom through 'points' at t in [0, 1], with its derivative in t."""
    n = len(points) - 1
    x = min(max(t, 0.0), 1.0) * n
    i = min(int(x), n - 1)
    f = x - i
    p0, p1, p2, p3 = (points[max(i - 1, 0)], points[i], points[i + 1], points[min(i + 2, n)])
    out, der = [], []
    for k in range(2):
        a, b, c, d = p0[k], p1[k], p2[k], p3[k]
        out.append(0.5 * (2 * b + (-a + c) * f + (2 * a - 5 * b + 4 * c - d) * f * f + (-a + 3 * b - 3 * c + d) * f ** 3))
        der.append(0.5 * ((-a + c) + 2 * (2 * a - 5 * b + 4 * c - d) * f + 3 * (-a + 3 * b - 3 * c + d) * f * f) * n)
    return out, der


# (radius, height) from the centre of the base up to the tip of the knob.
KETTLE_PROFILE = [(0.0, 0.0), (0.45, 0.0), (0.66, 0.05), (0.78, 0.22), (0.8, 0.42), (0.74, 0.64), (0.58, 0.82),
                  (0.42, 0.93), (0.36, 0.98), (0.3, 1.04), (0.2, 1.08), (0.09, 1.1), (0.07, 1.18), (0.1, 1.26),
                  (0.06, 1.3), (0.0, 1.31)]


def write_kettle(path, nu=96, nv=72):
    """Lathe of KETTLE_PROFILE about z; normals from the profile tangent (dr, dz): n = (dz cos, dz sin, -dr)/|.|."""
    samples = [catmull_rom(KETTLE_PROFILE, j / nv) for j in range(nv + 1)]
    arc = [0.0]
    for j in range(1, nv + 1):
        (r0, z0), (r1, z1) = samples[j - 1][0], samples[j][0]
        arc.append(arc[-1] + math.hypot(r1 - r0, z1 - z0))
    mean_r = sum(s[0][0] for s in samples) / len(samples)
    verts, norms, uvs = [], [], []
    for j, ((r, z), (dr, dz)) in enumerate(samples):
        ln = math.hypot(dr, dz) or 1.0
        nr, nz = dz / ln, -dr / ln
        if r < 1e-6:  # the poles: the axis
            nr, nz = 0.0, (-1.0 if j == 0 else 1.0)
        for i in range(nu + 1):
            u = i / nu
            ph = u * 2.0 * math.pi
            c, s = math.cos(ph), math.sin(ph)
            verts.append((max(r, 0.0) * c, max(r, 0.0) * s, z))
            norms.append((nr * c, nr * s, nz))
            uvs.append((u, arc[j] / (2.0 * math.pi * mean_r)))
    write_grid_obj(path, "kettle", verts, norms, uvs, nu, nv, digits=4)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "..", "examples", "showcase"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    write_hdr(os.path.join(a.out, "studio.hdr"), studio)
    write_hdr(os.path.join(a.out, "sky.hdr"), sky)
    write_body(os.path.join(a.out, "body.obj"))
    write_kettle(os.path.join(a.out, "kettle.obj"))
    print("wrote studio.hdr, sky.hdr, body.obj and kettle.obj to", os.path.abspath(a.out))


if __name__ == "__main__":
    main()

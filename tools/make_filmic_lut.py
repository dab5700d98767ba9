#!/usr/bin/env python3
# Generates data/ocio/luts/filmic_tonescale.spi1d (the "Filmic" view's tone curve) and prints the
# RGB matrices used in data/ocio/config.ocio. Python standard library only; output is deterministic.
"""Filmic view of Specula's OCIO config.

Scene-linear Rec.709 goes through an AllocationTransform lg2 shaper covering 16.5 stops around
middle grey (0.18 * 2^-10 .. 0.18 * 2^6.5), then this 1D LUT.  The LUT maps the shaper's [0, 1]
back to scene-linear x and applies a smooth S-shaped tonescale (in log-exposure terms) with a
soft highlight shoulder:

    y(x) = (x / (x + s0)) ** p            (Michaelis-Menten / Naka-Rushton style, p > 1 gives a toe)

with p = 1.4 and s0 chosen so that middle grey 0.18 maps to 0.18 display-linear (so "Standard"
and "Filmic" agree at middle grey).  The result is shifted so that the darkest sample is exactly
0, and stays below 1 at the top of the range (0.18 * 2^6.5 = 16.3 maps to ~0.963 display-linear,
~0.983 sRGB code).  Its output is display-linear Rec.709; the "sRGB - Display" colorspace applies
the sRGB encoding.  Channels are processed independently, which also desaturates highlights.

Usage:  python3 tools/make_filmic_lut.py [--out data/ocio/luts/filmic_tonescale.spi1d] [--matrices]
"""

import argparse
import math
import os
import sys

MIDDLE_GREY = 0.18
STOPS_BELOW = 10.0
STOPS_ABOVE = 6.5
LOG2_MIN = math.log2(MIDDLE_GREY) - STOPS_BELOW  # -12.473931188...
LOG2_MAX = math.log2(MIDDLE_GREY) + STOPS_ABOVE  # 4.026068811...
POWER = 1.4
LUT_SIZE = 4096

# s0 such that (0.18 / (0.18 + s0)) ** POWER == 0.18
S0 = MIDDLE_GREY / (MIDDLE_GREY ** (1.0 / POWER)) - MIDDLE_GREY


def tonescale(x):
    return (x / (x + S0)) ** POWER


def lut_values(n=LUT_SIZE):
    y_min = tonescale(2.0 ** LOG2_MIN)
    values = []
    for i in range(n):
        t = i / (n - 1)
        x = 2.0 ** (LOG2_MIN + t * (LOG2_MAX - LOG2_MIN))
        y = (tonescale(x) - y_min) / (1.0 - y_min)
        values.append(max(0.0, y))
    return values


def write_spi1d(path, values):
    lines = ["Version 1", "From 0.0 1.0", "Length %d" % len(values), "Components 1", "{"]
    lines += ["    %.9f" % v for v in values]
    lines.append("}")
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = path + ".tmp"
    with open(tmp, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, path)


# ---- matrices (printed for the config; 3x3 row-major, applied to column vectors) ----------------

def xy_to_xyz(x, y):
    return [x / y, 1.0, (1.0 - x - y) / y]


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def mat_vec(m, v):
    return [sum(m[i][k] * v[k] for k in range(3)) for i in range(3)]


def mat_inv(m):
    a, b, c = m[0]
    d, e, f = m[1]
    g, h, i = m[2]
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return [[(e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det],
            [(f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det],
            [(d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det]]


def rgb_to_xyz(primaries, white):
    cols = [xy_to_xyz(*p) for p in primaries]
    m = [[cols[j][i] for j in range(3)] for i in range(3)]
    s = mat_vec(mat_inv(m), xy_to_xyz(*white))
    return [[m[i][j] * s[j] for j in range(3)] for i in range(3)]


BRADFORD = [[0.8951, 0.2664, -0.1614], [-0.7502, 1.7135, 0.0367], [0.0389, -0.0685, 1.0296]]


def bradford(src_white, dst_white):
    s = mat_vec(BRADFORD, xy_to_xyz(*src_white))
    d = mat_vec(BRADFORD, xy_to_xyz(*dst_white))
    scale = [[d[0] / s[0], 0, 0], [0, d[1] / s[1], 0], [0, 0, d[2] / s[2]]]
    return mat_mul(mat_inv(BRADFORD), mat_mul(scale, BRADFORD))


D65 = (0.3127, 0.3290)
ACES_WHITE = (0.32168, 0.33767)
REC709 = [(0.640, 0.330), (0.300, 0.600), (0.150, 0.060)]
AP1 = [(0.713, 0.293), (0.165, 0.830), (0.128, 0.044)]
P3 = [(0.680, 0.320), (0.265, 0.690), (0.150, 0.060)]
AP0 = [(0.7347, 0.2653), (0.0, 1.0), (0.0001, -0.0770)]


def to_rec709(primaries, white):
    m = rgb_to_xyz(primaries, white)
    if white != D65:
        m = mat_mul(bradford(white, D65), m)
    return mat_mul(mat_inv(rgb_to_xyz(REC709, D65)), m)


def ocio_matrix(m):
    flat = [m[0][0], m[0][1], m[0][2], 0, m[1][0], m[1][1], m[1][2], 0, m[2][0], m[2][1], m[2][2], 0, 0, 0, 0, 1]
    return "[" + ", ".join(("%.12g" % (0.0 if abs(v) < 1e-12 else v)) for v in flat) + "]"


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    default_out = os.path.join(here, "..", "data", "ocio", "luts", "filmic_tonescale.spi1d")
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=default_out)
    ap.add_argument("--matrices", action="store_true", help="print the colorspace matrices for config.ocio")
    args = ap.parse_args(argv)
    values = lut_values()
    write_spi1d(args.out, values)
    print("wrote %s (%d entries); allocation lg2 vars: [%.9f, %.9f]; s0 = %.9f, p = %.2f"
          % (os.path.normpath(args.out), len(values), LOG2_MIN, LOG2_MAX, S0, POWER))
    if args.matrices:
        print("ACEScg -> lin_rec709:", ocio_matrix(to_rec709(AP1, ACES_WHITE)))
        print("P3-D65 -> lin_rec709:", ocio_matrix(to_rec709(P3, D65)))
        print("ACES2065-1 -> lin_rec709:", ocio_matrix(to_rec709(AP0, ACES_WHITE)))
        print("lin_rec709 -> CIE XYZ (D65):", ocio_matrix(rgb_to_xyz(REC709, D65)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

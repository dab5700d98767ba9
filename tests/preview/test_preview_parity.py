#!/usr/bin/env python3
"""Image parity of the GPU preview (issue 14 item 4): every example and showcase scene rendered by `specula preview`
(OpenGL through headless EGL: Mesa llvmpipe in CI) and by the CPU's `--integrator raster` (the same light transport,
pixel centres, 2x2-quad derivatives with helper-pixel extrapolation, the tessellation's attributes), 192x108.
Per AOV (beauty, diffuse, specular, normal): mean |GPU - CPU| <= 1 % of the mean |CPU|, and the 99th percentile of the
per-pixel relative error |GPU - CPU| / (|CPU| + 1 % of the mean) <= 5 % (channel sums).

  test_preview_parity.py SPECULA_BIN SOURCE_DIR OUT_DIR

Scenes listed in KNOWN_GAPS are measured and printed but not asserted (docs/preview.md says why); every other scene
must pass, and a known gap that starts to pass is reported so that the list shrinks."""
import glob
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from parity_metrics import channels, parity  # noqa: E402

# Scenes whose preview does not yet match per pixel (docs/preview.md "Parity"), measured 2026-12-03.
KNOWN_GAPS = {
    # glint/tubes: normal AOV 2.4 %: 122 of 20736 pixels at the tori's silhouettes where the rasteriser and Embree see
    # different tubes (beauty and specular 0.05 %).
    "glint/tubes",
    # cornell: normal AOV 1.07 % on an Intel AVX-512 machine (0.98 % on an AMD AVX2 one): 59 pixels on the room's
    # corner edges where the rasteriser and Embree pick different walls at a shared edge (machine-dependent ties).
    "cornell",
}
CHANNELS = {"beauty": ["R", "G", "B"], "diffuse": ["diffuse.R", "diffuse.G", "diffuse.B"],
            "specular": ["specular.R", "specular.G", "specular.B"], "normal": ["normal.X", "normal.Y", "normal.Z"]}


def metrics(cpu_path, gpu_path):
    return {aov: parity(channels(cpu_path, chans), channels(gpu_path, chans)) for aov, chans in CHANNELS.items()}


def main():
    binary, root, out_dir = sys.argv[1], sys.argv[2], sys.argv[3]
    os.makedirs(out_dir, exist_ok=True)
    scenes = sorted(glob.glob(os.path.join(root, "examples", "*.json")) +
                    glob.glob(os.path.join(root, "examples", "*", "*.json")))
    failures, newly_passing, rows = [], [], []
    for path in scenes:
        name = os.path.relpath(path, os.path.join(root, "examples"))[:-5]
        stem = os.path.join(out_dir, name.replace("/", "_"))
        cpu = subprocess.run([binary, "render", path, "--integrator", "raster", "--resolution", "192x108", "-o",
                              stem + ".cpu.exr", "--progress", "none"], capture_output=True, text=True)
        gpu = subprocess.run([binary, "preview", path, "--resolution", "192x108", "-o", stem + ".gpu.exr"],
                             capture_output=True, text=True)
        if cpu.returncode or gpu.returncode:
            failures.append("%s: cpu exit %d, gpu exit %d: %s" % (name, cpu.returncode, gpu.returncode,
                                                                 (cpu.stderr + gpu.stderr).strip()[-300:]))
            continue
        m = metrics(stem + ".cpu.exr", stem + ".gpu.exr")
        ok = all(mad <= 0.01 and p99 <= 0.05 for mad, p99 in m.values())
        tag = "pass" if ok else ("gap " if name in KNOWN_GAPS else "FAIL")
        rows.append("%-34s %s  " % (name, tag) + "  ".join("%s %.4f/%.4f" % (k, *v) for k, v in m.items()))
        if not ok and name not in KNOWN_GAPS:
            failures.append(name)
        if ok and name in KNOWN_GAPS:
            newly_passing.append(name)
    print("scene                              result  per AOV: mean|diff|/mean / p99 relative error")
    print("\n".join(rows))
    passed = sum(1 for r in rows if " pass " in r)
    print("%d of %d scenes within 1 %% / 5 %% on every AOV; %d known gaps" % (passed, len(scenes),
                                                                         sum(1 for r in rows if " gap " in r)))
    if newly_passing:
        print("now passing (remove from KNOWN_GAPS): " + ", ".join(newly_passing))
    if failures:
        print("FAILED: " + "; ".join(failures))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""The engine example examples/glsl-host (issue 14 item 3, docs/glsl.md): cook scene.json's material with
`specula glsl --resources`, draw it with glsl_host_example (the host's own camera, sphere, lights and light loop; the
uniform block and textures bound from the manifest alone), and compare its image with `specula render --integrator
raster` of scene.json, the CPU twin of the rasteriser.

Asserted on the beauty (channel sums, as tests/preview/test_preview_parity.py): mean |host - CPU| <= 1 % of the
mean |CPU|, and the 99th percentile of |host - CPU| / (|CPU| + 1 % of the mean) <= 5 % (the preview's parity
criterion). Also: the manifest lists an image file and a built-in table, the picture is not black, and changing one
uniform-block member by name (--set) changes the picture, so the block really is what the shader reads.

  test_glsl_host.py SPECULA_BIN HOST_BIN EXAMPLE_DIR OUT_DIR"""
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from parity_metrics import channels, exit_status, parity  # noqa: E402

RGB = ("R", "G", "B")


def run(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True)
    sys.stdout.write(r.stdout)
    if r.returncode:
        raise SystemExit("FAILED (exit %d): %s\n%s" % (r.returncode, " ".join(cmd), r.stderr.strip()[-2000:]))
    return r


def main():
    specula, host, example, out = sys.argv[1:5]
    cooked = os.path.join(out, "cooked")
    os.makedirs(cooked, exist_ok=True)
    scene = os.path.join(example, "scene.json")
    size = "256x192"
    failures = []

    # The asset pipeline: the module and its resources (EXR per level) plus manifest.json.
    run([specula, "glsl", scene, "-o", os.path.join(cooked, "module.glsl"), "--resources", cooked])
    manifest = json.load(open(os.path.join(cooked, "manifest.json")))
    kinds = sorted({r["kind"] for r in manifest["resources"]})
    members = len(manifest["uniform_block"]["members"])
    print("manifest: %d uniform members, resources %s" % (members, kinds))
    if "image_file" not in kinds or "builtin_table" not in kinds or members == 0:
        failures.append("the example's material should list an image file, a built-in table and uniforms")

    run([host, os.path.join(cooked, "module.glsl"), os.path.join(cooked, "manifest.json"), "--size", size,
         "-o", os.path.join(out, "host.exr")])
    run([specula, "render", scene, "--integrator", "raster", "--resolution", size, "--progress", "none",
         "-o", os.path.join(out, "cpu.exr")])
    cpu, gpu = channels(os.path.join(out, "cpu.exr"), RGB), channels(os.path.join(out, "host.exr"), RGB)
    mad, p99 = parity(cpu, gpu)
    print("host vs specula render --integrator raster: mean|diff|/mean %.5f (<= 0.01), p99 relative %.5f (<= 0.05); "
          "mean beauty %.4f" % (mad, p99, cpu.mean()))
    if not (mad <= 0.01 and p99 <= 0.05):
        failures.append("parity: %.5f / %.5f" % (mad, p99))
    if not gpu.mean() > 0.02:
        failures.append("the host image is black (mean %.5f)" % gpu.mean())

    # A member set by name must reach the shader: a green base instead of the red one.
    run([host, os.path.join(cooked, "module.glsl"), os.path.join(cooked, "manifest.json"), "--size", size,
         "--set", "u_base_color=0.1,0.5,0.1", "-o", os.path.join(out, "host_green.exr")])
    green = channels(os.path.join(out, "host_green.exr"), RGB)
    changed, _ = parity(gpu, green)
    print("--set u_base_color=0.1,0.5,0.1: mean|diff|/mean %.3f (>= 0.2), green/red mean %.2f (> 1)"
          % (changed, green[:, :, 1].mean() / green[:, :, 0].mean()))
    if not (changed >= 0.2 and green[:, :, 1].mean() > green[:, :, 0].mean()):
        failures.append("--set did not change the base colour")

    return exit_status(failures)


if __name__ == "__main__":
    sys.exit(main())

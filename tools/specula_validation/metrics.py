"""Image metrics, all computed by `specula compare --json` (plugin/cli/validation_metrics.cpp): the pages and the
CI checks never re-implement them.

Masks are `FILE:LAYER` strings (pixels where any channel of LAYER is > 0; several = union), or "all".
"""
import json
import subprocess


def _run(cmd):
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError(f"specula compare failed ({out.returncode}): {' '.join(cmd)}\n{out.stderr}")
    return json.loads(out.stdout)


def compare(specula, test, ref, aov="specular", masks=("all",), top_rows=None, diff_png=None):
    """{"rmse", "mae", "rel_rmse", "mean_a", "mean_b", "mask_pixels", ...} of AOV 'aov' of test against ref, over
    the mask and every channel. top_rows "N/D" keeps the first N/D of the mask's rows (e.g. the far third)."""
    cmd = [specula, "compare", test, ref, "--aov", aov, "--json"]
    for m in masks:
        cmd += ["--mask", m]
    if top_rows:
        cmd += ["--mask-top-rows", top_rows]
    if diff_png:
        cmd += ["--diff", diff_png]
    return _run(cmd)


def flicker(specula, test_pattern, ref_pattern, frames, aov="specular", masks=("all",), top_rows=None):
    """Flicker over a frame sequence (validation.md §2): patterns are printf patterns of the frame index (e.g.
    "work/tubes_c20_f%02d.exr"), and so may be the masks (then the mask is the union over the frames). Returns
    {"flicker", "shimmer" (raw temporal std of the test), "shimmer_ref", "mask_pixels", ...}."""
    cmd = [specula, "compare", test_pattern, ref_pattern, "--aov", aov, "--json", "--frames", str(frames)]
    for m in masks:
        cmd += ["--mask", m]
    if top_rows:
        cmd += ["--mask-top-rows", top_rows]
    return _run(cmd)

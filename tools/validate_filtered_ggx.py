#!/usr/bin/env python3
"""Filtered-GGX validation (issue 4): cached references, measurements, table and pictures.

Protocol: shared/specs/validation.md. Page: docs/validation/filtered-ggx.md. Test: tests/unit/test_validation_filtered_ggx.cpp
(ctest, label cpu), which renders the 1-spp images in-process and compares them with the cached references.

Scenes are examples/filtered-ggx/{sphere,torus,cylinders,plane}.json, each written in its *reference* configuration
(4096 spp, Gaussian pixel filter with sigma^2 = 1/(2 pi), every bsdf.ggx_filtered with filter "none"). The 1-spp test
renders are derived from them by changing only: render.spp = 1, render.pixel_center = true, render.derivatives
(ray | quad) and, in every bsdf.ggx_filtered node, the inputs filter, kernel and derivatives (analytic | quad).

Commands (run from anywhere; paths are relative to the repository root):

  tools/validate_filtered_ggx.py [--build DIR] references [--force] [--scene NAME ...]
      Renders the references of the scenes whose cache is stale (tools/specula_validation/manifest.py: scene or
      texture SHA-256, derived scenes, or the renderer's output on a probe changed), or all of them with --force:
      per scene one 4096-spp image and 16 flicker frames (`specula render --camera-shift-px`, (1/8, 1/16) px per
      frame, 1024 spp each). Keeps their specular AOV as half-float ZIP EXRs in tests/validation/filtered_ggx/ and
      writes the toolkit's manifest.json there (command lines, hashes, probe fingerprint, timings).
  tools/validate_filtered_ggx.py [--build DIR] check
      Verifies the cache against the manifest (the test runs exactly this and fails loudly if it fails).
  tools/validate_filtered_ggx.py [--build DIR] report
      Runs the test binary in report mode (every mode, every scene, flicker for every mode), renders the pictures
      with the CLI, cross-checks the CLI numbers against the in-process ones, writes the tables into
      docs/validation/filtered-ggx.md and the pictures to docs/validation/img/filtered-ggx-*.png.
  tools/validate_filtered_ggx.py [--build DIR] all
      references (stale ones only) + report: everything the page shows. Every command line used is printed.

Needs the Python standard library, oiiotool, a build with the `specula` and `test_validation_filtered_ggx` targets,
and the reference renders. Shared steps: tools/specula_validation/ (docs/validation/README.md).
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from specula_validation import exr, metrics, rel  # noqa: E402
from specula_validation.manifest import Cache  # noqa: E402
from specula_validation.page import replace_block as replace_marked, write_png  # noqa: E402
from specula_validation.render import Renderer, specula_version  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = ["sphere", "torus", "cylinders", "plane"]
SCENE_DIR = "examples/filtered-ggx"
CACHE_DIR = "tests/validation/filtered_ggx"
MANIFEST = CACHE_DIR + "/manifest.json"
DOC = "docs/validation/filtered-ggx.md"
IMG_DIR = "docs/validation/img"
REF_SPP = 4096
FLICKER_FRAMES = 16
FLICKER_SPP = 1024
SHIFT_PX = (0.125, 0.0625)  # camera motion per frame, in pixels at the look-at distance (screen x right, y down)
NORMAL_MAP = "bumps_normal.png"


def shift_px(t):
    """Camera offset of flicker frame t (`specula render --camera-shift-px`): t (1/8, 1/16) px along (right, down)."""
    return (t * SHIFT_PX[0], t * SHIFT_PX[1])


def make_normal_map(path, n=128):
    """The plane's tangent-space normal map (OpenGL convention, 8-bit, periodic): the gradient of the height field
    h = 0.5 sin(8 pi x) sin(8 pi y) + 0.35 sin(2 pi (3x + 5y)) + 0.25 sin(2 pi (11x - 7y)), scaled by 0.012 (slopes up
    to about 0.49). Regenerated only if missing: it is an input of the plane's reference (hashed in the manifest)."""
    tau = 2 * math.pi
    rows = []
    for j in range(n):
        y = (j + 0.5) / n
        row = bytearray()
        for i in range(n):
            x = (i + 0.5) / n
            a, b = tau * (3 * x + 5 * y), tau * (11 * x - 7 * y)
            hx = 2 * tau * math.cos(4 * tau * x) * math.sin(4 * tau * y) + 1.05 * tau * math.cos(a) + 2.75 * tau * math.cos(b)
            hy = 2 * tau * math.sin(4 * tau * x) * math.cos(4 * tau * y) + 1.75 * tau * math.cos(a) - 1.75 * tau * math.cos(b)
            v = (-0.012 * hx, -0.012 * hy, 1.0)
            ln = math.sqrt(sum(c * c for c in v))
            row += bytes(max(0, min(255, round((c / ln * 0.5 + 0.5) * 255))) for c in v)
        rows.append(bytes(row))
    write_png(path, n, n, rows)


def load_scene(name):
    with open(os.path.join(ROOT, SCENE_DIR, name + ".json")) as f:
        return json.load(f)


def cache_spec(specula):
    """The cache as this script renders it now: per scene the scene file itself (the reference configuration) at
    REF_SPP, and FLICKER_FRAMES frames at FLICKER_SPP with the camera shifted by shift_px(t)."""
    c = Cache(os.path.join(ROOT, CACHE_DIR), page=DOC, generator="tools/validate_filtered_ggx.py",
              regenerate=f"python3 tools/validate_filtered_ggx.py --build {rel(os.path.dirname(os.path.dirname(specula)))} "
                         "references",
              protocol={"aov": "specular", "ref_spp": REF_SPP, "frames": FLICKER_FRAMES, "frame_spp": FLICKER_SPP,
                        "shift_px_per_frame": list(SHIFT_PX),
                        "reference_filter": "gaussian, sigma^2 = 1/(2 pi) (render.filter of the scene files)",
                        "storage": "specular AOV only (specular.R/G/B), half-float, ZIP (half rounding: relative "
                                   "error <= 4.9e-4)"})
    for n in SCENES:
        c.add_scene(n, os.path.join(ROOT, SCENE_DIR, n + ".json"))
        c.add_variant(n, "reference", load_scene(n))
        c.add_file(n, f"{n}_ref.exr", "reference", REF_SPP)
        for t in range(FLICKER_FRAMES):
            c.add_file(n, f"{n}_f{t:02d}.exr", "reference", FLICKER_SPP, shift_px(t))
    return c


def check_problems(specula, scenes=None):
    with tempfile.TemporaryDirectory(prefix="fggx_probe_") as tmp:
        return cache_spec(specula).check(specula, tmp, scenes)


def cmd_references(args):
    specula = args.specula
    work = os.path.join(args.work, "references")
    os.makedirs(work, exist_ok=True)
    os.makedirs(os.path.join(ROOT, CACHE_DIR), exist_ok=True)
    nm = os.path.join(ROOT, SCENE_DIR, NORMAL_MAP)
    if not os.path.exists(nm):
        make_normal_map(nm)
        print(f"wrote {rel(nm)}")
    spec_ = cache_spec(specula)
    old = {}
    if os.path.exists(spec_.path):
        with open(spec_.path) as f:
            old = json.load(f).get("scenes", {})
    records = {f["file"]: {k: f[k] for k in ("command", "seconds") if k in f}
               for e in old.values() for f in e.get("files", [])}
    rnd = Renderer(specula, work, verbose=True)
    for name in (args.scene or SCENES):
        why = ["--force"] if args.force else check_problems(specula, [name])
        if not why:
            print(f"{name}: references are up to date")
            continue
        print(f"{name}: rendering references ({'; '.join(why)})")
        scene_path = os.path.join(ROOT, SCENE_DIR, name + ".json")
        for f in spec_.scenes[name]["files"]:
            stem = f["file"][:-4]
            full, seconds = rnd.render(scene_path, stem, spp=f["spp"], shift_px=f["camera_shift_px"])
            exr.write_cached(full, os.path.join(ROOT, CACHE_DIR, f["file"]), ["specular.R", "specular.G", "specular.B"])
            records[f["file"]] = {"command": rnd.commands[-1], "seconds": round(seconds, 2)}
            if f["camera_shift_px"] is None:
                os.makedirs(os.path.join(ROOT, IMG_DIR), exist_ok=True)
                shutil.copyfile(full[:-4] + ".png", os.path.join(ROOT, IMG_DIR, f"filtered-ggx-{name}-reference.png"))
        # after every scene, so an interrupted run keeps its work (other scenes keep their records)
        spec_.write(specula, work, records, specula_version(specula))
    total = sum(os.path.getsize(os.path.join(ROOT, CACHE_DIR, f)) for f in os.listdir(os.path.join(ROOT, CACHE_DIR)))
    print(f"{CACHE_DIR}: {total / 1e6:.2f} MB")


# ---- report ---------------------------------------------------------------------------------------------------------

MODES = ([("none", "-")] + [(f, k) for f in ("slope", "projected", "projected_approx") for k in ("full", "axis_aligned")] +
         [(f, "-") for f in ("iso_max", "iso_sum", "iso_mean", "iso_rect")])
DERIVS = ("ray", "quad")
# Pictures on the page: the 1-spp renders of these modes (with 2x2-quad derivatives, as a GPU shades) and their errors.
PICTURE_MODES = [("none", "-", "quad"), ("slope", "full", "quad"), ("projected", "full", "quad"),
                 ("projected_approx", "axis_aligned", "quad"), ("iso_mean", "-", "quad")]
METHOD = {"none": "unfiltered", "slope": "slope (K16)", "projected": "projected (exact)",
          "projected_approx": "projected approx.", "iso_max": "iso_max", "iso_sum": "iso_sum", "iso_mean": "iso_mean",
          "iso_rect": "iso_rect (K16)"}


def picture_tag(scene, filt, kernel, deriv):
    parts = [scene, filt] + ([] if kernel == "-" else [kernel]) + [deriv]
    return "-".join(p.replace("_", "-") for p in parts)


def fmt(x, digits=4):
    if x is None:
        return "–"
    if x == 0 or 1e-3 <= abs(x) < 1e4:
        return f"{x:.{digits}g}"
    return f"{x:.3e}"


def ratio(x):
    return "–" if x is None else f"{x:.3f}"


def replace_block(text, name, body):
    return replace_marked(text, f"<!-- BEGIN generated: {name} -->", f"<!-- END generated: {name} -->", body)


def cmd_report(args):
    spec_ = cache_spec(args.specula)
    stale = check_problems(args.specula)
    if stale:
        raise SystemExit(spec_.stale_message(stale, "filtered-GGX"))
    with open(spec_.path) as f:
        manifest = json.load(f)
    report_dir = os.path.join(args.work, "report")
    shutil.rmtree(report_dir, ignore_errors=True)
    os.makedirs(report_dir)
    commands = []
    env = dict(os.environ, SPECULA_FGGX_REPORT_DIR=report_dir)
    cmd = [rel(args.test_bin), "--gtest_filter=FilteredGgxValidation.*"]  # also writes the derived scenes
    commands.append("SPECULA_FGGX_REPORT_DIR=" + rel(report_dir) + " " + " ".join(cmd))
    print("$ " + commands[-1], flush=True)
    t0 = time.time()
    test_rc = subprocess.run(cmd, cwd=ROOT, env=env).returncode
    print(f"test binary (report mode, flicker for every mode): {time.time() - t0:.0f} s, exit code {test_rc}")
    data = {}
    for n in SCENES:
        with open(os.path.join(report_dir, n + ".json")) as f:
            data[n] = json.load(f)

    # Pictures: CLI renders of the picture modes, cross-checked against the in-process numbers.
    img_dir = os.path.join(ROOT, IMG_DIR)
    os.makedirs(img_dir, exist_ok=True)
    pics = os.path.join(args.work, "pictures")
    os.makedirs(pics, exist_ok=True)
    worst = 0.0
    rnd = Renderer(args.specula, pics, scene_dir=os.path.join(ROOT, SCENE_DIR))
    for n in SCENES:
        refpng = os.path.join(args.work, "references", f"{n}_ref.png")
        if os.path.exists(refpng):  # also copied when the reference is rendered
            shutil.copyfile(refpng, os.path.join(img_dir, f"filtered-ggx-{n}-reference.png"))
        ref = os.path.join(ROOT, CACHE_DIR, f"{n}_ref.exr")
        for filt, kernel, deriv in PICTURE_MODES:
            tag = picture_tag(n, filt, kernel, deriv)
            with open(os.path.join(report_dir, "scenes", f"{n}__{filt}__{kernel}__{deriv}.json")) as f:
                s = json.load(f)  # the test's own derived scene: nothing is derived twice
            exr_path, _ = rnd.render(s, tag)
            commands.append(rnd.commands[-1])
            shutil.copyfile(exr_path[:-4] + ".png", os.path.join(img_dir, f"filtered-ggx-{tag}.png"))
            diff = os.path.join(img_dir, f"filtered-ggx-{tag}-diff.png")
            r = metrics.compare(args.specula, exr_path, ref, diff_png=diff)
            commands.append(f"{rel(args.specula)} compare {rel(exr_path)} {rel(ref)} --aov specular --json --mask all "
                            f"--diff {rel(diff)}")
            m = data[n]["modes"][f"{filt}/{kernel}/{deriv}"]
            for key in ("rmse", "mae"):
                d = abs(r[key] - m[key]) / max(m[key], 1e-12)
                worst = max(worst, d)
                if d > 1e-3:
                    raise SystemExit(f"{tag}: CLI {key} {r[key]} != in-process {m[key]}: the two paths disagree")
    print(f"CLI renders reproduce the in-process RMSE/MAE (largest relative difference {worst:.1e})")

    # Tables.
    lines = []
    for n in SCENES:
        d = data[n]
        lines.append(f"**{n}** ({d['width']}×{d['height']}; mean reference specular {fmt(d['reference_mean'])}; "
                     f"grazing mask {d['grazing_pixels']} px; flicker mask {d.get('object_pixels', '–')} px)\n")
        lines.append("| method | kernel | derivatives | RMSE | MAE | rel. RMSE | RMSE ratio | MAE ratio | grazing MAE "
                     "ratio | flicker ratio | grazing flicker ratio | ms / frame |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
        for deriv in DERIVS:
            for filt, kernel in MODES:
                m = d["modes"][f"{filt}/{kernel}/{deriv}"]
                lines.append(f"| {METHOD[filt]} | {kernel.replace('_', '-')} | {deriv} | {fmt(m['rmse'])} | "
                             f"{fmt(m['mae'])} | {m['rel_rmse']:.2f} | {ratio(m['rmse_ratio'])} | {ratio(m['mae_ratio'])} | "
                             f"{ratio(m.get('grazing_mae_ratio'))} | {ratio(m.get('flicker_ratio'))} | "
                             f"{ratio(m.get('grazing_flicker_ratio'))} | {m['ms_per_frame']:.1f} |")
        lines.append("")
    table = "\n".join(lines)

    # Projected vs slope in the grazing region, every scene.
    g = ["| scene | kernel | derivatives | slope grazing MAE | projected / slope | projected approx. / slope |",
         "|---|---|---|---|---|---|"]
    for n in SCENES:
        for deriv in DERIVS:
            for kernel in ("full", "axis_aligned"):
                ms = data[n]["modes"]
                s_ = ms[f"slope/{kernel}/{deriv}"]["grazing_mae"]
                p_ = ms[f"projected/{kernel}/{deriv}"]["grazing_mae"]
                a_ = ms[f"projected_approx/{kernel}/{deriv}"]["grazing_mae"]
                g.append(f"| {n} | {kernel.replace('_', '-')} | {deriv} | {fmt(s_)} | "
                         f"{(p_ / s_ if s_ else float('nan')):.3f} | {(a_ / s_ if s_ else float('nan')):.3f} |")
    grazing = "\n".join(g)

    # TK21's other statements, measured: one column per scene and derivative mode.
    cols = [(n, d) for n in SCENES for d in DERIVS]
    def mv(n, d, key, field):
        return data[n]["modes"][f"{key}/{d}"].get(field)
    def row(label, f):
        return "| " + label + " | " + " | ".join(f(n, d) for n, d in cols) + " |"
    def iso_best(field):
        def f(n, d):
            v = {k: mv(n, d, f"{k}/-", field) for k in ("iso_max", "iso_sum", "iso_mean", "iso_rect")}
            return "all equal" if max(v.values()) == min(v.values()) else min(v, key=v.get)
        return f
    t = ["| statement (TK21) | " + " | ".join(f"{n} {d}" for n, d in cols) + " |", "|---" * (len(cols) + 1) + "|"]
    for kern in ("full", "axis_aligned"):
        for field, name in (("rmse", "RMSE"), ("mae", "MAE")):
            t.append(row(f"{kern.replace('_', '-')} kernel: {name} projected / slope (Figs. 13, 14)",
                         lambda n, d, k=kern, fl=field: ratio(mv(n, d, f"projected/{k}", fl) / mv(n, d, f"slope/{k}", fl))))
    t.append(row("projected approx. vs exact: largest difference of RMSE ratios (Fig. 7)",
                 lambda n, d: f"{max(abs(mv(n, d, f'projected_approx/{k}', 'rmse_ratio') - mv(n, d, f'projected/{k}', 'rmse_ratio')) for k in ('full', 'axis_aligned')):.3f}"))
    for field, name in (("rmse", "RMSE"), ("mae", "MAE")):
        t.append(row(f"projected: {name} full / axis-aligned kernel (§6: full is lower)",
                     lambda n, d, fl=field: ratio(mv(n, d, "projected/full", fl) / mv(n, d, "projected/axis_aligned", fl))))
    t.append(row("projected: flicker full / axis-aligned kernel (§6: full flickers more)",
                 lambda n, d: ratio(mv(n, d, "projected/full", "flicker") / mv(n, d, "projected/axis_aligned", "flicker"))))
    t.append(row("isotropic filter with the lowest RMSE (Fig. 15: iso_mean)", iso_best("rmse")))
    t.append(row("isotropic filter with the lowest MAE (Fig. 15: iso_mean)", iso_best("mae")))
    t.append(row("RMSE iso_sum / iso_rect (Fig. 15: iso_sum slightly lower)",
                 lambda n, d: ratio(mv(n, d, "iso_sum/-", "rmse") / mv(n, d, "iso_rect/-", "rmse"))))
    t.append(row("RMSE iso_max / iso_sum (§5: iso_max the lowest conservative)",
                 lambda n, d: ratio(mv(n, d, "iso_max/-", "rmse") / mv(n, d, "iso_sum/-", "rmse"))))
    paper = "\n".join(t)

    # Pictures.
    p = []
    for n in SCENES:
        head = ["reference (4096 spp)"] + [f"{METHOD[f]}{'' if k == '-' else ', ' + k.replace('_', '-')}"
                                            for f, k, _ in PICTURE_MODES]
        p.append(f"**{n}** (1 spp at the pixel centre, 2×2-quad derivatives; error maps: |test − reference| of the "
                 "specular AOV, viridis, scaled to each map's 99th percentile, colour bar below each map)\n")
        p.append("| " + " | ".join(head) + " |")
        p.append("|" + "---|" * len(head))
        row = [f"![](img/filtered-ggx-{n}-reference.png)"]
        row2 = ["error maps →"]
        for filt, kernel, deriv in PICTURE_MODES:
            tag = picture_tag(n, filt, kernel, deriv)
            row.append(f"![](img/filtered-ggx-{tag}.png)")
            row2.append(f"![](img/filtered-ggx-{tag}-diff.png)")
        p.append("| " + " | ".join(row) + " |")
        p.append("| " + " | ".join(row2) + " |")
        p.append("")
    pictures = "\n".join(p)

    refcmds = []
    for n in SCENES:
        fs = manifest["scenes"][n]["files"]
        refcmds.append(f"{fs[0]['command']}    # {fs[0]['seconds']} s")
        refcmds.append(f"{fs[2]['command']}    # ... 16 frames, {fs[2]['seconds']} s each")
    cmds = "```\n" + "\n".join(refcmds + commands) + "\n```"

    doc_path = os.path.join(ROOT, DOC)
    with open(doc_path) as f:
        text = f.read()
    text = replace_block(text, "table", table)
    text = replace_block(text, "grazing", grazing)
    text = replace_block(text, "paper", paper)
    text = replace_block(text, "pictures", pictures)
    text = replace_block(text, "commands", cmds)
    with open(doc_path, "w") as f:
        f.write(text)
    print(f"wrote {DOC} and {IMG_DIR}/filtered-ggx-*.png")
    big = [f for f in os.listdir(img_dir) if f.startswith("filtered-ggx-") and os.path.getsize(os.path.join(img_dir, f)) > 300e3]
    if big:
        print("warning: pictures over 300 KB: " + ", ".join(big))
    if test_rc != 0:
        print("warning: the test binary failed (see above): the page shows the measured numbers anyway")
    return 0


def cmd_check(args):
    problems = check_problems(args.specula)
    if problems:
        print(cache_spec(args.specula).stale_message(problems, "filtered-GGX"), file=sys.stderr)
        return 1
    print(f"{CACHE_DIR}: up to date ({', '.join(SCENES)})")
    return 0


def cmd_manifest(args):
    """Rewrites the manifest for the cached files as they are, keeping their records."""
    spec_ = cache_spec(args.specula)
    with open(spec_.path) as f:
        old = json.load(f).get("scenes", {})
    records = {f["file"]: {k: f[k] for k in ("command", "seconds") if k in f}
               for e in old.values() for f in e.get("files", [])}
    with tempfile.TemporaryDirectory(prefix="fggx_probe_") as tmp:
        spec_.write(args.specula, tmp, records, specula_version(args.specula))
    print(f"wrote {MANIFEST}")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"), help="CMake build folder (default: build)")
    ap.add_argument("--specula", help="the specula binary (default: BUILD/bin/specula)")
    ap.add_argument("--work", default=os.path.join(ROOT, "out", "validation", "filtered-ggx"),
                    help="scratch folder for full renders (default: out/validation/filtered-ggx)")
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("references", help="render missing/stale references (all with --force)")
    r.add_argument("--force", action="store_true")
    r.add_argument("--scene", action="append", choices=SCENES)
    sub.add_parser("check", help="verify the cache against the manifest (what the test runs)")
    sub.add_parser("manifest", help="rewrite the manifest for the cached files as they are")
    sub.add_parser("report", help="measure every mode, write the page's tables and pictures")
    sub.add_parser("all", help="references (stale only) + report")
    args = ap.parse_args()
    args.build = os.path.abspath(args.build)
    args.work = os.path.abspath(args.work)
    args.specula = os.path.abspath(args.specula or os.path.join(args.build, "bin", "specula"))
    args.test_bin = os.path.join(args.build, "tests", "test_validation_filtered_ggx")
    if args.command == "references":
        cmd_references(args)
    elif args.command == "check":
        return cmd_check(args)
    elif args.command == "manifest":
        return cmd_manifest(args)
    elif args.command == "report":
        cmd_report(args)
    else:
        args.force, args.scene = False, None
        cmd_references(args)
        cmd_report(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())

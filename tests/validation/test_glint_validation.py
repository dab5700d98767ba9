#!/usr/bin/env python3
"""ctest `glint_validation` (label cpu): the C21 claims of docs/validation/glint.md, in CI size, against the cached
references of tests/validation/glint/ (only 1-spp renders here; references are never rendered by this test).

  1. The cache is up to date (tools/specula_validation/manifest.py: SHA-256 of the example scenes, normal maps,
     derived reference scenes and cached files, and the renderer's output on probe renders); otherwise the test
     FAILS and prints the regenerate command.
  2. GGAA (s_K 0.5) lowers the specular RMSE and the flicker of the thin tubes (C21 Fig. 8) and of the plane to the
     horizon (Fig. 1a -> 1b), and the RMSE of the brushed sphere with MIP-filtered normals.
  3. LEAN + glint lowers the error at a distance against glint alone with MIP-filtered normals (Fig. 7, Fig. 1c),
     and LEAN with rho beats LEAN without rho on the anisotropic brushed map (Fig. 7).

Margins: each bound is the measured ratio (docs/validation/glint.md) plus a margin, e.g. measured 0.42 -> <= 0.55.
Usage: test_glint_validation.py SPECULA_BINARY SOURCE_DIR
"""
import os
import sys
import tempfile
import time

SPECULA, SRC = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
sys.path.insert(0, os.path.join(SRC, "tools"))
import validate_glint as vg  # noqa: E402
from specula_validation import exr, ratio  # noqa: E402

# scene -> 1-spp methods rendered here, and the methods whose 16-frame flicker is measured
METHODS = {"tubes": ["c20", "ggaa05"], "sphere": ["naive_c20", "naive_ggaa05", "lean_norho_ggaa05", "lean_ggaa05"],
           "horizon": ["naive_c20", "naive_ggaa05", "lean_ggaa05"]}
FLICKER = {"tubes": ["c20", "ggaa05"], "horizon": ["naive_c20", "naive_ggaa05"]}

# (description, scene, kind, numerator method, denominator method, measured, bound); kind: rmse | flicker | far_rmse
CLAIMS = [
    ("tubes: GGAA 0.5 / no GGAA, RMSE", "tubes", "rmse", "ggaa05", "c20", 0.304, 0.40),
    ("tubes: GGAA 0.5 / no GGAA, flicker", "tubes", "flicker", "ggaa05", "c20", 0.305, 0.40),
    ("horizon: GGAA 0.5 / no GGAA (MIP normals), RMSE", "horizon", "rmse", "naive_ggaa05", "naive_c20", 0.958, 0.99),
    ("horizon: GGAA 0.5 / no GGAA (MIP normals), flicker", "horizon", "flicker", "naive_ggaa05", "naive_c20", 0.789,
     0.90),
    ("horizon: LEAN+glint / glint alone (GGAA 0.5), RMSE, far third", "horizon", "far_rmse", "lean_ggaa05",
     "naive_ggaa05", 0.411, 0.52),
    ("sphere: GGAA 0.5 / no GGAA (MIP normals), RMSE", "sphere", "rmse", "naive_ggaa05", "naive_c20", 0.672, 0.80),
    ("sphere: LEAN+glint / glint alone (GGAA 0.5), RMSE", "sphere", "rmse", "lean_ggaa05", "naive_ggaa05", 0.497, 0.62),
    ("sphere: LEAN with rho / LEAN without rho (GGAA 0.5), RMSE", "sphere", "rmse", "lean_ggaa05",
     "lean_norho_ggaa05", 0.761, 0.90),
]


def value(res, kind, k):
    if kind == "rmse":
        return res["methods"][k]["rmse"]
    if kind == "far_rmse":
        return res["methods"][k]["far"]["rmse"]
    return res["flicker"][k]["flicker"]


def main():
    t0 = time.time()
    exr.require_oiiotool()
    problems = vg.check_cache(SPECULA, list(METHODS))
    if problems:
        print(vg.cache_spec(SPECULA, list(METHODS)).stale_message(problems, "glint validation (about 15 min on 2 "
                                                                            "cores to regenerate)"), file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory(prefix="glint_validation_") as work:
        results = vg.evaluate(SPECULA, work, list(METHODS), METHODS, FLICKER)
    renders = results.pop("_renders")
    vg.print_tables(results)
    failed = 0
    print()
    for desc, sid, kind, num, den, measured, bound in CLAIMS:
        r = ratio(value(results[sid], kind, num), value(results[sid], kind, den))
        ok = r <= bound
        failed += not ok
        print(f"{'ok  ' if ok else 'FAIL'} {desc}: {r:.3f} (documented {measured:.3f}, bound <= {bound:.2f})")
    print(f"\n{renders} renders, {time.time() - t0:.1f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

"""Specula's one validation toolkit (docs/validation/README.md; protocol shared/specs/validation.md).

Every validation page (filtered GGX, LEAN, glints; LTC and P-NDF next) and its CI check use these modules and
nothing else for the shared steps:

  render    `specula render` with overrides (spp, resolution, seed, --camera-shift-px), command log
  metrics   RMSE / MAE / relative RMSE and flicker through `specula compare --json` (masks, frame sequences)
  manifest  the one cache-manifest format (hashlib SHA-256 of inputs and cached files, behavioural fingerprint)
  exr       reading EXRs (one route: oiiotool) and writing cached references (oiiotool)
  page      PNG pictures, false-colour error maps with a colour bar, Markdown tables, generated blocks of a page

Standard library only, plus the `specula` and `oiiotool` executables.
"""
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def rel(path):
    """'path' relative to the repository root (for command lines printed on pages)."""
    return os.path.relpath(os.path.abspath(path), ROOT)


def ratio(a, b):
    """a / b, NaN when b is not positive (the claims of every page are such ratios)."""
    return a / b if b and b > 0 else float("nan")

#!/usr/bin/env python3
# Layering check of core/: scans the #include lines of core/** and fails on any include of nodes/ or plugin/ from core
# (core knows no node by name) and on any cycle among core's folders, printing the includes that make it (issue 36).
#
# Usage: test_layering.py [SOURCE_DIR]   (default: the repository this file lives in). Exit 0 = layers point one way.
#
# The floors, bottom to top, as the includes draw them (docs/architecture.md):
#   {util, math, color} < {geometry, io} < texture < io_module < ltc < render < graph < {codegen, scene} < {api, farm}
# (io_module: the dlopen'ed OpenImageIO module's table, whose entries are io's and texture's functions).
# KNOWN_UPWARD lists the includes that still point up a floor, each with why, until they are moved; they are the only
# exceptions. An include in KNOWN_UPWARD that no longer exists is reported (delete the line: the list only shrinks).
# Any other include that closes a cycle fails the test.
import os
import re
import sys
from collections import defaultdict

INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^">]+)[">]')

# (including file, included header): upward includes not yet moved.
KNOWN_UPWARD = {
    # The LTC fit and evaluation speak the lobes' types (BsdfSample, Sampler, the GGX and Fresnel it fits) while the
    # lobes answer area-light queries through core/ltc: ltc <-> render.
    ("core/ltc/ltc_reference.cpp", "core/render/sampler.h"),
    ("core/ltc/ltc_reference.h", "core/render/bsdf.h"),
    ("core/ltc/ltc_prefilter.cpp", "core/render/lobes/ggx.h"),
    ("core/ltc/ltc_ggx.h", "core/render/lobes/fresnel.h"),
    ("core/ltc/ltc.h", "core/render/bsdf.h"),
    ("core/ltc/ltc_fit.cpp", "core/render/lobes/ggx.h"),
    ("core/ltc/ltc.cpp", "core/render/sampler.h"),
    ("core/ltc/ltc.cpp", "core/render/sampling.h"),
    # The integrators and the acceleration structure read the Scene, which holds render's cameras, lights and
    # materials: render <-> scene (the integrators would sit on a floor above scene).
    ("core/render/shadow_maps.cpp", "core/scene/scene.h"),
    ("core/render/integrator.cpp", "core/scene/scene.h"),
    ("core/render/renderer.cpp", "core/scene/scene.h"),
    ("core/render/accel.cpp", "core/scene/scene.h"),
}


def scan(root):
    """All quoted/angled includes of core/**: list of (file, line, header)."""
    found = []
    for dirpath, dirnames, files in os.walk(os.path.join(root, "core")):
        dirnames.sort()
        for name in sorted(files):
            if not name.endswith((".h", ".hpp", ".cpp", ".cc", ".inl")):
                continue
            path = os.path.join(dirpath, name)
            rel = os.path.relpath(path, root).replace(os.sep, "/")
            with open(path, encoding="utf-8", errors="replace") as f:
                for number, text in enumerate(f, 1):
                    m = INCLUDE.match(text)
                    if m:
                        found.append((rel, number, m.group(1)))
    return found


def folder(path):
    return path.split("/")[1]


def find_cycle(edges):
    """One cycle of the folder graph as a list of folders (first == last), or None."""
    state = {}
    stack = []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(edges[n]):
            if state.get(m) == 1:
                return stack[stack.index(m):] + [m]
            if m not in state:
                c = visit(m)
                if c:
                    return c
        stack.pop()
        state[n] = 2
        return None

    for n in sorted(edges):
        if n not in state:
            c = visit(n)
            if c:
                return c
    return None


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", ".."))
    includes = scan(root)
    if not includes:
        print(f"no #include lines found under {root}/core", file=sys.stderr)
        return 1
    failures = 0

    for rel, number, header in includes:
        if header.split("/")[0] in ("nodes", "plugin"):
            print(f"FAIL core includes a node or a front end: {rel}:{number}: #include \"{header}\"")
            failures += 1

    edges = defaultdict(set)
    via = defaultdict(list)
    seen_known = set()
    for rel, number, header in includes:
        parts = header.split("/")
        if parts[0] != "core" or len(parts) < 3:
            continue
        src, dst = folder(rel), parts[1]
        if src == dst:
            continue
        if (rel, header) in KNOWN_UPWARD:
            seen_known.add((rel, header))
            continue
        edges[src].add(dst)
        edges[dst]
        via[(src, dst)].append(f"{rel}:{number}: #include \"{header}\"")

    cycle = find_cycle(edges)
    if cycle:
        print("FAIL folder cycle in core: " + " -> ".join(cycle))
        for a, b in zip(cycle, cycle[1:]):
            for line in via[(a, b)]:
                print(f"  {a} -> {b}: {line}")
        failures += 1

    for rel, header in sorted(KNOWN_UPWARD - seen_known):
        print(f"note: known upward include gone, delete it from KNOWN_UPWARD: {rel} -> {header}")

    print(f"{len(includes)} includes in core/ scanned; folders and their arrows (known upward includes left out):")
    for src in sorted(edges):
        print(f"  {src} -> {', '.join(sorted(edges[src])) or '(none)'}")
    print(f"{len(seen_known)} known upward includes tolerated")
    if failures:
        return 1
    print("OK: no core file includes nodes/ or plugin/, and core's folders form no cycle")
    return 0


if __name__ == "__main__":
    sys.exit(main())

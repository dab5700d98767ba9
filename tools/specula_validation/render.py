"""Running `specula render` with overrides; every command line is recorded for the page."""
import copy
import json
import os
import shlex
import subprocess

from . import ROOT


def specula_version(specula):
    return subprocess.run([specula, "--version"], capture_output=True, text=True, check=True).stdout.strip()


def overrides_args(spp=None, resolution=None, seed=None, shift_px=None, threads=None):
    """The `specula render` arguments of the overrides (shift_px: (dx, dy) pixels, see docs/cli.md)."""
    a = []
    if spp is not None:
        a += ["--spp", str(spp)]
    if resolution is not None:
        a += ["--resolution", resolution if isinstance(resolution, str) else f"{resolution[0]}x{resolution[1]}"]
    if seed is not None:
        a += ["--seed", str(seed)]
    if shift_px is not None and tuple(shift_px) != (0, 0):
        a += ["--camera-shift-px", f"{float(shift_px[0])!r},{float(shift_px[1])!r}"]
    if threads is not None:
        a += ["--threads", str(threads)]
    return a


def rebase_files(scene, src_dir, dst_dir=None):
    """A copy of 'scene' whose relative 'file' and 'normal_map' keys (texture and normal-map inputs, mesh shapes,
    environment maps), written relative to src_dir, are made absolute (dst_dir None) or relative to dst_dir, so that
    the JSON can be written anywhere."""
    s = copy.deepcopy(scene)

    def rebase(obj):
        # 'normal_map': the file input of bsdf.ltc_normal_map and bsdf.glint_pndf. Generated maps
        # ('generate:<kind>:<size>:<seed>') are names, not paths.
        for key in ("file", "normal_map"):
            f = obj.get(key)
            if isinstance(f, str) and not os.path.isabs(f) and not f.startswith("generate:"):
                p = os.path.normpath(os.path.join(src_dir, f))
                obj[key] = p if dst_dir is None else os.path.relpath(p, dst_dir)

    for m in s.get("materials", {}).values():
        for n in m.get("nodes", {}).values():
            if isinstance(n.get("inputs"), dict):
                rebase(n["inputs"])
    for item in s.get("shapes", []) + s.get("lights", []):
        rebase(item)
    return s


class Renderer:
    """Renders scene dicts (written as JSON into a work folder) or scene files with `specula render`."""

    def __init__(self, specula, workdir, verbose=False, scene_dir=None):
        self.specula = os.path.abspath(specula)
        self.work = workdir
        self.verbose = verbose
        self.scene_dir = scene_dir  # where relative 'file' inputs of scene dicts resolve
        self.commands = []
        self.count = 0
        os.makedirs(workdir, exist_ok=True)

    def _display(self, cmd):
        return " ".join(shlex.quote(os.path.relpath(c, ROOT) if os.path.isabs(c) and c.startswith(ROOT) else c)
                        for c in cmd)

    def render(self, scene, name, spp=None, resolution=None, seed=None, shift_px=None, threads=None, extra=()):
        """Renders 'scene' (a dict, or the path of a scene file) to WORK/name.exr. Returns (exr path, seconds of
        the render as `specula` reports it)."""
        exr = os.path.join(self.work, name + ".exr")
        if isinstance(scene, dict):
            js = os.path.join(self.work, name + ".json")
            with open(js, "w") as f:
                json.dump(rebase_files(scene, self.scene_dir) if self.scene_dir else scene, f, indent=1)
        else:
            js = os.path.abspath(scene)
        cmd = [self.specula, "render", js, "-o", exr, "--progress", "json",
               *overrides_args(spp, resolution, seed, shift_px, threads), *extra]
        self.commands.append(self._display(cmd))
        if self.verbose:
            print("  $", self.commands[-1], flush=True)
        out = subprocess.run(cmd, capture_output=True, text=True)
        if out.returncode != 0:
            raise RuntimeError(f"render failed ({out.returncode}): {self.commands[-1]}\n{out.stderr}")
        secs = None
        for line in out.stdout.splitlines():
            if '"event":"done"' in line:
                secs = json.loads(line)["seconds"]
        self.count += 1
        return exr, secs

    def camera(self, scene, name, resolution=None, shift_px=None):
        """The camera `specula render` would use (after overrides), as {"position", "look_at", ...} floats."""
        if isinstance(scene, dict):
            js = os.path.join(self.work, name + ".json")
            with open(js, "w") as f:
                json.dump(rebase_files(scene, self.scene_dir) if self.scene_dir else scene, f, indent=1)
        else:
            js = scene
        cmd = [self.specula, "render", js, "--print-camera", *overrides_args(None, resolution, None, shift_px)]
        return json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)


def run_logged(cmd, log, env=None):
    """Runs a command line (any tool: specula, normalmap, ltc-report, a bench), appends it to 'log' for the page, and
    exits with its output when it fails. Returns stdout."""
    log.append(" ".join(shlex.quote(os.path.relpath(c, ROOT) if os.path.isabs(c) and c.startswith(ROOT) else c)
                        for c in cmd))
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        raise SystemExit("command failed (%d): %s\n%s%s" % (r.returncode, log[-1], r.stdout, r.stderr))
    return r.stdout


def tiled_uv_nodes(tiles):
    """Graph nodes for uv scaled by 'tiles' with its footprint (duv/dx, duv/dy) scaled the same, and the inputs that
    wire them into a texture or BSDF node ({"uv", "duvdx", "duvdy"})."""
    nodes = {
        "uvs": {"type": "geometry.uv"},
        "uv": {"type": "math.mul.vec2", "inputs": {"a": "@uvs.uv", "b": tiles}},
        "dx": {"type": "math.mul.vec2", "inputs": {"a": "@uvs.duvdx", "b": tiles}},
        "dy": {"type": "math.mul.vec2", "inputs": {"a": "@uvs.duvdy", "b": tiles}},
    }
    return nodes, {"uv": "@uv.out", "duvdx": "@dx.out", "duvdy": "@dy.out"}

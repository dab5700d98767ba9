"""The one cache-manifest format of the validation pages (schema "specula-validation-manifest/1").

A page's cached references (tests/validation/<page>/) are described by manifest.json:

  {"schema": "specula-validation-manifest/1", "page": "docs/validation/<page>.md", "generator": "tools/...",
   "regenerate": "<the command that regenerates the cache>", "renderer_version": "specula x.y.z" (information only),
   "protocol": {...free-form, the page's constants...},
   "probe": {"resolution": [24, 16], "spp": 8},
   "scenes": {"<id>": {
       "scene": "examples/.../scene.json",
       "inputs_sha256": {"<repo path>": "<sha256>", ...},            # the scene file and every file it reads
       "variants": {"<name>": {"scene_sha256": "<sha256 of the canonical derived scene JSON>",
                               "probe": {"camera_shift_px": null | [dx, dy], "pixels_sha1": "<oiiotool --hash>"}}},
       "files": [{"file": "x.exr", "variant": "<name>", "spp": N, "camera_shift_px": null | [dx, dy],
                  "sha256": "<sha256 of the cached file>", "command": "...", "seconds": s}, ...],
       "extra": {...free-form...}}}}

Staleness (validation.md §3). The cache is stale when an input file, a derived scene (the page's tool changed how
it derives them), the list of files (spp, camera shifts), a cached file, or the renderer's *behaviour* changed. The
behaviour is a fingerprint: each variant is rendered as a tiny probe (probe.resolution, probe.spp, with and without
the largest camera shift of its files) and the probe's float pixels are hashed. An internal refactor that leaves
the renderer's output bit-identical leaves the probes unchanged, so no regeneration; a change of the output changes
the probes and the check FAILS, loudly, with the regenerate command. It never passes silently.
"""
import copy
import hashlib
import json
import os

from . import ROOT, exr, rel
from .render import Renderer

SCHEMA = "specula-validation-manifest/1"
PROBE = {"resolution": [24, 16], "spp": 8}


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def sha256_json(obj):
    return hashlib.sha256(json.dumps(obj, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def scene_inputs(scene, scene_dir):
    """Repository paths of every 'file' input of every node of a scene whose relative paths resolve in
    scene_dir."""
    out = []
    for m in scene.get("materials", {}).values():
        for n in m.get("nodes", {}).values():
            f = n.get("inputs", {}).get("file")
            if isinstance(f, str):
                p = rel(os.path.normpath(os.path.join(scene_dir, f)))
                if p not in out:
                    out.append(p)
    return sorted(out)


class Cache:
    """What a page's cache must hold, as its tool derives it *now*. Fill with add_scene() / add_variant() /
    add_file(); then check() against the manifest, or write() a new manifest after rendering."""

    def __init__(self, cache_dir, page, generator, regenerate, protocol=None):
        self.dir = cache_dir
        self.path = os.path.join(cache_dir, "manifest.json")
        self.page, self.generator, self.regenerate, self.protocol = page, generator, regenerate, protocol or {}
        self.scenes = {}

    def add_scene(self, sid, scene_path, scene_dir=None):
        """scene_path: the example scene file; scene_dir: where the variants' relative 'file' inputs resolve
        (default: the scene file's folder)."""
        scene_dir = scene_dir or os.path.dirname(os.path.abspath(scene_path))
        with open(scene_path) as f:
            base = json.load(f)
        inputs = [rel(scene_path)] + scene_inputs(base, scene_dir)
        self.scenes[sid] = {"scene": rel(scene_path), "scene_dir": scene_dir, "inputs": inputs, "variants": {},
                            "files": [], "extra": {}}

    def add_variant(self, sid, name, scene):
        """A derived scene (a dict, relative paths as in the example scene) rendered into the cache."""
        s = self.scenes[sid]
        for p in scene_inputs(scene, s["scene_dir"]):
            if p not in s["inputs"]:
                s["inputs"].append(p)
        s["variants"][name] = copy.deepcopy(scene)

    def add_file(self, sid, name, variant, spp, camera_shift_px=None):
        self.scenes[sid]["files"].append({"file": name, "variant": variant, "spp": spp,
                                          "camera_shift_px": list(camera_shift_px) if camera_shift_px else None})

    # ---- fingerprint -------------------------------------------------------------------------------------------
    def _probe_shift(self, sid, variant):
        shifts = [f["camera_shift_px"] for f in self.scenes[sid]["files"]
                  if f["variant"] == variant and f["camera_shift_px"]]
        return max(shifts, key=lambda d: abs(d[0]) + abs(d[1])) if shifts else None

    def probes(self, specula, work, sid):
        """{variant: {"camera_shift_px", "pixels_sha1"}}: the behavioural fingerprint of the renderer on each
        variant of scene sid (probe renders of PROBE size, without and with the largest camera shift)."""
        s = self.scenes[sid]
        rnd = Renderer(specula, work, scene_dir=s["scene_dir"])
        out = {}
        for name, scene in s["variants"].items():
            shift = self._probe_shift(sid, name)
            hashes = []
            for k, d in enumerate([None, shift] if shift else [None]):
                p, _ = rnd.render(scene, f"probe_{sid}_{name}_{k}", spp=PROBE["spp"], resolution=PROBE["resolution"],
                                  shift_px=d)
                hashes.append(exr.pixel_hash(p))
            out[name] = {"camera_shift_px": shift, "pixels_sha1": hashes}
        return out

    # ---- check ---------------------------------------------------------------------------------------------------
    def check(self, specula, work, scenes=None):
        """Human-readable problems; empty = the cache is up to date for these scenes (default all)."""
        if not os.path.exists(self.path):
            return [f"{rel(self.path)} does not exist"]
        with open(self.path) as f:
            man = json.load(f)
        if man.get("schema") != SCHEMA:
            return [f"{rel(self.path)}: schema {man.get('schema')!r}, expected {SCHEMA!r}"]
        problems = []
        if man.get("probe") != PROBE:
            problems.append(f"probe settings {man.get('probe')} != {PROBE}")
        for sid in scenes or list(self.scenes):
            s, ms = self.scenes[sid], man.get("scenes", {}).get(sid)
            if ms is None:
                problems.append(f"scene {sid}: not in the manifest")
                continue
            for p in s["inputs"]:
                got = sha256_file(os.path.join(ROOT, p)) if os.path.exists(os.path.join(ROOT, p)) else None
                if ms.get("inputs_sha256", {}).get(p) != got:
                    problems.append(f"scene {sid}: input {p} changed or is missing (SHA-256)")
            for p in ms.get("inputs_sha256", {}):
                if p not in s["inputs"]:
                    problems.append(f"scene {sid}: input {p} is no longer read")
            for name, scene in s["variants"].items():
                mv = ms.get("variants", {}).get(name)
                if mv is None:
                    problems.append(f"scene {sid}: variant {name} is not in the manifest")
                elif mv.get("scene_sha256") != sha256_json(scene):
                    problems.append(f"scene {sid}: the derived {name} scene changed ({self.generator} or the scene)")
            want = [{k: f[k] for k in ("file", "variant", "spp", "camera_shift_px")} for f in s["files"]]
            have = [{k: f.get(k) for k in ("file", "variant", "spp", "camera_shift_px")} for f in ms.get("files", [])]
            if want != have:
                problems.append(f"scene {sid}: the cached files (names, spp or camera shifts) differ from what "
                                f"{self.generator} renders now")
            for f in ms.get("files", []):
                p = os.path.join(self.dir, f["file"])
                if not os.path.exists(p):
                    problems.append(f"{f['file']}: missing from {rel(self.dir)}")
                elif sha256_file(p) != f.get("sha256"):
                    problems.append(f"{f['file']}: content differs from the manifest (SHA-256)")
            if not problems:  # probes only when everything else matches (they cost renders)
                now = self.probes(specula, work, sid)
                for name, pr in now.items():
                    if ms.get("variants", {}).get(name, {}).get("probe") != pr:
                        problems.append(f"scene {sid}: the renderer's output changed (probe of the {name} variant, "
                                        f"{PROBE['resolution'][0]}x{PROBE['resolution'][1]} at {PROBE['spp']} spp, "
                                        f"no longer matches the manifest)")
        return problems

    def stale_message(self, problems, what):
        bar = "=" * 100
        return (f"{bar}\nFAIL: the cached {what} references are STALE:\n  " + "\n  ".join(problems) +
                f"\n\nThe comparison would be meaningless. Regenerate them and commit {rel(self.dir)}/:\n"
                f"    cd {ROOT} && {self.regenerate}\n{bar}")

    # ---- write -----------------------------------------------------------------------------------------------
    def write(self, specula, work, records, renderer_version, extra=None):
        """Writes the manifest for every scene of this Cache. records: {file name: {"command", "seconds", ...}}
        (how each cached file was made); extra: {sid: {...}} free-form."""
        man = {"schema": SCHEMA, "page": self.page, "generator": self.generator, "regenerate": self.regenerate,
               "renderer_version": renderer_version, "protocol": self.protocol, "probe": PROBE, "scenes": {}}
        # Regenerating a subset of scenes (--scenes) must not drop the others' entries: keep them as they are (their
        # probes are re-checked by check() like any other entry).
        if os.path.exists(self.path):
            with open(self.path) as fh:
                kept = json.load(fh).get("scenes", {})
            man["scenes"].update({sid: e for sid, e in kept.items() if sid not in self.scenes})
        for sid, s in self.scenes.items():
            probes = self.probes(specula, work, sid)
            entry = {"scene": s["scene"],
                     "inputs_sha256": {p: sha256_file(os.path.join(ROOT, p)) for p in s["inputs"]},
                     "variants": {n: {"scene_sha256": sha256_json(v), "probe": probes[n], "scene_json": v}
                                  for n, v in s["variants"].items()},
                     "files": []}
            for f in s["files"]:
                e = dict(f, sha256=sha256_file(os.path.join(self.dir, f["file"])))
                e.update(records.get(f["file"], {}))
                entry["files"].append(e)
            entry["extra"] = (extra or {}).get(sid, {})
            man["scenes"][sid] = entry
        tmp = self.path + ".tmp"
        with open(tmp, "w") as fh:
            json.dump(man, fh, indent=1)
            fh.write("\n")
        os.replace(tmp, self.path)
        return man

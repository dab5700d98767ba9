# The "Specula" render engine: exports the depsgraph, runs `specula render --progress json` as a child process,
# shows its tile progress, stops it within a second when the user cancels, and loads the beauty and AOV passes.
# The CLI owns the policies (atomic output, partial image on cancel, exit codes: docs/cli.md); this is a thin layer.
import json
import os
import queue
import shutil
import signal
import subprocess
import tempfile
import threading
import time

import bpy

from . import export, preferences
from .materials import ExportError

# EXR layer (docs/scene-format.md#outputs) -> Blender pass: (name, channels, chan_id, type).
AOV_PASSES = {
    "combined": ("Combined", 4, "RGBA", "COLOR"),
    "diffuse": ("Diffuse", 3, "RGB", "COLOR"),
    "specular": ("Specular", 3, "RGB", "COLOR"),
    "normal": ("Normal", 3, "XYZ", "VECTOR"),
    "depth": ("Depth", 1, "Z", "VALUE"),
}
AOV_CHANNELS = {"combined": ("R", "G", "B"),
                "diffuse": ("diffuse.R", "diffuse.G", "diffuse.B"),
                "specular": ("specular.R", "specular.G", "specular.B"),
                "normal": ("normal.X", "normal.Y", "normal.Z"),
                "depth": ("depth.Z",)}
CANCEL_GRACE_SECONDS = 3.0   # SIGTERM lets the CLI finish loading and write its partial image; then killed

# What the last render did, for tests and the UI: exit code, cancel latency, timings, warnings, paths.
last_render = {}


def enabled_aovs(view_layer):
    aovs = []
    if view_layer.specula.pass_diffuse:
        aovs.append("diffuse")
    if view_layer.specula.pass_specular:
        aovs.append("specular")
    if view_layer.use_pass_normal:
        aovs.append("normal")
    if view_layer.use_pass_z:
        aovs.append("depth")
    return aovs


def _read_lines(stream, sink):
    for line in iter(stream.readline, ""):
        sink.put(line)
    sink.put(None)


class SpeculaRenderEngine(bpy.types.RenderEngine):
    bl_idname = "SPECULA"
    bl_label = "Specula"
    bl_use_preview = False
    bl_use_eevee_viewport = True          # Material Preview / viewport shading use EEVEE (the node fallbacks)
    bl_use_shading_nodes_custom = False   # the standard shader node tree and panels
    bl_use_postprocess = True

    def update_render_passes(self, scene=None, renderlayer=None):
        for aov in ["combined"] + enabled_aovs(renderlayer):
            name, channels, chan_id, kind = AOV_PASSES[aov]
            self.register_pass(scene, renderlayer, name, channels, chan_id, kind)

    def render(self, depsgraph):
        last_render.clear()
        scene = depsgraph.scene
        width, height = export.render_size(scene)
        prefs = preferences.get()
        keep = bool(prefs and prefs.keep_files)
        tmp = tempfile.mkdtemp(prefix="specula_", dir=self.temporary_directory or None)
        last_render["folder"] = tmp
        try:
            self._render_in(depsgraph, width, height, tmp, prefs)
        except ExportError as e:
            self._fail("Specula export: %s" % e)
        finally:
            if not keep:
                shutil.rmtree(tmp, ignore_errors=True)

    # ---- steps ---------------------------------------------------------------------------------------------
    def _fail(self, message):
        last_render["error"] = message
        self.report({"ERROR"}, message)

    def _render_in(self, depsgraph, width, height, tmp, prefs):
        binary, message = preferences.locate_binary()
        if binary is None:
            self._fail(message)
            return
        self.update_stats("", "Specula: exporting")
        t0 = time.perf_counter()
        scene_path, exr_path = os.path.join(tmp, "scene.json"), os.path.join(tmp, "render.exr")
        warnings = export.write_scene(depsgraph, scene_path, width, height)
        last_render.update(export_seconds=time.perf_counter() - t0, warnings=warnings, scene=scene_path)
        for w in warnings:
            self.report({"WARNING"}, "Specula: " + w)
        if self.test_break():
            return

        cmd = [binary, "render", scene_path, "-o", exr_path, "--progress", "json",
               "--threads", str(prefs.threads if prefs else 0)]
        crop = self._border(depsgraph.scene, width, height)
        if crop:
            cmd += ["--crop", "%d,%d,%d,%d" % crop]
        try:
            proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                    start_new_session=True)
        except OSError as e:
            self._fail("Specula: cannot run '%s': %s" % (binary, e))
            return
        lines, errors = queue.Queue(), []
        threading.Thread(target=_read_lines, args=(proc.stdout, lines), daemon=True).start()
        err_thread = threading.Thread(target=lambda: errors.extend(proc.stderr.readlines()), daemon=True)
        err_thread.start()

        cancelled_at, done_event, partial = None, None, None
        while True:
            if cancelled_at is None and self.test_break():
                cancelled_at = time.perf_counter()
                proc.send_signal(signal.SIGTERM)   # the CLI stops its tiles and writes OUT.partial.exr
            if cancelled_at is not None and time.perf_counter() - cancelled_at > CANCEL_GRACE_SECONDS:
                proc.kill()
                break
            try:
                line = lines.get(timeout=0.05)
            except queue.Empty:
                # Keep waiting after the process has exited: its last lines (the "done" event) may still be on their
                # way through the reader thread, which ends the stream with None at EOF. Breaking on exit lost them
                # on a loaded machine ("Specula render failed (exit 0): no output").
                continue
            if line is None:
                break
            event = self._event(line)
            if event is None:
                continue
            kind = event.get("event")
            if kind == "tile":
                self.update_progress(float(event.get("progress", 0.0)))
                self.update_stats("", "Specula: tile %d/%d, %.2f Msamples/s, ETA %.1fs" % (
                    event.get("done", 0), event.get("total", 0), event.get("samples_per_second", 0.0) / 1e6,
                    event.get("eta", 0.0)))
            elif kind == "done":
                done_event = event
            elif kind == "cancelled":
                partial = event.get("partial")
        code = proc.wait()
        err_thread.join(timeout=1.0)
        last_render.update(returncode=code, command=cmd, stderr="".join(errors))
        if cancelled_at is not None:
            last_render["cancel_seconds"] = time.perf_counter() - cancelled_at
            if partial and os.path.isfile(partial):
                self._load(partial, width, height, crop, depsgraph.view_layer)   # what was rendered so far
            return
        if code != 0 or done_event is None or not os.path.isfile(exr_path):
            detail = "".join(errors).strip().splitlines()
            reason = detail[-1] if detail else "no output"
            self._fail("Specula render failed (exit %s): %s" % (code, reason))
            return
        last_render.update(render_seconds=float(done_event.get("seconds", 0.0)), exr=exr_path)
        self._load(exr_path, width, height, crop, depsgraph.view_layer)
        self.update_stats("", "Specula: %d samples in %.2fs" % (done_event.get("samples", 0),
                                                                done_event.get("seconds", 0.0)))

    @staticmethod
    def _event(line):
        line = line.strip()
        if not line.startswith("{"):
            return None
        try:
            return json.loads(line)
        except ValueError:
            return None

    @staticmethod
    def _border(scene, width, height):
        """Specula's --crop (top-left origin) for a border render, or None."""
        r = scene.render
        if not r.use_border:
            return None
        x0, x1 = int(r.border_min_x * width), int(round(r.border_max_x * width))
        y0, y1 = height - int(round(r.border_max_y * height)), height - int(r.border_min_y * height)
        if x1 <= x0 or y1 <= y0:
            return None
        return (x0, y0, x1, y1)

    def _load(self, exr, width, height, crop, view_layer):
        if crop:   # a border render's result is the border itself; Blender places it in the frame
            x0, y0, x1, y1 = crop
            x, y, w, h = 0, 0, x1 - x0, y1 - y0
        else:
            x, y, w, h = 0, 0, width, height
        try:
            passes = read_passes(exr, ["combined"] + enabled_aovs(view_layer))
        except (ImportError, OSError) as e:
            self._fail("Specula: cannot read the render %s: %s" % (exr, e))
            return
        result = self.begin_result(x, y, w, h)
        layer = result.layers[0]
        for aov, data in passes.items():
            name = AOV_PASSES[aov][0]
            if name in layer.passes and data.shape[:2] == (h, w):
                layer.passes[name].rect = data.reshape(h * w, -1)
        self.end_result(result)


def read_passes(exr, aovs):
    """{aov: float32 array (h, w, channels), bottom row first} read with OpenImageIO's Python module (Debian's
    python3-openimageio; Blender's own EXR loader does not read multi-layer files into a render layer)."""
    try:
        import numpy as np
        import OpenImageIO as oiio
    except ImportError as e:
        raise ImportError("%s (the Specula add-on reads EXR passes with OpenImageIO's Python module: "
                          "apt-get install python3-openimageio)" % e)
    image = oiio.ImageInput.open(exr)
    if image is None:
        raise OSError(oiio.geterror())
    try:
        spec = image.spec()
        pixels = image.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    finally:
        image.close()
    if pixels is None:
        raise OSError("no pixels in %s" % exr)
    pixels = np.asarray(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)[::-1]
    names = list(spec.channelnames)
    out = {}
    for aov in aovs:
        channels = AOV_CHANNELS[aov]
        if not all(c in names for c in channels):
            continue
        data = pixels[:, :, [names.index(c) for c in channels]]
        if aov == "combined":   # Specula's beauty is opaque
            data = np.concatenate([data, np.ones(data.shape[:2] + (1,), dtype=np.float32)], axis=2)
        out[aov] = np.ascontiguousarray(data)
    return out


def register():
    bpy.utils.register_class(SpeculaRenderEngine)


def unregister():
    bpy.utils.unregister_class(SpeculaRenderEngine)

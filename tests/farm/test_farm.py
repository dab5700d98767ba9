#!/usr/bin/env python3
"""ctest `farm` (issue 18): a single-node Slurm cluster started in a temporary folder runs `specula farm submit` jobs:
a 2x2-tile job with 2 sample splits per tile (one frame) and a 2-frame animation (camera path and a material literal
keyed), one array task killed once while it runs; the finish job resubmits it; the merged frames must equal
single-process renders bit for bit. Daemons are stopped by PID. Skipped (exit 77, a clear message) where Slurm
cannot run: not root, or slurm-wlm/munge missing.
usage: test_farm.py SPECULA_BINARY
"""
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from slurm_cluster import SlurmCluster, SlurmUnavailable  # noqa: E402

SKIP = 77

SCENE = {
    "version": 1,
    "description": "farm test: the anchor sphere, keyed camera path and roughness",
    "render": {"width": 256, "height": 160, "spp": 64, "seed": 3, "integrator": "path", "max_depth": 4},
    "camera": {"position": [0, -6, 2.5], "look_at": [0, 0, 1], "up": [0, 0, 1], "fov": 39.6},
    "materials": {
        "copper": {"nodes": {"surface": {"type": "bsdf.ggx", "inputs": {"roughness": 0.2, "fresnel": "schlick",
                                                                        "f0": [0.95, 0.64, 0.54]}}},
                   "output": "@surface.bsdf"},
        "grey": {"nodes": {"surface": {"type": "bsdf.diffuse", "inputs": {"color": [0.5, 0.5, 0.5]}}},
                 "output": "@surface.bsdf"},
    },
    "shapes": [
        {"type": "sphere", "radius": 1, "transform": {"translate": [0, 0, 1]}, "material": "copper"},
        {"type": "quad", "size": [20, 20], "material": "grey"},
    ],
    "lights": [{"type": "point", "position": [4, -4, 6], "power": 1500}],
    "animation": {
        "frame_start": 1, "frame_end": 2, "fps": 24,
        "tracks": [
            {"target": "/camera/position", "keys": [{"frame": 1, "value": [0, -6, 2.5]}, {"frame": 2, "value": [1.5, -5.8, 2.4]}]},
            {"target": "/materials/copper/nodes/surface/inputs/roughness", "interpolation": "smooth",
             "keys": [{"frame": 1, "value": 0.2}, {"frame": 2, "value": 0.05}]},
        ],
    },
}


def pixels(path):
    import OpenImageIO as oiio
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        raise RuntimeError(buf.geterror())
    return list(buf.spec().channelnames), buf.get_pixels(oiio.FLOAT)


def bit_identical(a, b):
    import numpy as np
    ca, pa = pixels(a)
    cb, pb = pixels(b)
    if ca != cb or pa.shape != pb.shape:
        return False, f"channels {ca} vs {cb}, shapes {pa.shape} vs {pb.shape}"
    same = np.array_equal(pa.view(np.uint32), pb.view(np.uint32))
    return same, f"max |difference| {float(np.abs(pa - pb).max()):.3g}"


def wait_for(cond, timeout, what):
    end = time.time() + timeout
    while time.time() < end:
        if cond():
            return
        time.sleep(0.25)
    raise TimeoutError("timed out waiting for " + what)


def main():
    specula = os.path.abspath(sys.argv[1])
    t0 = time.time()
    with tempfile.TemporaryDirectory(prefix="specula-farm-") as tmp:
        cluster = SlurmCluster(os.path.join(tmp, "slurm"))
        try:
            cluster.start()
        except SlurmUnavailable as e:
            cluster.stop()
            print(f"SKIP: no single-node Slurm cluster here: {e}")
            return SKIP
        try:
            return run(cluster, specula, tmp, t0)
        finally:
            cluster.stop()
            print(f"daemons stopped; farm test took {time.time() - t0:.1f} s")


def run(cluster, specula, tmp, t0):
    scene = os.path.join(tmp, "farmscene.json")
    with open(scene, "w") as f:
        json.dump(SCENE, f)
    env = cluster.env

    def sp(*args, check=True):
        out = subprocess.run([specula, *args], env=env, capture_output=True, text=True)
        if check and out.returncode != 0:
            raise RuntimeError(f"specula {' '.join(args)} -> {out.returncode}\n{out.stdout}{out.stderr}")
        return out

    # Job A: one frame in 2x2 tiles x 2 sample splits (8 tasks); job B: two frames whole (2 tasks).
    a = sp("farm", "submit", scene, "--frames", "1", "--tiles", "2x2", "--spp-split", "2", "--dir", os.path.join(tmp, "farmA"))
    # Farm B's folder holds spaces, a quote and a '$' (issue 35): sbatch gets it as one argv word (--chdir), the
    # scripts' log paths are relative to it, and the exec line quotes it.
    dir_b = os.path.join(tmp, "farm B's $(dir) & co")
    b = sp("farm", "submit", scene, "--frames", "1-2", "--dir", dir_b)
    print(a.stdout + b.stdout, end="")
    job_a = [l for l in a.stdout.splitlines() if l.startswith("jobs:")][0].split()[2].rstrip(",")

    # Kill one task of job A once, while it runs (the finish job must resubmit its piece).
    victim = f"{job_a}_5"
    def running():
        out = cluster.run("squeue", "-h", "-r", "-j", job_a, "-o", "%i %T", check=False).stdout
        return any(l.split()[0] == victim and l.split()[1] == "RUNNING" for l in out.splitlines() if l.strip())
    killed = False
    try:
        wait_for(running, 60, f"task {victim} to run")
        cluster.run("scancel", "--signal=KILL", victim)
        killed = True
    except TimeoutError:
        pass
    piece5 = os.path.join(tmp, "farmA", "pieces", "f0001_x00_y01_s01.exr")
    wait_for(lambda: not running(), 30, f"task {victim} to end")
    if killed and not os.path.exists(piece5):
        print(f"killed task {victim} while it ran; its piece is missing")
    else:
        # The task finished before the kill landed: remove its piece, which is what a lost task leaves (the finish
        # job runs only after every task of the array has ended, so it still sees the gap).
        killed = True
        if os.path.exists(piece5):
            os.remove(piece5)
        print(f"task {victim} finished before the kill landed; its piece was removed instead (same recovery path)")

    frames_a = os.path.join(tmp, "farmA", "frames", "farmscene_0001.exr")
    frames_b = [os.path.join(dir_b, "frames", f"farmscene_{f:04d}.exr") for f in (1, 2)]
    wait_for(lambda: os.path.exists(frames_a) and all(os.path.exists(p) for p in frames_b), 240, "the merged frames")
    # The task and finish logs of farm B are in its own logs/ folder, whatever its name holds.
    logs_b = sorted(os.listdir(os.path.join(dir_b, "logs")))
    print(f"farm B logs: {logs_b}")
    ok_logs = sum(l.startswith("task_") for l in logs_b) == 2 and any(l.startswith("finish_") for l in logs_b)
    status = sp("farm", "status", os.path.join(tmp, "farmA")).stdout
    print(status, end="")
    with open(os.path.join(tmp, "farmA", "plan.json")) as f:
        attempts = json.load(f)["attempts"]
    print(f"farm A: resubmissions {attempts}")
    ok = ok_logs
    if not ok_logs:
        print("FAIL: farm B's logs are not in its logs/ folder")
    if killed and attempts < 1:
        print("FAIL: the killed task's piece was not resubmitted")
        ok = False

    # Single-process references.
    ref_a = os.path.join(tmp, "ref_a.exr")
    block = SCENE["render"]["spp"] // 2
    sp("render", scene, "--frame", "1", "--sample-block", str(block), "-o", ref_a, "--progress", "none")
    same, why = bit_identical(frames_a, ref_a)
    print(f"2x2 tiles x 2 sample splits vs single process (sample_block {block}): {'bit-identical' if same else 'DIFFERENT'} ({why})")
    ok &= same
    for f, merged in zip((1, 2), frames_b):
        ref = os.path.join(tmp, f"ref_b{f}.exr")
        sp("render", scene, "--frame", str(f), "-o", ref, "--progress", "none")
        same, why = bit_identical(merged, ref)
        print(f"frame {f} vs single process: {'bit-identical' if same else 'DIFFERENT'} ({why})")
        ok &= same
    # The two frames differ (the animation did something).
    same12, _ = bit_identical(frames_b[0], frames_b[1])
    if same12:
        print("FAIL: frames 1 and 2 are identical: the animation changed nothing")
        ok = False
    # A finished frame is never overwritten: finishing again keeps it.
    before = os.stat(frames_a).st_mtime_ns
    print(sp("farm", "finish", os.path.join(tmp, "farmA")).stdout, end="")
    if os.stat(frames_a).st_mtime_ns != before:
        print("FAIL: farm finish rewrote a finished frame")
        ok = False
    print(f"{'PASS' if ok else 'FAIL'} in {time.time() - t0:.1f} s")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

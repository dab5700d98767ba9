"""EXR access, one route: oiiotool (OpenImageIO tools). Metrics never read pixels here (see metrics.py); this is
for pictures and for writing cached references."""
import shutil
import subprocess


def require_oiiotool():
    if shutil.which("oiiotool") is None:
        raise SystemExit("FAIL: oiiotool (Debian: openimageio-tools) is needed to read and write EXRs")


def read(paths):
    """Reads EXRs through `oiiotool --info -v --dumpdata` (one process per batch of 64). Returns a list of
    {"w", "h", "ch": {channel name: [floats, row-major]}} (values as oiiotool prints them: pictures only)."""
    out = []
    for i in range(0, len(paths), 64):
        batch = paths[i:i + 64]
        res = subprocess.run(["oiiotool", "--info", "-v", "--dumpdata", *batch], capture_output=True, text=True)
        if res.returncode != 0:
            raise RuntimeError("oiiotool failed: " + res.stderr)
        cur = None
        for line in res.stdout.splitlines():
            s = line.strip()
            if s.startswith("Pixel ("):
                a, b = s.split(":", 1)
                x, y = a[a.index("(") + 1:a.index(")")].split(",")
                k = int(y) * cur["w"] + int(x)
                for name, v in zip(cur["names"], b.split()):
                    cur["ch"][name][k] = float(v)
            elif s.startswith("channel list:"):
                cur["names"] = [c.strip() for c in s[len("channel list:"):].split(",")]
                cur["ch"] = {n: [0.0] * (cur["w"] * cur["h"]) for n in cur["names"]}
            elif " x " in s and "channel" in s and ":" in s and not line.startswith(" "):
                dims = s.split(":", 1)[1].split(",")[0].split("x")
                cur = {"w": int(dims[0]), "h": int(dims[1])}
                out.append(cur)
    if len(out) != len(paths):
        raise RuntimeError(f"read {len(out)} images from {len(paths)} files")
    for img in out:
        img.pop("names", None)
    return out


def layer(img, name, channels=("R", "G", "B")):
    """The channels of one layer of an image from read(), e.g. layer(img, "specular") -> [R, G, B] (the beauty
    layer's channels are the unprefixed R, G, B)."""
    if name == "beauty" and f"beauty.{channels[0]}" not in img["ch"]:
        return [img["ch"][c] for c in channels]
    return [img["ch"][f"{name}.{c}"] for c in channels]


def pixel_hash(path):
    """OpenImageIO's SHA-1 of the pixel data (`oiiotool --hash`): the same for the same float pixels, whatever
    the file's metadata."""
    res = subprocess.run(["oiiotool", "--hash", path], capture_output=True, text=True, check=True)
    for line in res.stdout.splitlines():
        if "SHA-1:" in line:
            return line.split("SHA-1:", 1)[1].strip()
    raise RuntimeError(f"oiiotool --hash printed no SHA-1 for {path}:\n{res.stdout}")


def write_cached(src, dst, channels, coverage=None):
    """Writes the cached reference: 'channels' of src (e.g. specular.R,G,B), plus, with coverage = another EXR,
    its R channel as coverage.Y; half float, ZIP, no date or software attributes."""
    cmd = ["oiiotool", "--nosoftwareattrib", src, "--ch", ",".join(channels)]
    if coverage:
        cmd += [coverage, "--ch", "R", "--chnames", "coverage.Y", "--chappend"]
    cmd += ["--eraseattrib", "DateTime", "-d", "half", "--compression", "zip", "-o", dst]
    subprocess.run(cmd, check=True)

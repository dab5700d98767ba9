"""The GPU/CPU image-parity criterion shared by the preview tests (docs/preview.md "Parity"): EXR reading and, per
AOV, the mean |GPU - CPU| over the mean |CPU| and the 99th percentile of the per-pixel relative error."""
import numpy as np
import OpenImageIO as oiio


def read_exr(path):
    """(pixels as float64 H x W x C, channel names) of the first subimage."""
    image = oiio.ImageInput.open(path)
    if image is None:
        raise OSError(oiio.geterror())
    spec = image.spec()
    px = np.asarray(image.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT), dtype=np.float64)
    image.close()
    return px.reshape(spec.height, spec.width, spec.nchannels), list(spec.channelnames)


def channels(path, names):
    """The named channels of an EXR, H x W x len(names)."""
    px, have = read_exr(path)
    return px[:, :, [have.index(c) for c in names]]


def parity(cpu, gpu, keep=None):
    """(mean |gpu - cpu| / mean |cpu|, p99 of |gpu - cpu| / (|cpu| + 1 % of its mean)), on channel sums per pixel, over
    the pixels where 'keep' (H x W booleans; default all) is true. An all-zero cpu gives (0, 0) when gpu is zero too,
    else (0, 1)."""
    if keep is not None:
        cpu, gpu = cpu[keep][:, None, :], gpu[keep][:, None, :]
    mean = np.abs(cpu).mean()
    if mean == 0.0:
        return 0.0, 0.0 if np.abs(gpu).max() == 0.0 else 1.0
    lx = np.abs(cpu).sum(axis=2)
    rel = np.abs(cpu - gpu).sum(axis=2) / (lx + 0.01 * lx.mean())
    return float(np.abs(cpu - gpu).mean() / mean), float(np.percentile(rel, 99))


def edge_ambiguous(normal, shifted_normals, threshold=0.1):
    """H x W booleans: pixels whose surface changes when the camera moves by GL's sub-pixel precision (the normal AOV
    of any shifted render differs by more than 'threshold' in channel sum). Their centres lie on an edge between two
    surfaces, where the rasteriser's snapped edge and the ray tracer's hit test may each pick either surface."""
    amb = np.zeros(normal.shape[:2], dtype=bool)
    for s in shifted_normals:
        amb |= np.abs(s - normal).sum(axis=2) > threshold
    return amb


def exit_status(failures):
    """Prints the failures, if any, on one FAILED line; the test's exit status (1 if any)."""
    if failures:
        print("FAILED: " + "; ".join(failures))
        return 1
    return 0

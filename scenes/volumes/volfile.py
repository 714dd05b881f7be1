"""What the grid scripts of this folder share: Mitsuba's .vol writer and smooth value noise.

Format (little endian; Mitsuba 3's gridvolume): 'VOL', version byte 3, int32 encoding 1
(float32), int32 x, y, z resolutions and channel count, six float32 for the bounding box, then
the values with x fastest and the channels innermost.
"""

import os
import struct

import numpy as np


def value_noise(rng, res, cells):
    """Smooth noise in [0, 1]: random values on a (cells+1)^3 lattice, cubic-smoothstep
    interpolated to res^3 samples (array axes z, y, x)."""
    lattice = rng.random((cells + 1,) * 3)
    t = (np.arange(res) + 0.5) / res * cells
    i0 = np.minimum(t.astype(int), cells - 1)
    f = t - i0
    f = f * f * (3 - 2 * f)
    a = lattice[i0] * (1 - f)[:, None, None] + lattice[i0 + 1] * f[:, None, None]
    a = a[:, i0] * (1 - f)[None, :, None] + a[:, i0 + 1] * f[None, :, None]
    a = a[:, :, i0] * (1 - f)[None, None, :] + a[:, :, i0 + 1] * f[None, None, :]
    return a


def write_vol(path, data, bbox=(0, 0, 0, 1, 1, 1)):
    """data[z, y, x, c] as a version 3 float32 .vol, atomically."""
    zres, yres, xres, channels = data.shape
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as f:
        f.write(b"VOL")
        f.write(struct.pack("<B", 3))
        f.write(struct.pack("<iiiii", 1, xres, yres, zres, channels))
        f.write(struct.pack("<6f", *bbox))
        f.write(np.ascontiguousarray(data, dtype="<f4").tobytes())  # x fastest, c innermost
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)

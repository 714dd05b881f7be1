"""Writes the data of pt's `sunsky` emitter (crates/pt-sky):

1. `crates/pt-sky/data/hosek_wilkie.bin`: the coefficient tables of the Hosek-Wilkie sky model
   (Hosek and Wilkie 2012, "An analytic model for full spectral sky-dome radiance") and of its
   solar radiance function (Hosek and Wilkie 2013, "Adding a solar-radiance function to the
   Hosek-Wilkie skylight model"), copied from the files Mitsuba 3.9.1 ships and reads for its
   `sunsky` emitter (`data/sunsky/sunsky_datasets.bin`, `sampling_data.bin`), which hold the
   published tables of the authors' reference implementation
   (http://cgg.mff.cuni.cz/projects/SkylightModelling/), resampled by Mitsuba's authors
   (sun irradiance per turbidity and solar elevation). The authors' BSD-3 licence is copied
   beside it (`data/LICENSE-hosek-wilkie`), as it requires.

   Layout (little-endian): the 8 bytes `PTSKY1\\0\\0`, then per table, in the order of
   TABLES below, a u32 count and that many f32. Mitsuba stores the model tables as f64 and
   evaluates them in f32 in its single-precision variants, which are the references; f32 is what
   it computes with.

2. `crates/pt-sky/src/testdata/mitsuba_sunsky.json`: Mitsuba 3.9.1's `sunsky` evaluated
   (scalar_rgb and scalar_spectral) in a set of directions for several parameter sets, and the
   sun directions it computes from dates and places: the values pt-sky's unit tests compare
   with.

    .venv/bin/python references/make_sunsky_tables.py
"""

import json
import shutil
import struct
from pathlib import Path

import mitsuba as mi
import numpy as np

REPO = Path(__file__).resolve().parents[1]
DATA = Path(mi.__file__).parent / "data" / "sunsky"
OUT = REPO / "crates" / "pt-sky" / "data"
CHECKS = REPO / "crates" / "pt-sky" / "src" / "testdata" / "mitsuba_sunsky.json"

# (file, field, shape): the order of the tables in hosek_wilkie.bin.
TABLES = [
    ("sunsky_datasets.bin", "sky_params_rgb", (10, 2, 6, 3, 9)),
    ("sunsky_datasets.bin", "sky_rad_rgb", (10, 2, 6, 3)),
    ("sunsky_datasets.bin", "sky_params_spec", (10, 2, 6, 11, 9)),
    ("sunsky_datasets.bin", "sky_rad_spec", (10, 2, 6, 11)),
    ("sunsky_datasets.bin", "sun_rad_rgb", (10, 45, 3, 4, 6)),
    ("sunsky_datasets.bin", "sun_rad_spec", (10, 45, 11, 4)),
    ("sunsky_datasets.bin", "sun_ld_spec", (11, 6)),
    ("sampling_data.bin", "sun_irradiance", (10, 30, 11)),
]

DTYPES = {9: "<f2", 10: "<f4", 11: "<f8"}


def read_tensor_file(path):
    """Mitsuba's TensorFile: `tensor_file\\0`, a 2-byte version, a u32 field count, then per
    field a u16 name length, the name, a u16 rank, a u8 type, a u64 byte offset and the shape
    (u64 each)."""
    b = path.read_bytes()
    if b[:12] != b"tensor_file\0":
        raise SystemExit(f"{path}: not a Mitsuba tensor file")
    pos = 14
    (count,) = struct.unpack_from("<I", b, pos)
    pos += 4
    fields = {}
    for _ in range(count):
        (n,) = struct.unpack_from("<H", b, pos)
        pos += 2
        name = b[pos:pos + n].decode()
        pos += n
        rank, dtype, offset = struct.unpack_from("<HBQ", b, pos)
        pos += 11
        shape = struct.unpack_from(f"<{rank}Q", b, pos)
        pos += 8 * rank
        fields[name] = np.frombuffer(b, dtype=DTYPES[dtype], count=int(np.prod(shape)),
                                     offset=offset).reshape(shape)
    return fields


def write_tables():
    files = {f: read_tensor_file(DATA / f) for f in {t[0] for t in TABLES}}
    out = bytearray(b"PTSKY1\0\0")
    for f, name, shape in TABLES:
        a = files[f][name]
        if a.shape != shape:
            raise SystemExit(f"{f}:{name} has shape {a.shape}, expected {shape}")
        out += struct.pack("<I", a.size) + a.astype("<f4").tobytes()
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "hosek_wilkie.bin").write_bytes(bytes(out))
    shutil.copyfile(DATA / "LICENSE", OUT / "LICENSE-hosek-wilkie")


def unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def directions(sun, rng, n=24):
    """Directions above the horizon: random ones, some near the sun, some inside its disc (the
    limb included) for the given half aperture."""
    d = rng.normal(size=(n, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.02
    d = [unit(x) for x in d]
    t1 = unit(np.cross(sun, [0.0, 0.0, 1.0]))
    t2 = np.cross(sun, t1)
    for ang_deg in [0.0, 0.05, 0.2, 0.26, 0.9, 5.0, 20.0]:
        a = np.radians(ang_deg)
        d.append(unit(np.cos(a) * sun + np.sin(a) * t1))
        d.append(unit(np.cos(a) * sun + np.sin(a) * (0.6 * t1 + 0.8 * t2)))
    d.append(unit([0.3, -0.1, 1e-3]))  # grazing
    d.append(np.array([0.0, 0.0, 1.0]))  # zenith
    return d


def eval_mitsuba(variant, params, dirs, wavelengths=None):
    mi.set_variant(variant)
    em = mi.load_dict(dict(type="sunsky", **params))
    out = []
    for d in dirs:
        si = mi.SurfaceInteraction3f()
        si.wi = mi.Vector3f(*(-d))
        if wavelengths is None:
            out.append([float(x) for x in em.eval(si)])
        else:
            row = []
            for k in range(0, len(wavelengths), 4):
                lam = (list(wavelengths[k:k + 4]) + [wavelengths[k]] * 4)[:4]
                si.wavelengths = lam
                row += [float(x) for x in em.eval(si)][: len(wavelengths[k:k + 4])]
            out.append(row)
    return out


def write_checks():
    rng = np.random.default_rng(2026)
    configs = [
        dict(turbidity=3.0, albedo=0.3, sun=[0.3, 0.2, 0.6]),
        dict(turbidity=7.3, albedo=0.8, complex_sun=True, sun=[-0.5, 0.4, 0.3]),
        dict(turbidity=1.5, albedo=0.1, sun_aperture=2.0, sun_scale=0.5, sky_scale=2.0,
             sun=[0.0, -0.2, 0.98]),
        dict(turbidity=9.7, albedo=0.5, sun_aperture=3.0, complex_sun=True, sun=[0.9, 0.1, 0.05]),
        dict(turbidity=1.0, albedo=0.0, sun=[0.2, 0.7, 0.02]),
        dict(turbidity=10.0, albedo=1.0, complex_sun=True, sun=[0.1, 0.1, 0.9]),
    ]
    wavelengths = [330.0, 360.0, 400.0, 455.0, 551.3, 600.0, 700.0, 719.0, 760.0]
    cases = []
    for c in configs:
        sun = unit(c.pop("sun"))
        params = dict(c, sun_direction=[float(x) for x in sun])
        dirs = directions(sun, rng)
        cases.append(dict(
            params=params,
            directions=[[float(x) for x in d] for d in dirs],
            rgb=eval_mitsuba("scalar_rgb", params, dirs),
            wavelengths=wavelengths,
            spectral=eval_mitsuba("scalar_spectral", params, dirs, wavelengths),
        ))
    mi.set_variant("scalar_rgb")
    places = [
        dict(),
        dict(hour=8.5),
        dict(year=2024, month=1, day=15, hour=11.0, minute=37.0, second=12.0,
             latitude=48.2, longitude=16.37, timezone=1.0),
        dict(year=1999, month=12, day=31, hour=17.25, latitude=-33.9, longitude=18.4,
             timezone=2.0),
        dict(year=2026, month=6, day=21, hour=12.0, latitude=51.48, longitude=0.0, timezone=1.0),
        dict(year=2031, month=9, day=3, hour=19.0, minute=45.0, latitude=-12.0,
             longitude=-77.0, timezone=-5.0),
    ]
    suns = []
    for p in places:
        em = mi.load_dict(dict(type="sunsky", **p))
        suns.append(dict(params=p, sun_direction=[float(x) for x in mi.traverse(em)["sun_direction"]]))
    CHECKS.parent.mkdir(parents=True, exist_ok=True)
    CHECKS.write_text(json.dumps(dict(
        source="Mitsuba 3.9.1 sunsky (scalar_rgb, scalar_spectral); references/make_sunsky_tables.py",
        radiance=cases, sun_positions=suns), indent=1) + "\n")


if __name__ == "__main__":
    write_tables()
    write_checks()

"""Mitsuba 3 Python emitter plugin `goniometric` for IES files: a point light whose intensity
over directions is an IES LM-63 type C table, which pt reads as (scenes/README.md,
"Photometric lights"):

    <emitter type="goniometric">
        <string name="filename" value="ies/downlight.ies"/>
        <rgb name="intensity" value="1, 0.85, 0.7"/>   <!-- colour; its luminance is divided out -->
        <float name="scale" value="0.008"/>            <!-- factor on the candelas, default 1 -->
        <transform name="to_world"> ... </transform>   <!-- nadir along local +z -->
    </emitter>

Same meaning as pt (crates/pt-scene/src/ies.rs reads the file, crates/pt-render/src/light/
profile.rs evaluates it), written here from the format's description, not translated:
candela x multiplier x ballast factor (x ballast-lamp factor before LM-63-2002) x scale, times
intensity / luminance(intensity); vertical angle gamma from local +z, horizontal angle C from
local +x towards +y; bilinear in (gamma, C) between tabulated angles after filling the circle
of azimuths by the file's symmetry; zero beyond the last vertical angle.

Only the emitter's light-sampling side exists (`sample_direction`, what the `path` integrator
uses): a delta light cannot be hit, and the references need nothing else. The llvm_ad_rgb
variant only (the reference scene is RGB); equirectangular goniometric images are not read here.
make_references.py imports this module and calls register() after every mi.set_variant.
"""

import math


def read_ies(path):
    """(theta radians, phi radians, values[row][column]) of a type C IES file, the circle of
    azimuths filled by its symmetry; values in candela times the file's factors."""
    text = open(path, "rb").read().decode("latin-1")
    lines = text.splitlines()
    head = lines[0].strip().upper()
    old = not (head.startswith("IESNA:LM-63-2002") or "2019" in head)
    k = next(i for i, l in enumerate(lines) if l.lstrip().startswith("TILT="))
    tilt = lines[k].split("=", 1)[1].strip().upper()
    nums = [float(t) for l in lines[k + 1:] for t in l.replace(",", " ").split()]
    pos = 0
    if tilt == "INCLUDE":
        n = int(nums[1])
        pos = 2 + 2 * n
    (_, _, mult, nv, nh, ptype, _, _, _, _, ballast, lamp, _) = nums[pos:pos + 13]
    nv, nh = int(nv), int(nh)
    if ptype != 1:
        raise ValueError(f"{path}: only photometric type C")
    pos += 13
    vert = nums[pos:pos + nv]
    hor = nums[pos + nv:pos + nv + nh]
    cd = nums[pos + nv + nh:pos + nv + nh + nv * nh]
    factor = mult * ballast * (lamp if old else 1.0)
    h0, h1 = hor[0], hor[-1]
    if nh == 1:
        images = lambda c: [0.0]
    elif (h0, h1) == (0.0, 90.0):
        images = lambda c: [c, -c, 180.0 - c, 180.0 + c]
    elif (h0, h1) == (0.0, 180.0):
        images = lambda c: [c, -c]
    elif (h0, h1) == (90.0, 270.0):
        images = lambda c: [c, 180.0 - c]
    elif (h0, h1) == (0.0, 360.0):
        images = lambda c: [c]
    else:
        raise ValueError(f"{path}: horizontal angles {h0}-{h1}")
    cols = []
    for j, h in enumerate(hor):
        for c in images(h):
            c = c % 360.0
            if all(abs(c - x) >= 1e-6 for x, _ in cols):
                cols.append((c, j))
    cols.sort()
    theta = [math.radians(v) for v in vert]
    phi = [math.radians(c) for c, _ in cols]
    values = [[cd[j * nv + i] * factor for _, j in cols] for i in range(nv)]
    return theta, phi, values


def register():
    import drjit as dr
    import mitsuba as mi

    # The tables live in JIT arrays (gathered per lane): llvm_ad_rgb, the variant the
    # references render in.
    if mi.is_spectral or mi.is_polarized or not dr.is_jit_v(mi.Float):
        return

    class Goniometric(mi.Emitter):
        def __init__(self, props):
            mi.Emitter.__init__(self, props)
            name = str(props.get("filename"))
            path = str(mi.Thread.thread().file_resolver().resolve(name))
            if not name.lower().endswith(".ies"):
                raise ValueError(f"goniometric: this plugin reads .ies files, not '{name}'")
            theta, phi, values = read_ies(path)
            scale = float(props.get("scale")) if props.has_property("scale") else 1.0
            if props.has_property("intensity"):
                c = props.get("intensity")
                colour = [float(c[0]), float(c[1]), float(c[2])] if hasattr(c, "__len__") else [float(c)] * 3
            else:
                colour = [1.0, 1.0, 1.0]
            lum = 0.212671 * colour[0] + 0.715160 * colour[1] + 0.072169 * colour[2]
            self.m_colour = mi.Color3f(*[x * scale / lum for x in colour])
            to_world = props.get("to_world") if props.has_property("to_world") else mi.ScalarTransform4f()
            import numpy as np
            m = np.array(to_world.matrix, dtype=np.float64).reshape(4, 4)
            self.m_pos = mi.Point3f(*[float(x) for x in m[:3, 3]])
            # Rows of the world-to-local rotation: the normalised columns of to_world's linear part.
            cols = [m[:3, k] / np.linalg.norm(m[:3, k]) for k in range(3)]
            self.m_axes = [mi.Vector3f(*[float(x) for x in c]) for c in cols]
            self.m_theta = mi.Float(theta)
            self.m_phi = mi.Float(phi)
            self.m_values = mi.Float([v for row in values for v in row])
            self.m_nt, self.m_np = len(theta), len(phi)
            self.m_phi0 = phi[0]
            self.m_theta_range = (theta[0], theta[-1])
            self.m_flags = mi.EmitterFlags.DeltaPosition

        def intensity(self, d_world, active):
            """Table value towards the unit world direction `d_world` (bilinear, zero outside the
            rows)."""
            x = dr.dot(d_world, self.m_axes[0])
            y = dr.dot(d_world, self.m_axes[1])
            z = dr.dot(d_world, self.m_axes[2])
            th = dr.acos(dr.clip(z, -1.0, 1.0))
            inside = active & (th >= self.m_theta_range[0] - 1e-5) & (th <= self.m_theta_range[1] + 1e-5)
            nt, np_ = self.m_nt, self.m_np
            i = dr.binary_search(0, nt, lambda k: dr.gather(mi.Float, self.m_theta, dr.minimum(k, nt - 1)) <= th)
            i = dr.clip(mi.UInt32(dr.maximum(mi.Int32(i) - 1, 0)), 0, nt - 2)
            ph = dr.atan2(y, x)
            ph = dr.select(ph < 0.0, ph + 2.0 * math.pi, ph)
            ph = dr.select(ph < self.m_phi0, ph + 2.0 * math.pi, ph)
            if np_ > 1:
                # binary_search(start, end, pred) returns the first index in [start, end) where
                # pred fails (end if none): the node after phi's cell, the last cell wrapping.
                j = dr.binary_search(0, np_, lambda k: dr.gather(mi.Float, self.m_phi, dr.minimum(k, np_ - 1)) <= ph)
                j = mi.UInt32(dr.maximum(mi.Int32(j) - 1, 0))
                last = j == np_ - 1
                j1 = dr.select(last, 0, j + 1)
                p0 = dr.gather(mi.Float, self.m_phi, j)
                p1 = dr.select(last, self.m_phi0 + 2.0 * math.pi, dr.gather(mi.Float, self.m_phi, j1))
                s = dr.clip((ph - p0) / (p1 - p0), 0.0, 1.0)
            else:
                j = mi.UInt32(0)
                j1 = mi.UInt32(0)
                s = mi.Float(0.0)
            t0 = dr.gather(mi.Float, self.m_theta, i)
            t1 = dr.gather(mi.Float, self.m_theta, i + 1)
            t = dr.clip((th - t0) / (t1 - t0), 0.0, 1.0)
            v = lambda r, c: dr.gather(mi.Float, self.m_values, r * np_ + c, inside)
            lo = dr.lerp(v(i, j), v(i, j1), s)
            hi = dr.lerp(v(i + 1, j), v(i + 1, j1), s)
            return dr.select(inside, dr.lerp(lo, hi, t), 0.0)

        def sample_direction(self, it, sample, active=True):
            ds = dr.zeros(mi.DirectionSample3f)
            ds.p = self.m_pos
            ds.n = mi.Normal3f(0.0)
            ds.uv = mi.Point2f(0.0)
            ds.time = it.time
            ds.pdf = mi.Float(1.0)
            ds.delta = mi.Bool(True)
            ds.emitter = mi.EmitterPtr(self)
            d = self.m_pos - it.p
            dist2 = dr.squared_norm(d)
            ds.dist = dr.sqrt(dist2)
            ds.d = d / ds.dist
            value = self.intensity(-ds.d, active) / dist2
            return ds, dr.select(active, self.m_colour * value, 0.0)

        def pdf_direction(self, it, ds, active=True):
            return mi.Float(0.0)

        def eval_direction(self, it, ds, active=True):
            return dr.select(active, self.m_colour * self.intensity(-ds.d, active) / dr.squared_norm(ds.p - it.p), 0.0)

        def eval(self, si, active=True):
            return mi.Color3f(0.0)

        def sample_ray(self, time, sample1, sample2, sample3, active=True):
            raise NotImplementedError("goniometric: light tracing is not implemented in this plugin")

        def bbox(self):
            p = mi.ScalarPoint3f(dr.slice(self.m_pos) if hasattr(dr, "slice") else self.m_pos)
            return mi.ScalarBoundingBox3f(p)

        def traverse(self, callback):
            pass

        def to_string(self):
            return f"Goniometric[{self.m_nt} x {self.m_np} angles]"

    mi.register_emitter("goniometric", lambda props: Goniometric(props))

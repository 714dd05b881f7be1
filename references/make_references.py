#!/usr/bin/env python3
"""Render the Mitsuba 3 reference images for the scenes in scenes/.

Usage (from the repository root, with the virtual environment described in
references/README.md):

    .venv/bin/python references/make_references.py                  # every scenes/*.xml
    .venv/bin/python references/make_references.py cornell-box      # selected scenes
    .venv/bin/python references/make_references.py cornell-box --spp 16384
    .venv/bin/python references/make_references.py --dry-run        # show what would happen
    .venv/bin/python references/make_references.py cornell-box --spp 256 --check-variance

For each scene `scenes/<name>.xml` it writes

    references/<name>.exr      mean radiance, float32, channels R, G, B (linear sRGB), and A
                               (Mitsuba's alpha) when the scene's film has pixel_format rgba
    references/<name>_channels.exr  for an `aov` or `moment` integrator: every channel of
                               Mitsuba's film by name (the image, the nested integrator's copy,
                               the AOVs; or the moments)
    references/<name>_var.exr  per-pixel variance OF THE MEAN (sample variance / spp), float32 RGB

(a scene in a folder below scenes/, e.g. `scenes/atlas/veach-mis.xml`, which must be named
explicitly, writes into the same folder below references/: `references/atlas/veach-mis.exr`,
manifest key `atlas/veach-mis`; tests/references.rs reads only the top level)
and updates the scene's entry in references/manifest.json (variant, spp, seed, Mitsuba version,
wall time, date, the scene file's sha256, max_depth, the <default> values used, and how the
variance was computed). Files are written atomically (temporary file, then os.replace).

Colour mode and variant.  A scene is spectral if its XML (comments removed) contains a
<spectrum> with wavelength:value pairs, a filename or a type (d65, blackbody, ...), or the word
`blackbody`, or if it carries the marker comment `<!-- pt:mode=spectral -->`
(`<!-- pt:mode=rgb -->` forces RGB); otherwise it is RGB.  The variant is llvm_ad_<mode> when the
Dr.Jit LLVM backend works on this machine (checked in a subprocess; DRJIT_LIBLLVM_PATH is set to
libLLVM.so.19.1 unless already set), else scalar_<mode>.  --variant overrides the choice.

Variance.  With llvm_ad_* variants, a box reconstruction filter (radius 0.5: every sample lands in
exactly one pixel with weight 1) and a sampling integrator, the scene's integrator is wrapped in a
small moment integrator (`RGBMoment` below) that is Mitsuba's `moment` plugin (moment.cpp) with the
second moments taken of the per-sample linear sRGB value instead of CIE XYZ: the stock plugin only
writes XYZ moments, from which RGB variances cannot be recovered (cross terms are missing).  Per
pixel it gives m1 = mean f and m2 = mean f^2; passes of --pass-spp samples with different seeds are
combined in float64 and var_of_mean = max(m2 - m1^2, 0) / (spp - 1).  Otherwise (scalar variants,
where a Python integrator would be called once per sample; other filters; non-sampling integrators)
the image is rendered as K >= 16 independent batches with different seeds, and
var_of_mean = sample variance of the batch means / K.

Skipping.  A scene whose manifest entry has the same scene sha256, the same colour mode and at
least the requested spp (and whose files exist) is "up to date" and skipped.  A reference is never
replaced by one with fewer samples unless --force is given (--force also re-renders up-to-date
scenes).  Scenes using plugins Mitsuba does not know (project-only models) are reported and skipped.

Plugins.  Every references/plugins/*.py is imported (after the first mi.set_variant) and its
`register()` function, if present, is called after every mi.set_variant, before scenes are loaded.
register() must look up variant-dependent classes (mi.BSDF, ...) when it is called.

Mitsuba never runs in CI; this script is run by a person when a scene or the pipeline changes.
"""

import argparse
import datetime
import hashlib
import importlib.util
import json
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

# Must be set before Dr.Jit initialises its LLVM backend (older LLVMs load but fail to compile).
os.environ.setdefault("DRJIT_LIBLLVM_PATH", "libLLVM.so.19.1")

import numpy as np  # noqa: E402

REF_DIR = Path(__file__).resolve().parent
REPO = REF_DIR.parent
SCENE_DIR = REPO / "scenes"
PLUGIN_DIR = REF_DIR / "plugins"
MANIFEST = REF_DIR / "manifest.json"
EXPECTED_MITSUBA = "3.9.1"
VARIANTS = ("llvm_ad_rgb", "llvm_ad_spectral", "scalar_rgb", "scalar_spectral")
MIN_BATCHES = 16


def log(*a):
    print(*a, flush=True)


# --------------------------------------------------------------------------------------------
# Scene inspection (no Mitsuba needed)
# --------------------------------------------------------------------------------------------

def resolve_scene(arg):
    p = Path(arg)
    candidates = [p, SCENE_DIR / arg, SCENE_DIR / (arg + ".xml")]
    for c in candidates:
        if c.is_file():
            return c.resolve()
    raise SystemExit(f"error: scene {arg!r} not found (looked for {', '.join(map(str, candidates))})")


def reference_name(path):
    """Manifest key and output stem of a scene: its path below scenes/ without .xml
    (scenes/cornell-box.xml -> cornell-box, scenes/atlas/veach-mis.xml -> atlas/veach-mis);
    a scene outside scenes/ uses its file stem."""
    try:
        return path.relative_to(SCENE_DIR).with_suffix("").as_posix()
    except ValueError:
        return path.stem


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def colour_mode(xml_text):
    """'spectral' or 'rgb', with the reason."""
    m = re.search(r"<!--\s*pt:mode\s*=\s*(rgb|spectral)\s*-->", xml_text)
    if m:
        return m.group(1), f"marker comment pt:mode={m.group(1)}"
    text = re.sub(r"<!--.*?-->", "", xml_text, flags=re.S)
    if re.search(r"blackbody", text, flags=re.I):
        return "spectral", "blackbody"
    for tag in re.finditer(r"<spectrum\b[^>]*>", text):
        t = tag.group(0)
        if re.search(r"\bvalue\s*=\s*[\"'][^\"']*:", t):
            return "spectral", "<spectrum> with wavelength:value pairs"
        if re.search(r"\b(filename|type)\s*=", t):
            return "spectral", "<spectrum> from a file or plugin type"
    return "rgb", "no wavelength-dependent data"


def xml_defaults(xml_text):
    """The scene's <default name=... value=...> entries, in file order."""
    text = re.sub(r"<!--.*?-->", "", xml_text, flags=re.S)
    out = {}
    for tag in re.finditer(r"<default\b[^>]*>", text):
        n = re.search(r"\bname\s*=\s*[\"']([^\"']*)[\"']", tag.group(0))
        v = re.search(r"\bvalue\s*=\s*[\"']([^\"']*)[\"']", tag.group(0))
        if n and v:
            out[n.group(1)] = v.group(1)
    return out


# --------------------------------------------------------------------------------------------
# Manifest and atomic output
# --------------------------------------------------------------------------------------------

def load_manifest():
    if MANIFEST.is_file():
        with open(MANIFEST) as f:
            return json.load(f)
    return {"comment": "Mitsuba 3 references; written by references/make_references.py",
            "scenes": {}}


def atomic_write_bytes(path, data):
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def save_manifest(manifest):
    manifest["scenes"] = dict(sorted(manifest["scenes"].items()))
    atomic_write_bytes(MANIFEST, (json.dumps(manifest, indent=2) + "\n").encode())


def write_exr(mi, path, rgb, metadata, alpha=None):
    rgb = np.ascontiguousarray(rgb, dtype=np.float32)
    assert rgb.ndim == 3 and rgb.shape[2] == 3
    if alpha is None:
        bmp = mi.Bitmap(rgb, pixel_format=mi.Bitmap.PixelFormat.RGB)
    else:
        rgba = np.concatenate([rgb, np.asarray(alpha, dtype=np.float32)[..., None]], axis=2)
        bmp = mi.Bitmap(np.ascontiguousarray(rgba), pixel_format=mi.Bitmap.PixelFormat.RGBA)
    write_bitmap(mi, path, bmp, metadata)


def write_bitmap(mi, path, bmp, metadata):
    """`bmp` with `metadata` in its header, as an OpenEXR file written atomically."""
    md = bmp.metadata()
    for k, v in metadata.items():
        md[k] = v
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    bmp.write(str(tmp), mi.Bitmap.FileFormat.OpenEXR)
    os.replace(tmp, path)


def write_preview_png(path, rgb):
    """Tone-mapped (clamp + sRGB gamma) 8-bit PNG preview; needs only numpy and zlib."""
    import struct
    import zlib
    x = np.clip(rgb, 0.0, 1.0)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    img = (x * 255.0 + 0.5).astype(np.uint8)
    h, w, _ = img.shape
    raw = b"".join(b"\x00" + img[y].tobytes() for y in range(h))

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


# --------------------------------------------------------------------------------------------
# Mitsuba set-up
# --------------------------------------------------------------------------------------------

_llvm_ok = {}


def llvm_works(mode):
    """Does llvm_ad_<mode> load and compile a kernel?  Checked in a subprocess, because an
    incompatible libLLVM can crash the process rather than raise."""
    if mode not in _llvm_ok:
        code = ("import mitsuba as mi, drjit as dr\n"
                f"mi.set_variant('llvm_ad_{mode}')\n"
                "x = dr.arange(mi.Float, 16)\n"
                "print('probe', dr.sum(x * x))\n")
        try:
            r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                               timeout=300, env=os.environ.copy())
            m = re.search(r"probe \[?([0-9.]+)", r.stdout)
            _llvm_ok[mode] = r.returncode == 0 and m is not None and float(m.group(1)) == 1240
            if not _llvm_ok[mode]:
                log(f"note: llvm_ad_{mode} unusable (DRJIT_LIBLLVM_PATH="
                    f"{os.environ.get('DRJIT_LIBLLVM_PATH')}); falling back to scalar_{mode}."
                    f" {r.stderr.strip().splitlines()[-1] if r.stderr.strip() else ''}")
        except subprocess.TimeoutExpired:
            _llvm_ok[mode] = False
    return _llvm_ok[mode]


class Mitsuba:
    """Holds the imported module, switches variants and (re)registers plugins."""

    def __init__(self):
        import mitsuba as mi
        self.mi = mi
        self.variant = None
        self.plugin_modules = None
        if mi.__version__ != EXPECTED_MITSUBA:
            log(f"warning: Mitsuba {mi.__version__} installed, references are made with "
                f"{EXPECTED_MITSUBA}")

    def set_variant(self, variant):
        mi = self.mi
        if variant == self.variant:
            return
        mi.set_variant(variant)
        self.variant = variant
        if self.plugin_modules is None:
            self.plugin_modules = []
            for f in sorted(PLUGIN_DIR.glob("*.py")):
                spec = importlib.util.spec_from_file_location(f"pt_reference_plugins.{f.stem}", f)
                mod = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(mod)
                self.plugin_modules.append(mod)
                log(f"plugin module {f.name} imported")
        for mod in self.plugin_modules:
            if hasattr(mod, "register"):
                mod.register()


def make_rgb_moment(mi, nested):
    """Mitsuba's `moment` integrator (src/integrators/moment.cpp) with per-sample linear sRGB
    second moments as AOVs (the plugin itself only gives XYZ ones).  The returned radiance is the
    nested integrator's, so the film's R, G, B channels are unchanged; the last three AOVs are
    mean(R^2), mean(G^2), mean(B^2) over the samples of each pixel (box filter assumed)."""
    import drjit as dr

    class RGBMoment(mi.SamplingIntegrator):
        def __init__(self, props, nested):
            super().__init__(props)
            self.nested = nested

        def sample(self, scene, sampler, ray, medium=None, active=True):
            spec, valid, aovs = self.nested.sample(scene, sampler, ray, medium, active)
            if mi.is_rgb:
                rgb = mi.Color3f(spec)
            else:  # as the film / moment.cpp: divide by the wavelength pdf, to XYZ, to sRGB
                pdf = mi.pdf_rgb_spectrum(ray.wavelengths)
                s = spec * dr.select(pdf != 0, dr.rcp(pdf), 0)
                rgb = mi.xyz_to_srgb(mi.spectrum_to_xyz(s, ray.wavelengths, active))
            return spec, valid, list(aovs) + [rgb.x * rgb.x, rgb.y * rgb.y, rgb.z * rgb.z]

        def aov_names(self):
            return list(self.nested.aov_names()) + ["m2.R", "m2.G", "m2.B"]

        def to_string(self):
            return f"RGBMoment[nested={self.nested}]"

    return RGBMoment(mi.Properties(), nested)


# --------------------------------------------------------------------------------------------
# Rendering
# --------------------------------------------------------------------------------------------

def write_channels_exr(mi, path, names, planes, metadata):
    """Every channel of a film (`planes` is height x width x len(names)), named as given."""
    data = np.ascontiguousarray(planes, dtype=np.float32)
    bmp = mi.Bitmap(data, pixel_format=mi.Bitmap.PixelFormat.MultiChannel, channel_names=names)
    write_bitmap(mi, path, bmp, metadata)


def split(total, size):
    """Split `total` samples into passes of at most `size`."""
    return split_n(total, max(1, math.ceil(total / size)))


def split_n(total, n):
    """Split `total` samples into `n` near-equal passes."""
    base, extra = divmod(total, n)
    return [base + (1 if i < extra else 0) for i in range(n)]


def base_rgb(img, n_aov):
    """First three channels of the developed film (R, G, B), checking the layout."""
    return base_rgba(img, n_aov)[0]


def base_rgba(img, n_aov):
    """The developed film's R, G, B and its alpha (None for pixel_format rgb)."""
    nbase = img.shape[2] - n_aov
    if nbase not in (3, 4):
        raise RuntimeError(f"film gives {nbase} colour channels; need pixel_format rgb or rgba")
    return img[..., :3], (img[..., 3] if nbase == 4 else None)


def render_moment(mi, scene, spp, pass_spp, seed, progress=True):
    integ = make_rgb_moment(mi, scene.integrator())
    n_aov = len(integ.aov_names())
    s1 = s2 = sa = None
    passes = split(spp, pass_spp)
    for i, n in enumerate(passes):
        img = np.array(mi.render(scene, integrator=integ, spp=n, seed=seed + i), dtype=np.float64)
        rgb, alpha = base_rgba(img, n_aov)
        m2 = img[..., -3:]
        s1 = rgb * n if s1 is None else s1 + rgb * n
        s2 = m2 * n if s2 is None else s2 + m2 * n
        if alpha is not None:
            sa = alpha * n if sa is None else sa + alpha * n
        if progress and len(passes) > 1:
            log(f"  pass {i + 1}/{len(passes)} ({n} spp, seed {seed + i})")
    m1, m2 = s1 / spp, s2 / spp
    var = np.maximum(m2 - m1 * m1, 0.0) / max(spp - 1, 1)
    info = {
        "method": "moment",
        "description": ("Mitsuba's moment integrator (moment.cpp) re-implemented in Python to "
                        "record per-sample linear-sRGB second moments (the stock plugin records "
                        "only XYZ); box filter so each sample hits one pixel with weight 1; "
                        "m1 = film RGB, m2 = mean of f^2; passes combined in float64; "
                        "var_of_mean = max(m2 - m1^2, 0) / (spp - 1)"),
        "passes": len(passes),
        "pass_spp": passes[0],
        "seeds": f"{seed} + pass index (0..{len(passes) - 1})",
    }
    return m1, var, info, (None if sa is None else sa / spp)


def extra_channel_count(scene):
    """Channels an `aov` or `moment` integrator appends to the image mi.render returns (an aov
    integrator's outputs, not its nested integrators' copies; a moment integrator's first and
    second moments), 0 for other integrators."""
    integ = scene.integrator()
    names = integ.aov_names()
    if integ.class_name() == "MomentIntegrator":
        return len(names)
    if integ.class_name() != "AOVIntegrator":
        return 0
    # Each nested integrator adds NAME.R, .G, .B, .A; an albedo output has no .A.
    nested = sum(1 for n in names if n.endswith(".A") and n[:-2] + ".R" in names)
    return len(names) - 4 * nested


def render_batches(mi, scene, spp, pass_spp, seed, k_min=MIN_BATCHES, progress=True):
    k = max(k_min, math.ceil(spp / pass_spp))
    if spp < k:
        raise RuntimeError(f"batch variance needs spp >= {k}")
    batches = split_n(spp, k)
    n_aov = extra_channel_count(scene)
    means, alphas, films = [], [], []
    for i, n in enumerate(batches):
        img = np.array(mi.render(scene, spp=n, seed=seed + i), dtype=np.float64)
        rgb, alpha = base_rgba(img, n_aov)
        means.append(rgb * n)
        if alpha is not None:
            alphas.append(alpha * n)
        if n_aov:
            # The film (of an aov integrator: its AOV pass) holds every channel by name.
            films.append(np.array(scene.sensors()[0].film().bitmap(), dtype=np.float64) * n)
        if progress:
            log(f"  batch {i + 1}/{k} ({n} spp, seed {seed + i})")
    w = np.array(batches, dtype=np.float64)[:, None, None, None]
    b = np.stack(means) / w                       # batch means
    mean = np.sum(b * w, axis=0) / spp
    if len(set(batches)) == 1:
        var = np.var(b, axis=0, ddof=1) / k
    else:  # unequal batches: weighted estimate of the per-sample variance, divided by spp
        var = np.sum(w * (b - mean) ** 2, axis=0) / (k - 1) / spp
    info = {
        "method": "batches",
        "description": (f"{k} independent batches with different seeds; "
                        "var_of_mean = sample variance (ddof=1) of the batch means / K"),
        "batches": k,
        "batch_spp": batches[0],
        "seeds": f"{seed} + batch index (0..{k - 1})",
    }
    if films:
        bitmap = scene.sensors()[0].film().bitmap()
        names = [bitmap.struct_()[i].name for i in range(bitmap.channel_count())]
        info["aov_channels"] = (names, np.sum(films, axis=0) / spp)
    return mean, var, info, (np.sum(alphas, axis=0) / spp if alphas else None)


def moment_applicable(mi, scene, variant):
    """Why the moment method cannot be used (None if it can)."""
    if not variant.startswith("llvm_ad_"):
        return "scalar variant (a Python integrator would run once per sample)"
    if not isinstance(scene.integrator(), mi.SamplingIntegrator):
        return "integrator is not a sampling integrator"
    rf = scene.sensors()[0].film().rfilter()
    if not str(rf).startswith("BoxFilter") or abs(rf.radius() - 0.5) > 1e-6:
        return f"reconstruction filter is not a box of radius 0.5 ({rf})"
    return None


def integrator_params(integ):
    s = str(integ)
    name = integ.class_name() if hasattr(integ, "class_name") else type(integ).__name__
    out = {"type": name, "description": " ".join(s.split())}
    for key in ("max_depth", "rr_depth"):
        m = re.search(rf"\b{key}\s*=\s*(-?\d+)", s)
        if m:
            out[key] = int(m.group(1))
    return out


def stats(mean, var):
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.sqrt(var) / mean
    ok = np.isfinite(rel) & (mean > 0)
    return {
        "mean_rgb": [round(float(x), 6) for x in mean.reshape(-1, 3).mean(axis=0)],
        "mean_rel_stderr": round(float(rel[ok].mean()), 6) if ok.any() else None,
        "median_rel_stderr": round(float(np.median(rel[ok])), 6) if ok.any() else None,
        "max_value": round(float(mean.max()), 6),
    }


# --------------------------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------------------------

def choose_variant(mode, override):
    if override:
        return override
    return f"llvm_ad_{mode}" if llvm_works(mode) else f"scalar_{mode}"


def unknown_plugins(err):
    return sorted(set(re.findall(r'Plugin "([^"]+)" not found', str(err))))


def check_variance(msb, scene_path, args):
    """Render the scene with both methods at --spp and compare the mean variances."""
    mi = msb.mi
    text = scene_path.read_text()
    mode, _ = colour_mode(text)
    variant = choose_variant(mode, args.variant)
    if not variant.startswith("llvm_ad_"):
        raise SystemExit("--check-variance needs an llvm_ad_* variant")
    msb.set_variant(variant)
    scene = mi.load_file(str(scene_path))
    t = time.time()
    m_mean, m_var, _, _ = render_moment(mi, scene, args.spp, args.pass_spp, args.seed)
    t_m = time.time() - t
    t = time.time()
    b_mean, b_var, b_info, _ = render_batches(mi, scene, args.spp, max(1, args.spp // MIN_BATCHES),
                                           args.seed + 100000, progress=False)
    t_b = time.time() - t
    out = {"scene": scene_path.name, "variant": variant, "spp": args.spp,
           "batches": b_info["batches"], "time_moment_s": round(t_m, 2),
           "time_batches_s": round(t_b, 2)}
    for c, name in enumerate("RGB"):
        out[f"mean_var_moment_{name}"] = float(m_var[..., c].mean())
        out[f"mean_var_batches_{name}"] = float(b_var[..., c].mean())
        out[f"ratio_batches_over_moment_{name}"] = float(b_var[..., c].mean() / m_var[..., c].mean())
    ok = m_var > 0
    r = b_var[ok] / m_var[ok]
    out["per_pixel_ratio_median"] = float(np.median(r))
    out["per_pixel_ratio_mean"] = float(r.mean())
    out["mean_image_rel_diff"] = float(np.abs(m_mean.mean() - b_mean.mean()) / m_mean.mean())
    # (image mean difference in units of its standard error)
    out["mean_image_diff_z"] = float((m_mean.mean() - b_mean.mean()) /
                                     math.sqrt((m_var.sum() + b_var.sum()) / m_var.size ** 2))
    print(json.dumps(out, indent=2))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="See the module docstring and references/README.md.")
    ap.add_argument("scenes", nargs="*", help="scene names or files (default: scenes/*.xml)")
    ap.add_argument("--spp", type=int, default=4096, help="samples per pixel (default 4096)")
    ap.add_argument("--seed", type=int, default=0, help="base seed; pass i uses seed + i")
    ap.add_argument("--pass-spp", type=int, default=256,
                    help="samples per render pass (bounds llvm memory; default 256)")
    ap.add_argument("--variant", choices=VARIANTS, help="override the variant choice")
    ap.add_argument("--variance", choices=("auto", "moment", "batches"), default="auto",
                    help="variance method (default: moment when applicable, else batches)")
    ap.add_argument("--force", action="store_true",
                    help="re-render up-to-date scenes and allow fewer samples than the existing "
                         "reference")
    ap.add_argument("--dry-run", action="store_true", help="only report what would be done")
    ap.add_argument("--preview", metavar="DIR",
                    help="also write a clamped sRGB PNG preview <scene>.png into DIR")
    ap.add_argument("--check-variance", action="store_true",
                    help="compare moment and 16-batch variance at --spp; writes nothing")
    args = ap.parse_args()
    if args.spp < 2:
        ap.error("--spp must be >= 2")

    paths = ([resolve_scene(s) for s in args.scenes] if args.scenes
             else sorted(p.resolve() for p in SCENE_DIR.glob("*.xml")))
    if not paths:
        raise SystemExit("no scenes")

    if args.check_variance:
        msb = Mitsuba()
        for p in paths:
            check_variance(msb, p, args)
        return 0

    manifest = load_manifest()
    msb = None
    results = {}
    for path in paths:
        name = reference_name(path)
        text = path.read_text()
        digest = sha256_file(path)
        mode, why = colour_mode(text)
        if args.variant:
            mode = "spectral" if "spectral" in args.variant else "rgb"
        old = manifest["scenes"].get(name)
        mean_path, var_path = REF_DIR / f"{name}.exr", REF_DIR / f"{name}_var.exr"
        have = old is not None and mean_path.is_file() and var_path.is_file()

        if have and not args.force and old.get("scene_sha256") == digest \
                and old.get("mode") == mode and old.get("spp", 0) >= args.spp:
            log(f"{name}: up to date ({old['spp']} spp, {old['variant']})")
            results[name] = "up to date"
            continue
        if have and not args.force and old.get("spp", 0) > args.spp:
            log(f"{name}: REFUSED: existing reference has {old['spp']} spp > requested "
                f"{args.spp} (scene or mode changed); use --spp {old['spp']} or --force")
            results[name] = "refused"
            continue

        variant = choose_variant(mode, args.variant)
        log(f"{name}: {mode} ({why}), variant {variant}, {args.spp} spp")
        if args.dry_run:
            results[name] = "would render"
            continue

        if msb is None:
            msb = Mitsuba()
        mi = msb.mi
        msb.set_variant(variant)
        try:
            scene = mi.load_file(str(path))
        except Exception as e:  # noqa: BLE001
            missing = unknown_plugins(e)
            if missing:
                log(f"{name}: SKIPPED: uses plugin(s) {', '.join(missing)} unknown to Mitsuba "
                    f"(project-only models; register them from references/plugins/*.py)")
                results[name] = "skipped (unknown plugin)"
                continue
            log(f"{name}: FAILED to load: {e}")
            results[name] = "failed"
            continue

        film = scene.sensors()[0].film()
        # The image's size: a crop window's, else the film's.
        width, height = (int(x) for x in film.crop_size())
        method = args.variance
        reason = moment_applicable(mi, scene, variant)
        if method == "auto":
            method = "batches" if reason else "moment"
        elif method == "moment" and reason:
            raise SystemExit(f"{name}: moment variance not applicable: {reason}")

        mean_path.parent.mkdir(parents=True, exist_ok=True)
        t0 = time.time()
        try:
            if method == "moment":
                mean, var, vinfo, alpha = render_moment(
                    mi, scene, args.spp, args.pass_spp, args.seed)
            else:
                mean, var, vinfo, alpha = render_batches(
                    mi, scene, args.spp, args.pass_spp, args.seed)
                if reason:
                    vinfo["why_not_moment"] = reason
        except Exception as e:  # noqa: BLE001
            log(f"{name}: FAILED to render: {e}")
            results[name] = "failed"
            continue
        wall = time.time() - t0

        bad = (~np.isfinite(mean)).sum() + (~np.isfinite(var)).sum()
        if bad:
            log(f"{name}: FAILED: {bad} NaN/inf values; nothing written")
            results[name] = "failed"
            continue
        st = stats(mean, var)
        log(f"{name}: {wall:.1f} s, mean RGB {st['mean_rgb']}, "
            f"mean relative std error {st['mean_rel_stderr']}")

        date = datetime.datetime.now(datetime.timezone.utc).replace(microsecond=0).isoformat()
        meta = {"scene": path.name, "scene_sha256": digest, "variant": variant,
                "spp": args.spp, "seed": args.seed, "mitsuba_version": mi.__version__,
                "wall_time_s": round(wall, 2), "date": date}
        write_exr(mi, mean_path, mean, dict(meta, content="mean radiance (linear sRGB)"
                                             + ("" if alpha is None else " and alpha")),
                  alpha)
        write_exr(mi, var_path, var,
                  dict(meta, content="variance of the mean (sample variance / spp)",
                       variance_method=vinfo["method"]))
        if "aov_channels" in vinfo:
            names, planes = vinfo.pop("aov_channels")
            write_channels_exr(mi, mean_path.with_name(f"{name.split('/')[-1]}_channels.exr"),
                               names, planes, dict(meta, content="every channel of the film (aov, moment)"))
        if args.preview:
            Path(args.preview).mkdir(parents=True, exist_ok=True)
            write_preview_png(Path(args.preview) / f"{name.replace('/', '-')}.png", mean)

        import drjit as dr
        integ = integrator_params(scene.integrator())
        try:
            scene_rel = str(path.relative_to(REPO))
        except ValueError:
            scene_rel = str(path)
        manifest["scenes"][name] = {
            "scene": scene_rel,
            "scene_sha256": digest,
            "mode": mode,
            "mode_reason": why if not args.variant else f"--variant {args.variant}",
            "variant": variant,
            "spp": args.spp,
            "seed": args.seed,
            "width": width,
            "height": height,
            "max_depth": integ.get("max_depth"),
            "integrator": integ,
            "defaults": xml_defaults(text),
            "overrides": {"spp": args.spp},
            "mitsuba_version": mi.__version__,
            "drjit_version": dr.__version__,
            "drjit_libllvm_path": (os.environ.get("DRJIT_LIBLLVM_PATH")
                                   if variant.startswith("llvm") else None),
            "wall_time_s": round(wall, 2),
            "cpu_count": os.cpu_count(),
            "date": date,
            "files": {"mean": mean_path.name, "variance_of_mean": var_path.name},
            "variance": vinfo,
            "stats": st,
        }
        save_manifest(manifest)
        results[name] = "rendered"

    log("summary: " + ", ".join(f"{k}: {v}" for k, v in results.items()))
    return 1 if any(v in ("refused", "failed") for v in results.values()) else 0


if __name__ == "__main__":
    sys.exit(main())

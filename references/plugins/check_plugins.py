#!/usr/bin/env python3
"""Validate the Python BSDF plugins orennayar.py and minnaert.py in Mitsuba.

    .venv/bin/python references/plugins/check_plugins.py [--variants scalar_rgb llvm_ad_rgb]
                                                         [--furnace-samples 2097152]

(This file lives next to the plugins, so make_references.py imports it too; it has no
register() and does all its work under `if __name__ == "__main__"`.)

Checks, each printed with its numbers:

1. Lambert limit.  orennayar (all four variants) with sigma = 0 and minnaert with k = 1 against
   Mitsuba's own `diffuse`: eval and pdf on a grid of direction pairs (also below the surface),
   and sample() weights (orennayar only: both use Mitsuba's cosine-hemisphere warp, so the same
   random numbers give the same directions).
2. Rust formulas.  The Rust eval code (crates/pt-bsdf/src/oren_nayar.rs, minnaert.rs) written a
   second time in plain numpy (float64, Rust notation: wo = viewer, wi = light, f without the
   cosine) below; the plugin's eval must equal f * cos_i.  Max absolute and relative differences
   over a grid of direction pairs x sigma/k values, per Mitsuba variant.  Both implement the Rust
   code: the point is to catch Dr.Jit translation slips.
3. White furnace.  Mean of the sample() weight over many samples (llvm variant; stderr from the
   sample variance) at several viewing angles, against numpy Gauss-Legendre quadrature of f cos_i
   over the hemisphere, and against the analytic albedo where there is one (EON, Minnaert).
   Also max |weight - eval/pdf| over the samples (sample/eval/pdf consistency).
4. Chi^2 (mitsuba.chi2) of sample() against pdf() for minnaert k = 0.6, 1.8 and orennayar.

Exit status 1 if a check fails its tolerance.
"""

import argparse
import importlib.util
import math
import os
import sys
from pathlib import Path

import numpy as np

PLUGIN_DIR = Path(__file__).resolve().parent
PI = math.pi
RHO = (0.9, 0.5, 0.1)               # per-lane nonlinear terms (EON rho_ms, Full rho^2) differ
FURNACE_RHO = (1.0, 0.7, 0.3)       # lane 0 = 1: EON's albedo must be exactly 1 there
SIGMAS = (0.0, 0.1, 0.3, 0.5, 0.6, 0.8, 1.2, 3.0)
KS = (0.2, 0.6, 1.0, 1.5, 1.8, 3.0)
VARIANTS = ("qualitative", "full", "fujii", "eon")


# ------------------------------------------------------------------------------------------
# numpy re-implementation of the Rust eval (f without cosine), Rust notation
# ------------------------------------------------------------------------------------------

C1_FON = 0.5 - 2.0 / (3.0 * PI)
C2_FON = 2.0 / 3.0 - 28.0 / (15.0 * PI)


def np_qualitative_ab(sigma):
    s2 = sigma * sigma
    return 1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09)


def np_fon_albedo(mu, r):
    mu = np.clip(mu, 0.0, 1.0)
    a_f = 1.0 / (1.0 + C1_FON * r)
    b_f = r * a_f
    si = np.sqrt(np.maximum(1.0 - mu * mu, 0.0))
    g = si * (np.arccos(mu) - si * mu) + 2.0 / 3.0 * (si * mu * (1 + si + si * si) / (1 + si) - si)
    return a_f + b_f / PI * g


def np_orennayar_f(rho, sigma, variant, wo, wi):
    """rho (3,), wo/wi (N, 3): f (N, 3) as OrenNayar::new(rho, sigma, variant).eval(wo, wi)."""
    rho = np.asarray(rho, dtype=np.float64)[None, :]
    sigma = max(sigma, 0.0)
    if variant in ("qualitative", "full"):
        a, b = np_qualitative_ab(sigma)
    else:
        qa, qb = np_qualitative_ab(sigma)
        r = min(max(qb / qa, 0.0), 1.0)
        a, b = 1.0 / (1.0 + C1_FON * r), r
    zo, zi = wo[:, 2], wi[:, 2]
    above = (zo > 0) & (zi > 0)
    cos_i, cos_o = np.minimum(zi, 1.0), np.minimum(zo, 1.0)
    s = np.sum(wi * wo, axis=1) - cos_i * cos_o
    with np.errstate(divide="ignore", invalid="ignore"):
        if variant == "qualitative":
            t = np.maximum(cos_i, cos_o)
            f = rho * ((a + b * np.maximum(s, 0.0) / t) / PI)[:, None]
        elif variant in ("fujii", "eon"):
            r = b
            s_over_t = np.where(s > 0, s / np.maximum(cos_i, cos_o), s)
            f = rho * (a / PI * np.maximum(1.0 + r * s_over_t, 0.0))[:, None]
            if variant == "eon":
                e_o, e_i = np_fon_albedo(cos_o, r), np_fon_albedo(cos_i, r)
                avg = a * (1.0 + C2_FON * r)
                eps = 1e-7
                lobe = (np.maximum(1 - e_o, eps) * np.maximum(1 - e_i, eps)
                        / max(1 - avg, eps) / PI)
                rho_ms = rho * rho * avg / np.maximum(1.0 - rho * (1.0 - avg), eps)
                f = f + rho_ms * lobe[:, None]
        else:  # full
            s2 = sigma * sigma
            th_i, th_o = np.arccos(cos_i), np.arccos(cos_o)
            al, be = np.maximum(th_i, th_o), np.minimum(th_i, th_o)
            sin_i = np.sqrt(np.maximum(1 - zi * zi, 0.0))
            sin_o = np.sqrt(np.maximum(1 - zo * zo, 0.0))
            den = sin_i * sin_o
            cphi = np.where(den > 1e-6, np.clip(s / den, -1.0, 1.0), 0.0)
            k = 0.45 * s2 / (s2 + 0.09)
            tbp = 2 * be / PI
            c2 = np.where(cphi >= 0, k * np.sin(al), k * (np.sin(al) - tbp ** 3))
            c3 = 0.125 * s2 / (s2 + 0.09) * (4 * al * be / PI ** 2) ** 2
            tan_b = np.sin(be) / np.maximum(np.cos(be), 1e-7)
            h = 0.5 * (al + be)
            tan_h = np.sin(h) / np.maximum(np.cos(h), 1e-7)
            l1 = (a + cphi * c2 * tan_b + (1 - np.abs(cphi)) * c3 * tan_h) / PI
            l2 = 0.17 / PI * s2 / (s2 + 0.13) * (1 - cphi * tbp * tbp)
            f = np.maximum(rho * l1[:, None] + rho * rho * l2[:, None], 0.0)
    return np.where(above[:, None], f, 0.0)


def np_minnaert_f(rho, k, wo, wi):
    rho = np.asarray(rho, dtype=np.float64)[None, :]
    zo, zi = wo[:, 2], wi[:, 2]
    above = (zo > 0) & (zi > 0)
    ci = np.power(np.clip(zi, 1e-12, 1.0), k - 1.0)
    view = np.power(np.clip(zo, 0.0, 1.0), k - 1.0) if k >= 1.0 else np.ones_like(zo)
    f = rho * ((k + 1) / (2 * PI) * ci * view)[:, None]
    return np.where(above[:, None], f, 0.0)


def np_eon_albedo(rho, sigma, mu):
    qa, qb = np_qualitative_ab(sigma)
    r = min(max(qb / qa, 0.0), 1.0)
    a = 1.0 / (1.0 + C1_FON * r)
    e = np_fon_albedo(np.array([mu]), r)[0]
    avg = a * (1 + C2_FON * r)
    rho = np.asarray(rho, dtype=np.float64)
    rho_ms = rho * rho * avg / np.maximum(1 - rho * (1 - avg), 1e-7)
    return rho * e + rho_ms * (1 - e)


def np_albedo_quadrature(fn, theta_o_deg, n=256):
    """Integral of f(wo, wi) cos_i over the upper hemisphere of wi, wo at theta_o (azimuth 0).
    Gauss-Legendre in mu = cos_i on [0, cos_o] and [cos_o, 1] (kink where theta_i = theta_o)
    and in phi on [0, pi/2] and [pi/2, pi] (kink at cos_phi = 0), doubled by symmetry."""
    x, w = np.polynomial.legendre.leggauss(n)
    to = math.radians(theta_o_deg)
    wo1 = np.array([math.sin(to), 0.0, math.cos(to)])
    total = np.zeros(3)
    mu_edges = [0.0, wo1[2], 1.0]
    for m0, m1 in zip(mu_edges[:-1], mu_edges[1:]):
        if m1 - m0 < 1e-12:
            continue
        mu = 0.5 * (m1 - m0) * x + 0.5 * (m1 + m0)
        wmu = 0.5 * (m1 - m0) * w
        for p0, p1 in ((0.0, PI / 2), (PI / 2, PI)):
            ph = 0.5 * (p1 - p0) * x + 0.5 * (p1 + p0)
            wph = 0.5 * (p1 - p0) * w
            MU, PH = np.meshgrid(mu, ph, indexing="ij")
            W = np.outer(wmu, wph).ravel()
            st = np.sqrt(1 - MU.ravel() ** 2)
            wi = np.stack([st * np.cos(PH.ravel()), st * np.sin(PH.ravel()), MU.ravel()], axis=1)
            wo = np.broadcast_to(wo1, wi.shape)
            total += 2.0 * np.sum(fn(wo, wi) * (wi[:, 2] * W)[:, None], axis=0)
    return total


# ------------------------------------------------------------------------------------------
# Mitsuba side
# ------------------------------------------------------------------------------------------

def load_plugins(mi):
    mods = []
    for name in ("orennayar", "minnaert"):
        spec = importlib.util.spec_from_file_location(f"check_{name}", PLUGIN_DIR / f"{name}.py")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        mods.append(mod)
    return mods


def direction_grid():
    """All pairs (viewer, light) from a set of polar angles (some below the surface, some at
    grazing) and relative azimuths, the viewer at azimuth 37 degrees."""
    th = np.radians([0.0, 0.05, 10, 30, 45, 60, 75, 85, 89, 89.9, 95, 180])
    dphi = np.radians([0, 30, 60, 89, 90, 91, 120, 150, 180, 250])
    T_o, T_i, D = np.meshgrid(th, th, dphi, indexing="ij")
    T_o, T_i, D = T_o.ravel(), T_i.ravel(), D.ravel()
    p0 = math.radians(37.0)

    def vec(t, p):
        return np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=1)

    return vec(T_o, np.full_like(T_o, p0)), vec(T_i, p0 + D)


def mi_eval(mi, dr, bsdf, wv, wl):
    """eval and pdf at viewer wv / light wl (numpy (N, 3)); returns (N, 3), (N,)."""
    ctx = mi.BSDFContext()
    if mi.variant().startswith("scalar"):
        E, P = [], []
        si = dr.zeros(mi.SurfaceInteraction3f)
        for a, b in zip(wv, wl):
            si.wi = mi.Vector3f(*map(float, a))
            w = mi.Vector3f(*map(float, b))
            e = bsdf.eval(ctx, si, w)
            E.append([e[0], e[1], e[2]])
            P.append(float(bsdf.pdf(ctx, si, w)))
        return np.array(E, dtype=np.float64), np.array(P, dtype=np.float64)
    f32 = lambda x: x.astype(np.float32)  # noqa: E731
    si = dr.zeros(mi.SurfaceInteraction3f, len(wv))
    si.wi = mi.Vector3f(f32(wv[:, 0]), f32(wv[:, 1]), f32(wv[:, 2]))
    w = mi.Vector3f(f32(wl[:, 0]), f32(wl[:, 1]), f32(wl[:, 2]))
    return mi_color_np(bsdf.eval(ctx, si, w)), np.array(bsdf.pdf(ctx, si, w), dtype=np.float64)


def mi_color_np(c):
    """A JIT Color3f of width N as a float64 (N, 3) array."""
    return np.array(c, dtype=np.float64).reshape(3, -1).T


def bsdf_dict(kind, rho, **kw):
    d = {"type": kind, "reflectance": {"type": "rgb", "value": list(rho)}}
    d.update(kw)
    return d


def check_lambert_and_rust(mi, dr, variant, fails):
    mi.set_variant(variant)
    for mod in load_plugins(mi):
        mod.register()
    wv, wl = direction_grid()
    if variant.startswith("scalar"):  # the scalar Python loop is slow: every 3rd pair
        wv, wl = wv[::3], wl[::3]
    # Mitsuba stores directions in float32: give numpy the same (rounded) inputs, so that only
    # the arithmetic differs (s = wi.wo - cos_i cos_o cancels badly near the normal).
    wv, wl = (x.astype(np.float32).astype(np.float64) for x in (wv, wl))
    cos_l = wl[:, 2]
    print(f"\n== {variant}: {len(wv)} direction pairs (viewer, light), rho = {RHO} ==")

    # 1. Lambert limit
    lam = mi.load_dict(bsdf_dict("diffuse", RHO))
    e_l, p_l = mi_eval(mi, dr, lam, wv, wl)
    print("1. Lambert limit: max |plugin - diffuse| (eval incl. cosine, pdf)")
    for name, d in ([(f"orennayar {v} sigma=0", bsdf_dict("orennayar", RHO, sigma=0.0, variant=v))
                     for v in VARIANTS] + [("minnaert k=1", bsdf_dict("minnaert", RHO, k=1.0))]):
        b = mi.load_dict(d)
        e, p = mi_eval(mi, dr, b, wv, wl)
        de, dp = np.abs(e - e_l).max(), np.abs(p - p_l).max()
        ok = de < 1e-6 and dp < 1e-6
        print(f"   {name:28s} eval {de:.3e}  pdf {dp:.3e}  {'ok' if ok else 'FAIL'}")
        if not ok:
            fails.append(f"{variant} lambert {name}")
    if not variant.startswith("scalar"):
        # sample(): orennayar uses the same warp as diffuse, so the same directions
        n = 1 << 14
        rng = np.random.default_rng(3)
        u = rng.random((3, n)).astype(np.float32)
        ctx = mi.BSDFContext()
        for th in (0.0, 40.0, 80.0):
            si = dr.zeros(mi.SurfaceInteraction3f, n)
            t = math.radians(th)
            si.wi = mi.Vector3f(math.sin(t), 0.0, math.cos(t))
            bs_l, w_l = lam.sample(ctx, si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
            worst = 0.0
            for v in VARIANTS:
                b = mi.load_dict(bsdf_dict("orennayar", RHO, sigma=0.0, variant=v))
                bs, w = b.sample(ctx, si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
                worst = max(worst, np.abs(mi_color_np(w) - mi_color_np(w_l)).max(),
                            np.abs(np.array(bs.pdf) - np.array(bs_l.pdf)).max())
            print(f"   sample() at theta_view={th:4.1f}: max |weight, pdf diff| over the 4 "
                  f"variants {worst:.3e}")
            if worst > 1e-5:
                fails.append(f"{variant} lambert sample {th}")

    # 2. Rust formulas in numpy
    print("2. plugin eval vs numpy port of the Rust eval (f * cos_light): max abs / max rel diff")
    rows = []
    for v in VARIANTS:
        for s in SIGMAS:
            rows.append((f"orennayar {v:11s} sigma={s:<4}",
                         bsdf_dict("orennayar", RHO, sigma=s, variant=v),
                         lambda wo, wi, v=v, s=s: np_orennayar_f(RHO, s, v, wo, wi)))
    for k in KS:
        rows.append((f"minnaert k={k:<4}", bsdf_dict("minnaert", RHO, k=k),
                     lambda wo, wi, k=k: np_minnaert_f(RHO, k, wo, wi)))
    worst_abs = worst_rel = 0.0
    for name, d, fn in rows:
        b = mi.load_dict(d)
        e, p = mi_eval(mi, dr, b, wv, wl)
        ref = fn(wv, wl) * np.maximum(cos_l, 0.0)[:, None]
        da = np.abs(e - ref)
        rel = (da / np.maximum(np.abs(ref), 1e-3)).max()
        worst_abs, worst_rel = max(worst_abs, da.max()), max(worst_rel, rel)
        # pdf: cosine-weighted (orennayar) / cos^k (minnaert), 0 unless both above
        above = (wv[:, 2] > 0) & (wl[:, 2] > 0)
        if name.startswith("minnaert"):
            kk = d["k"]
            pref = np.where(above, (kk + 1) / (2 * PI) * np.power(np.clip(wl[:, 2], 0, 1), kk), 0)
        else:
            pref = np.where(above, wl[:, 2] / PI, 0.0)
        dp = np.abs(p - pref).max()
        ok = rel < 2e-4 and dp < 1e-5
        print(f"   {name:36s} abs {da.max():.3e}  rel {rel:.3e}  (max ref {ref.max():.4f})  "
              f"pdf {dp:.2e}  {'ok' if ok else 'FAIL'}")
        if not ok:
            fails.append(f"{variant} rust {name}")
    print(f"   worst over all: abs {worst_abs:.3e}, rel {worst_rel:.3e}")


def check_furnace(mi, dr, n, fails):
    mi.set_variant("llvm_ad_rgb")
    for mod in load_plugins(mi):
        mod.register()
    print(f"\n== white furnace (llvm_ad_rgb), {n} samples per angle, rho = {FURNACE_RHO} ==")
    print("   mean of sample() weight vs numpy quadrature of f cos; z = diff / stderr; "
          "analytic albedo where known; max |weight - eval/pdf|")
    configs = [("orennayar", v, s) for v, s in (("qualitative", 0.5), ("qualitative", 1.2),
                                                ("full", 0.6), ("full", 1.2),
                                                ("fujii", 0.6), ("fujii", 1.2),
                                                ("eon", 0.8), ("eon", 1.2))]
    configs += [("minnaert", None, k) for k in (0.6, 1.8, 3.0)]
    ctx = mi.BSDFContext()
    sampler = np.random.default_rng(11)
    for kind, v, p in configs:
        if kind == "orennayar":
            b = mi.load_dict(bsdf_dict("orennayar", FURNACE_RHO, sigma=p, variant=v))
            fn = lambda wo, wi, v=v, p=p: np_orennayar_f(FURNACE_RHO, p, v, wo, wi)  # noqa: E731
            label = f"orennayar {v} sigma={p}"
        else:
            b = mi.load_dict(bsdf_dict("minnaert", FURNACE_RHO, k=p))
            fn = lambda wo, wi, p=p: np_minnaert_f(FURNACE_RHO, p, wo, wi)  # noqa: E731
            label = f"minnaert k={p}"
        print(f"   {label}")
        for th in (0.0, 30.0, 60.0, 80.0, 89.0):
            t = math.radians(th)
            u = sampler.random((3, n)).astype(np.float32)
            si = dr.zeros(mi.SurfaceInteraction3f, n)
            si.wi = mi.Vector3f(math.sin(t), 0.0, math.cos(t))
            bs, w = b.sample(ctx, si, mi.Float(u[0]), mi.Point2f(u[1], u[2]))
            w_np = mi_color_np(w)
            e = mi_color_np(b.eval(ctx, si, bs.wo))
            pdf = np.array(bs.pdf, dtype=np.float64)
            good = pdf > 0
            cons = np.abs(w_np[good] - e[good] / pdf[good, None]).max() if good.any() else 0.0
            mean = w_np.mean(axis=0)
            se = w_np.std(axis=0, ddof=1) / math.sqrt(n)
            quad = np_albedo_quadrature(fn, th)
            if se.max() > 1e-7 * np.abs(mean).max():
                zs = f"z {np.array2string((mean - quad) / se, precision=2)}"
            else:  # constant weights (normal view for orennayar; minnaert's exact sampler)
                zs = f"|diff| {np.abs(mean - quad).max():.1e} (constant weights)"
            extra = ""
            if kind == "orennayar" and v == "eon":
                extra = f" analytic {np.array2string(np_eon_albedo(FURNACE_RHO, p, math.cos(t)), precision=5)}"
            elif kind == "minnaert":
                vf = math.cos(t) ** (p - 1) if p >= 1 else 1.0
                extra = f" analytic {np.array2string(np.array(FURNACE_RHO) * vf, precision=5)}"
            print(f"     theta={th:4.1f}  MC {np.array2string(mean, precision=5)} "
                  f"+- {se.max():.1e}  quad {np.array2string(quad, precision=5)}  "
                  f"{zs}{extra}  cons {cons:.1e}")
            # 5 sigma, or 1e-4 absolute where the weights are (almost) constant
            if np.any(np.abs(mean - quad) > np.maximum(5 * se, 1e-4)) or cons > 1e-4 * max(1, np.abs(w_np).max()):
                fails.append(f"furnace {label} theta={th}")


def check_chi2(mi, dr, fails):
    mi.set_variant("llvm_ad_rgb")
    for mod in load_plugins(mi):
        mod.register()
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain
    print("\n== chi^2 test of sample() against pdf() (llvm_ad_rgb) ==")
    for kind, extra in (("minnaert", '<float name="k" value="0.6"/>'),
                        ("minnaert", '<float name="k" value="1.8"/>'),
                        ("orennayar", '<float name="sigma" value="0.8"/><string name="variant" value="eon"/>')):
        for th in (40.0,):  # (both samplers ignore the viewing direction)
            t = math.radians(th)
            sample_func, pdf_func = BSDFAdapter(kind, extra, wi=[math.sin(t), 0, math.cos(t)])
            chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func,
                                 pdf_func=pdf_func, sample_dim=3)
            ok = chi2.run()
            print(f"   {kind} {extra} theta={th}: {'passed' if ok else 'FAILED'} "
                  f"(p-value {getattr(chi2, 'p_value', float('nan')):.3g})")
            if not ok:
                fails.append(f"chi2 {kind} {extra} {th}")
                print(chi2.messages)


def main():
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", "libLLVM.so.19.1")
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variants", nargs="+", default=["scalar_rgb", "llvm_ad_rgb"])
    ap.add_argument("--furnace-samples", type=int, default=1 << 21)
    ap.add_argument("--skip-furnace", action="store_true")
    ap.add_argument("--skip-chi2", action="store_true")
    args = ap.parse_args()
    import drjit as dr
    import mitsuba as mi
    print(f"Mitsuba {mi.__version__}, Dr.Jit {dr.__version__}")
    fails = []
    for v in args.variants:
        check_lambert_and_rust(mi, dr, v, fails)
    if not args.skip_furnace:
        check_furnace(mi, dr, args.furnace_samples, fails)
    if not args.skip_chi2:
        check_chi2(mi, dr, fails)
    print("\nRESULT:", "all checks passed" if not fails else f"{len(fails)} FAILED: {fails}")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())

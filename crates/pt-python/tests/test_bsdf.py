"""BSDFs from Python against the closed forms the Rust unit tests assert (pt-bsdf's
lambert.rs, conductor.rs, oren_nayar.rs, minnaert.rs), and the identity weight = f cos / pdf
for sampled directions. f32 arithmetic: tolerances are a few f32 ulps of the value (1e-6
relative), far below any formula or parameter mistake."""

import math

import numpy as np
import pytest

import pt_renderer as pt


def unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def test_lambert_value_pdf_and_weight():
    # lambert.rs closed_form_value_and_weight: f = R / pi, pdf = cos_i / pi, weight = R.
    b = pt.bsdf("diffuse", reflectance=(0.2, 0.5, 0.8))
    wo, wi = unit([0.3, 0.1, 0.9]), unit([-0.5, 0.2, 0.4])
    f = b.eval(wo, wi)[0]
    assert np.allclose(f, np.array([0.2, 0.5, 0.8]) / math.pi, rtol=1e-6)
    assert b.pdf(wo, wi)[0] == pytest.approx(wi[2] / math.pi, rel=1e-6)
    s = b.sample(wo, u=[[0.5, 0.25, 0.75]])
    assert s["valid"][0] and not s["delta"][0]
    assert np.allclose(s["weight"][0], [0.2, 0.5, 0.8], rtol=1e-5)
    # Below the surface: black, zero density.
    assert not b.eval(wo, -wi).any() and b.pdf(wo, -wi)[0] == 0.0
    assert np.allclose(b.eval(wo, wi, cosine=True)[0], f * wi[2], rtol=1e-6)


def test_conductor_normal_incidence():
    # conductor.rs gold_like_normal_incidence: eta 0.2, k 3.4 -> R = 12.2 / 13.
    b = pt.bsdf("conductor", eta=0.2, k=3.4)
    s = b.sample([0, 0, 1], u=[[0.3, 0.0, 0.0]])
    assert s["delta"][0] and s["pdf"][0] == 1.0
    assert np.allclose(s["wi"][0], [0, 0, 1])
    assert np.allclose(s["weight"][0], 12.2 / 13.0, rtol=1e-6)


def test_oren_nayar_qualitative_closed_form():
    # oren_nayar.rs qualitative_closed_form_at_a_known_configuration: theta_i 60, theta_o 30,
    # same azimuth: f = (A + B sin 60 tan 30) / pi with Oren & Nayar's (1994) A and B.
    sigma = 0.5
    b = pt.bsdf("orennayar", reflectance=1.0, sigma=sigma, variant="qualitative")
    t_i, t_o = math.radians(60), math.radians(30)
    wi = [math.sin(t_i), 0, math.cos(t_i)]
    wo = [math.sin(t_o), 0, math.cos(t_o)]
    s2 = sigma * sigma
    a, bb = 1 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09)
    expect = (a + bb * math.sin(t_i) * math.tan(t_o)) / math.pi
    assert b.eval(wo, wi)[0, 0] == pytest.approx(expect, abs=1e-6)


def test_minnaert_value_and_pdf():
    # minnaert.rs: f = R (k+1)/(2 pi) cos_i^(k-1) cos_o^(k-1), pdf = (k+1)/(2 pi) cos_i^k.
    k, r = 1.5, 0.7
    b = pt.bsdf("minnaert", reflectance=r, k=k)
    wo, wi = unit([0.2, -0.3, 0.8]), unit([-0.4, 0.1, 0.6])
    expect = r * (k + 1) / (2 * math.pi) * wi[2] ** (k - 1) * wo[2] ** (k - 1)
    assert b.eval(wo, wi)[0, 1] == pytest.approx(expect, rel=1e-5)
    assert b.pdf(wo, wi)[0] == pytest.approx((k + 1) / (2 * math.pi) * wi[2] ** k, rel=1e-5)


@pytest.mark.parametrize(
    "model, params",
    [
        ("roughconductor", dict(alpha=0.2, material="Au")),
        ("roughconductor", dict(alpha_u=0.05, alpha_v=0.4, distribution="ggx")),
        ("roughplastic", dict(alpha=0.3)),
        ("roughdielectric", dict(alpha=0.25, int_ior="bk7")),
        ("orennayar", dict(sigma=0.4, variant="eon")),
    ],
)
def test_sampled_weight_is_f_cos_over_pdf(model, params):
    """For every sampled non-delta direction, weight = f |cos| / pdf from eval and pdf: the three
    routines describe one distribution (a wrong pdf fails this at once)."""
    b = pt.bsdf(model, **params)
    wo = unit([0.5, 0.2, 0.6])
    s = b.sample(wo, n=2000, seed=7)
    ok = s["valid"] & ~s["delta"] & (s["pdf"] > 1e-3)
    assert ok.sum() > 1000
    f = b.eval(wo, s["wi"][ok])
    p = b.pdf(wo, s["wi"][ok])
    # Mixtures (plastic, dielectric) choose a lobe with a probability; the sample's pdf is the
    # mixture's, which pdf() returns too.
    assert np.allclose(p, s["pdf"][ok], rtol=2e-4, atol=1e-6)
    expect = f * np.abs(s["wi"][ok][:, 2:3]) / p[:, None]
    assert np.allclose(s["weight"][ok], expect, rtol=2e-3, atol=1e-6)


def test_spectral_bsdf_at_wavelengths():
    """A spectral conductor reads the named material's eta and k at each row's wavelength:
    gold reflects far more at 700 nm than at 450 nm, and rows are independent."""
    b = pt.bsdf("conductor", material="Au", mode="spectral")
    assert b.mode == "spectral"
    s = b.sample(np.tile([0, 0, 1.0], (2, 1)), u=[[0.5, 0, 0], [0.5, 0, 0]], wavelengths=[450.0, 700.0])
    r450, r700 = s["weight"][:, 0]
    assert 0.3 < r450 < 0.5 and r700 > 0.9
    one = b.sample([0, 0, 1.0], u=[[0.5, 0, 0]], wavelengths=700.0)
    assert one["weight"][0, 0] == r700


def test_models_listing():
    models = pt.bsdf_models()
    assert "roughconductor" in models and "alpha" in models["roughconductor"]
    assert "twosided" in models
    b = pt.bsdf("diffuse", two_sided=True)
    assert b.eval([0, 0, -1], [0, 0, -1])[0, 0] == pytest.approx(0.5 / math.pi, rel=1e-6)

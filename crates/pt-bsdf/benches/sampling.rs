//! BSDF sampling throughput (million samples per second, one thread): `sample` plus `pdf`
//! and `eval` of the sampled direction, as the integrator calls them at every vertex.
//! Run: `cargo bench -p pt-bsdf --bench sampling`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use pt_bsdf::{
    Bsdf, Conductor, Dielectric, Distribution, Lambert, Microfacet, Minnaert, OrenNayar,
    OrenNayarVariant, RoughConductor, RoughDielectric,
};
use pt_math::{Vec2, Vec3};
use pt_spectrum::SampledSpectrum;
use std::hint::black_box;

fn models() -> Vec<(&'static str, Bsdf)> {
    let rho = SampledSpectrum::from_rgb([0.7, 0.5, 0.3]);
    let (eta, k) = (
        SampledSpectrum::from_rgb([0.14, 0.37, 1.44]),
        SampledSpectrum::from_rgb([3.98, 2.39, 1.60]),
    );
    let one = SampledSpectrum::from_rgb([1.0; 3]);
    vec![
        ("lambert", Bsdf::Lambert(Lambert::new(rho))),
        (
            "orennayar_qualitative",
            Bsdf::OrenNayar(OrenNayar::new(rho, 0.5, OrenNayarVariant::Qualitative)),
        ),
        (
            "orennayar_eon",
            Bsdf::OrenNayar(OrenNayar::new(rho, 0.5, OrenNayarVariant::Eon)),
        ),
        ("minnaert", Bsdf::Minnaert(Minnaert::new(rho, 1.8))),
        ("conductor", Bsdf::Conductor(Conductor::new(eta, k, one))),
        (
            "roughconductor_ggx",
            Bsdf::RoughConductor(RoughConductor::new(
                eta,
                k,
                one,
                Microfacet::new(Distribution::Ggx, 0.2, 0.2),
            )),
        ),
        (
            "roughconductor_beckmann",
            Bsdf::RoughConductor(RoughConductor::new(
                eta,
                k,
                one,
                Microfacet::new(Distribution::Beckmann, 0.2, 0.2),
            )),
        ),
        ("dielectric", Bsdf::Dielectric(Dielectric::new(1.5))),
        (
            "roughdielectric_ggx",
            Bsdf::RoughDielectric(RoughDielectric::new(
                1.5,
                Microfacet::new(Distribution::Ggx, 0.2, 0.2),
            )),
        ),
    ]
}

fn bench(c: &mut Criterion) {
    const N: usize = 1 << 14;
    // Pre-generated inputs: viewer directions over the upper hemisphere and random numbers.
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let inputs: Vec<(Vec3, f32, Vec2)> = (0..N)
        .map(|_| {
            let (z, phi) = (rnd().max(1e-3), 2.0 * std::f32::consts::PI * rnd());
            let r = (1.0 - z * z).sqrt();
            (
                Vec3::new(r * phi.cos(), r * phi.sin(), z),
                rnd(),
                Vec2::new(rnd(), rnd()),
            )
        })
        .collect();
    let mut g = c.benchmark_group("bsdf_sample_eval_pdf");
    g.throughput(Throughput::Elements(N as u64));
    for (name, m) in models() {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut acc = 0.0f32;
                for &(wo, ul, u) in &inputs {
                    if let Some(bs) = m.sample(wo, ul, u) {
                        acc += bs.weight.0.x + m.pdf(wo, bs.wi) + m.eval(wo, bs.wi).0.y;
                    }
                }
                black_box(acc)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

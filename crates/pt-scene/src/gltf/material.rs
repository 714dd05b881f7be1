//! Materials: a glTF material becomes one BSDF (the metallic-roughness model, or a
//! transmissive or thin-film model, blends of those, wrapped in `twosided`, `mask` and
//! `normalmap` as the module doc describes), an emission and an interior medium.

use super::texture::{self, Encoding};
use super::{Ctx, GltfError};
use crate::ir::{
    BitmapDesc, BsdfDesc, BsdfKind, FilmBaseDesc, MediumDesc, MicrofacetDesc,
    MicrofacetDistribution, PhaseDesc, SourceLoc, SpectrumDesc, TextureChannel, TextureDesc,
    VolumeDesc,
};
use gltf::material::AlphaMode;
use std::sync::Arc;

/// Below this GGX alpha a transmissive or thin-film model is taken as smooth.
const SMOOTH_ALPHA: f32 = 1e-3;

/// The id of glTF's default material.
const DEFAULT_ID: &str = "gltf-default";

/// What a glTF material becomes.
pub(super) struct MappedMaterial {
    /// The BSDF (one per material; shapes index it).
    pub bsdf: BsdfDesc,
    /// Emitted radiance of every primitive with the material, if it emits.
    pub emission: Option<TextureDesc>,
    /// The medium inside (KHR_materials_volume).
    pub interior: Option<MediumDesc>,
}

impl MappedMaterial {
    /// Whether its primitives need tangents (a normal map around the BSDF).
    pub fn normal_mapped(&self) -> bool {
        matches!(self.bsdf.kind, BsdfKind::NormalMap { .. })
    }
}

/// The `pt info` lines of one material: what it maps to, the extensions used, notes.
#[derive(Default)]
struct Report {
    mapping: String,
    used: Vec<String>,
    notes: Vec<String>,
}

/// The material being mapped, with its names for messages.
struct Material<'r, 'd> {
    m: &'r gltf::Material<'d>,
    /// `materials[3]`.
    elem: String,
    /// `materials[3] 'name'`.
    label: String,
    loc: SourceLoc,
}

impl Material<'_, '_> {
    /// `kind` as a nested BSDF at the material's location.
    fn nest(&self, kind: BsdfKind) -> Box<BsdfDesc> {
        Box::new(BsdfDesc {
            loc: self.loc.clone(),
            id: None,
            kind,
        })
    }
}

/// The metallic-roughness model of a material, with its factors and textures.
struct Pbr {
    /// `GltfPbr` with its factors times textures.
    kind: BsdfKind,
    /// `baseColorFactor` (RGBA).
    base_color: [f32; 4],
    metallic: f32,
    roughness: f32,
    ior: f32,
    /// `baseColorTexture` (sRGB), whose alpha the opacity reads.
    base_color_texture: Option<Arc<BitmapDesc>>,
    /// Whether a texture is read (base colour or metallic-roughness).
    textured: bool,
}

/// Maps every material of the file (in index order), with the summary header.
pub(super) fn map_materials(
    cx: &mut Ctx,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
) -> Result<Vec<MappedMaterial>, GltfError> {
    cx.summary
        .push(format!("materials   {} (glTF)", doc.materials().len()));
    doc.materials()
        .map(|m| map_material(cx, doc, &m, buffers))
        .collect()
}

/// glTF's default material (for primitives without one): white, metallic 1, roughness 1,
/// two-sided as every opaque material.
pub(super) fn default_material(cx: &Ctx) -> MappedMaterial {
    let loc = cx.loc("default material".into());
    let kind = BsdfKind::GltfPbr {
        base_color: TextureDesc::constant(1.0),
        metallic: TextureDesc::constant(1.0),
        roughness: TextureDesc::constant(1.0),
        ior: 1.5,
    };
    MappedMaterial {
        bsdf: BsdfDesc {
            loc: loc.clone(),
            id: Some(DEFAULT_ID.into()),
            kind: BsdfKind::TwoSided {
                inner: Box::new(BsdfDesc {
                    loc,
                    id: None,
                    kind,
                }),
            },
        },
        emission: None,
        interior: None,
    }
}

/// Maps one material (see the module doc): the model, then the wrappers (two-sided, opacity
/// mask, normal map) from the inside out.
fn map_material(
    cx: &mut Ctx,
    doc: &gltf::Document,
    m: &gltf::Material,
    buffers: &[Vec<u8>],
) -> Result<MappedMaterial, GltfError> {
    let idx = m.index().unwrap_or(0);
    let elem = format!("materials[{idx}]");
    let label = format!(
        "{elem}{}",
        m.name().map(|n| format!(" '{n}'")).unwrap_or_default()
    );
    let mat = Material {
        m,
        loc: cx.loc(label.clone()),
        elem,
        label,
    };
    let mut r = Report::default();
    let pbr = metallic_roughness(cx, &mat, buffers, &mut r)?;
    let normal = normal_map(cx, &mat, buffers, &mut r)?;
    let emission = emission(cx, &mat, buffers, &mut r)?;
    if m.occlusion_texture().is_some() {
        // Ambient occlusion is a rasteriser's stand-in for what the path tracer computes.
        cx.warnings.push(format!(
            "{}: occlusionTexture ignored (a path tracer computes occlusion)",
            mat.label
        ));
    }
    let opacity = opacity(&mat, &pbr, &mut r);
    if m.ior().is_some() {
        r.used.push(format!("KHR_materials_ior (ior {})", pbr.ior));
    }
    let (kind, interior) = transmission(cx, &mat, &pbr, &mut r);
    let mut kind = iridescence(cx, doc, &mat, &pbr, kind, buffers, &mut r)?;
    if !matches!(
        kind,
        BsdfKind::Dielectric { .. }
            | BsdfKind::RoughDielectric { .. }
            | BsdfKind::ThinDielectric { .. }
    ) {
        // glTF's doubleSided only controls back-face culling in rasterisers; a path tracer sees
        // back faces anyway, so opaque materials shade both sides.
        kind = BsdfKind::TwoSided {
            inner: mat.nest(kind),
        };
    }
    kind = opacity.wrap(&mat, kind);
    if let Some((texture, scale)) = normal {
        kind = BsdfKind::NormalMap {
            texture: TextureDesc::Bitmap(texture),
            scale,
            gltf: true,
            inner: mat.nest(kind),
        };
    }
    cx.summary.push(format!("  {}: {}", mat.label, r.mapping));
    for u in &r.used {
        cx.summary.push(format!("      extension {u}"));
    }
    for nt in &r.notes {
        cx.summary.push(format!("      note: {nt}"));
    }
    Ok(MappedMaterial {
        bsdf: BsdfDesc {
            loc: mat.loc,
            id: Some(m.name().map_or(format!("material{idx}"), str::to_string)),
            kind,
        },
        emission,
        interior,
    })
}

/// `pbrMetallicRoughness` as `GltfPbr`: base colour = factor x texture, metallic = factor x
/// blue, roughness = factor x green of the metallic-roughness texture.
fn metallic_roughness(
    cx: &mut Ctx,
    mat: &Material,
    buffers: &[Vec<u8>],
    r: &mut Report,
) -> Result<Pbr, GltfError> {
    let pbr = mat.m.pbr_metallic_roughness();
    let bc = pbr.base_color_factor();
    let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
    let ior = mat.m.ior().unwrap_or(1.5);
    let base_color_texture = match pbr.base_color_texture() {
        Some(i) => texture::texture_of(
            cx,
            &i,
            Encoding::Srgb,
            buffers,
            &format!("{} baseColorTexture", mat.label),
        )?,
        None => None,
    };
    let mr_texture = match pbr.metallic_roughness_texture() {
        Some(i) => texture::texture_of(
            cx,
            &i,
            Encoding::Raw,
            buffers,
            &format!("{} metallicRoughnessTexture", mat.label),
        )?,
        None => None,
    };
    for (slot, t) in [
        ("baseColorTexture", &base_color_texture),
        ("metallicRoughnessTexture", &mr_texture),
    ] {
        if let Some(t) = t {
            r.notes.push(format!("{slot}: {}", texture::describe(t)));
        }
    }
    let base_color = match &base_color_texture {
        Some(t) => texture::scaled(
            TextureDesc::Bitmap(t.clone()),
            None,
            [bc[0], bc[1], bc[2]],
            0.0,
        ),
        None => TextureDesc::Constant(SpectrumDesc::Rgb([bc[0], bc[1], bc[2]])),
    };
    // One channel of the metallic-roughness texture times a factor, or the factor.
    let channel = |ch: TextureChannel, factor: f32| match &mr_texture {
        Some(t) => texture::scaled(TextureDesc::Bitmap(t.clone()), Some(ch), [factor; 3], 0.0),
        None => TextureDesc::constant(factor),
    };
    r.mapping = format!("gltf metallic-roughness: base colour {:?}, metallic {metallic}, roughness {roughness} (alpha {:.4}), dielectric ior {ior}", [bc[0], bc[1], bc[2]], roughness * roughness);
    Ok(Pbr {
        kind: BsdfKind::GltfPbr {
            base_color,
            metallic: channel(TextureChannel::Blue, metallic),
            roughness: channel(TextureChannel::Green, roughness),
            ior,
        },
        base_color: bc,
        metallic,
        roughness,
        ior,
        textured: base_color_texture.is_some() || mr_texture.is_some(),
        base_color_texture,
    })
}

/// `normalTexture` (raw data) and its `scale`.
fn normal_map(
    cx: &mut Ctx,
    mat: &Material,
    buffers: &[Vec<u8>],
    r: &mut Report,
) -> Result<Option<(Arc<BitmapDesc>, f32)>, GltfError> {
    let Some(nt) = mat.m.normal_texture() else {
        return Ok(None);
    };
    let scale = nt.scale();
    if !scale.is_finite() {
        return Err(cx.err(format!(
            "{}: normalTexture.scale must be finite, got {scale}",
            mat.elem
        )));
    }
    let what = format!("{} normalTexture", mat.label);
    let Some(t) = texture::normal_texture_of(cx, &nt, buffers, &what)? else {
        return Ok(None);
    };
    r.notes.push(format!(
        "normalTexture: {}, scale {scale}, tangent space from TANGENT (or generated from the uvs)",
        texture::describe(&t)
    ));
    Ok(Some((t, scale)))
}

/// The emitted radiance: `emissiveFactor` x `KHR_materials_emissive_strength` (x
/// `emissiveTexture`, sRGB, with its uv map); `None` when it is black.
fn emission(
    cx: &mut Ctx,
    mat: &Material,
    buffers: &[Vec<u8>],
    r: &mut Report,
) -> Result<Option<TextureDesc>, GltfError> {
    let m = mat.m;
    let texture = match m.emissive_texture() {
        Some(i) => texture::texture_of(
            cx,
            &i,
            Encoding::Srgb,
            buffers,
            &format!("{} emissiveTexture", mat.label),
        )?,
        None => None,
    };
    let strength = m.emissive_strength().unwrap_or(1.0);
    if m.emissive_strength().is_some() {
        r.used
            .push(format!("KHR_materials_emissive_strength ({strength})"));
    }
    let factor = m.emissive_factor();
    let emits = factor.iter().any(|c| *c > 0.0) && strength > 0.0;
    if !emits {
        return Ok(None);
    }
    let e = factor.map(|c| c * strength);
    if !e.iter().all(|c| c.is_finite() && *c >= 0.0) {
        return Err(cx.err(format!("{}: emissive must be finite and >= 0", mat.elem)));
    }
    r.notes.push(format!("emits radiance {e:?} (front side)"));
    Ok(Some(match texture {
        Some(t) => {
            r.notes.push(format!(
                "emissiveTexture: {}, times the emissive factor",
                texture::describe(&t)
            ));
            texture::scaled(TextureDesc::Bitmap(t), None, e, 0.0)
        }
        None => TextureDesc::Constant(SpectrumDesc::Rgb(e)),
    }))
}

/// Alpha as opacity (the renderer's `mask`: light meets the surface with probability
/// `opacity`, else passes straight through).
enum Opacity {
    /// No mask.
    Opaque,
    /// The same everywhere (no base colour texture), < 1.
    Constant(f32),
    /// Per texel: the factor's alpha times the base colour texture's alpha, compared with
    /// the cutoff in MASK mode.
    Textured {
        opacity: TextureDesc,
        cutoff: Option<f32>,
    },
}

impl Opacity {
    /// `kind` inside the mask, if there is one.
    fn wrap(self, mat: &Material, kind: BsdfKind) -> BsdfKind {
        let (opacity, cutoff) = match self {
            Opacity::Opaque => return kind,
            Opacity::Constant(o) => (TextureDesc::constant(o), None),
            Opacity::Textured { opacity, cutoff } => (opacity, cutoff),
        };
        BsdfKind::Mask {
            opacity,
            cutoff,
            inner: mat.nest(kind),
        }
    }
}

/// `alphaMode` BLEND: opacity = alpha; MASK: alpha >= alphaCutoff (default 0.5); alpha =
/// the factor's alpha (x the base colour texture's, read raw, per texel).
fn opacity(mat: &Material, pbr: &Pbr, r: &mut Report) -> Opacity {
    let mode = mat.m.alpha_mode();
    let a = pbr.base_color[3];
    let cutoff = mat.m.alpha_cutoff().unwrap_or(0.5);
    match (mode, &pbr.base_color_texture) {
        (AlphaMode::Opaque, _) => Opacity::Opaque,
        (_, Some(t)) => {
            let opacity = texture::scaled(
                TextureDesc::Bitmap(texture::as_raw(t)),
                Some(TextureChannel::Alpha),
                [a.clamp(0.0, 1.0); 3],
                0.0,
            );
            let cutoff = (mode == AlphaMode::Mask).then_some(cutoff);
            r.used.push(match cutoff {
                Some(c) => format!("alphaMode MASK: opacity 1 where {a} x texture alpha >= {c}, else 0, per texel (mask)"),
                None => format!("alphaMode BLEND: opacity {a} x texture alpha, per texel (mask)"),
            });
            Opacity::Textured { opacity, cutoff }
        }
        (_, None) => {
            let o = match mode {
                AlphaMode::Mask if a >= cutoff => 1.0,
                AlphaMode::Mask => 0.0,
                _ => a.clamp(0.0, 1.0),
            };
            r.used
                .push(format!("alphaMode {mode:?}: opacity {o} (mask)"));
            if o < 1.0 {
                Opacity::Constant(o)
            } else {
                Opacity::Opaque
            }
        }
    }
}

/// GGX roughness `alpha` on both axes.
fn ggx(alpha: f32) -> MicrofacetDesc {
    MicrofacetDesc {
        distribution: MicrofacetDistribution::Ggx,
        alpha_u: TextureDesc::constant(alpha),
        alpha_v: TextureDesc::constant(alpha),
    }
}

/// `KHR_materials_transmission` (with `KHR_materials_volume`): the transmissive model, blended
/// with the opaque one for a partial factor, and the interior medium; the opaque model
/// unchanged without transmission.
fn transmission(
    cx: &mut Ctx,
    mat: &Material,
    pbr: &Pbr,
    r: &mut Report,
) -> (BsdfKind, Option<MediumDesc>) {
    let m = mat.m;
    let Some(t) = m.transmission().filter(|t| t.transmission_factor() > 0.0) else {
        if m.volume().is_some() {
            r.notes
                .push("KHR_materials_volume without transmission has no effect".into());
        }
        return (pbr.kind.clone(), None);
    };
    let f = t.transmission_factor();
    if pbr.textured {
        r.notes
            .push("base colour / metallic-roughness textures ignored (transmissive)".into());
    }
    if t.transmission_texture().is_some() {
        cx.warnings.push(format!(
            "{}: transmissionTexture ignored (textures are not yet implemented)",
            mat.label
        ));
    }
    let (mut kind, interior) = match m.volume().filter(|v| v.thickness_factor() > 0.0) {
        Some(v) => (dielectric(pbr, r), volume_medium(mat, &v, r)),
        None => (thin_dielectric(pbr, r), None),
    };
    let bc = pbr.base_color;
    if bc[..3].iter().any(|c| (c - 1.0).abs() > 1e-6) {
        r.notes
            .push("baseColor tint of transmitted light ignored".into());
    }
    // A partial transmission: a blend of the opaque material and the transmissive one. glTF
    // mixes only the dielectric's diffuse base with the transmission lobe, under the same
    // specular layer, and leaves the metal part alone: the blend weight is f (1 - metallic),
    // and the specular layer is the opaque material's GGX reflection in one share and the
    // dielectric's Fresnel reflection in the other (the same ior and roughness, so nearly the
    // same lobe).
    let metallic = pbr.metallic;
    let w = f.min(1.0) * (1.0 - metallic.clamp(0.0, 1.0));
    if w < 1.0 {
        r.mapping = format!(
            "blend of {w:.4} x ({}) and {:.4} x (the opaque metallic-roughness material)",
            r.mapping,
            1.0 - w
        );
        r.notes.push(format!("transmissionFactor {f} with metallic {metallic}: blend weight f (1 - metallic) = {w} (approximates glTF's layering: see the module doc)"));
        kind = BsdfKind::Blend {
            weight: TextureDesc::constant(w),
            first: mat.nest(pbr.kind.clone()),
            second: mat.nest(kind),
        };
    }
    r.used
        .push(format!("KHR_materials_transmission (factor {f})"));
    (kind, interior)
}

/// Transmission through a volume: a smooth or GGX-rough dielectric of index `ior`.
fn dielectric(pbr: &Pbr, r: &mut Report) -> BsdfKind {
    let (ior, alpha) = (pbr.ior, pbr.roughness * pbr.roughness);
    let one = || TextureDesc::constant(1.0);
    if alpha < SMOOTH_ALPHA {
        r.mapping = format!("dielectric, ior {ior}");
        BsdfKind::Dielectric {
            int_ior: ior,
            ext_ior: 1.0,
            specular_reflectance: one(),
            specular_transmittance: one(),
        }
    } else {
        r.mapping = format!("roughdielectric GGX alpha {alpha:.4}, ior {ior}");
        BsdfKind::RoughDielectric {
            int_ior: ior,
            ext_ior: 1.0,
            microfacet: ggx(alpha),
            specular_reflectance: one(),
            specular_transmittance: one(),
        }
    }
}

/// glTF's thin-walled transmission (no volume): a thin dielectric slab, smooth.
fn thin_dielectric(pbr: &Pbr, r: &mut Report) -> BsdfKind {
    let ior = pbr.ior;
    r.mapping = format!("thindielectric (thin-walled: no volume), ior {ior}");
    if pbr.roughness * pbr.roughness >= SMOOTH_ALPHA {
        r.notes.push(format!(
            "roughness {} ignored (thin-walled transmission is smooth)",
            pbr.roughness
        ));
    }
    BsdfKind::ThinDielectric {
        int_ior: ior,
        ext_ior: 1.0,
        specular_reflectance: TextureDesc::constant(1.0),
        specular_transmittance: TextureDesc::constant(1.0),
    }
}

/// The Beer-Lambert medium of `KHR_materials_volume`: white light is `attenuationColor` after
/// `attenuationDistance`, so `exp(-sigma_t d) = c`; none for an infinite distance.
fn volume_medium(mat: &Material, v: &gltf::material::Volume, r: &mut Report) -> Option<MediumDesc> {
    let (d, c) = (v.attenuation_distance(), v.attenuation_color());
    let note = format!(
        "KHR_materials_volume (thicknessFactor {} only marks a volume)",
        v.thickness_factor()
    );
    if !(d.is_finite() && d > 0.0) {
        r.used.push(format!(
            "{note}: no attenuation (attenuationDistance infinite)"
        ));
        return None;
    }
    let sigma = c.map(|ci| {
        if ci > 0.0 {
            -ci.min(1.0).ln() / d
        } else {
            f32::MAX.sqrt()
        }
    });
    r.used.push(format!(
        "{note}: interior medium sigma_t = -ln({c:?})/{d} = {sigma:?} per m"
    ));
    // KHR_materials_volume's attenuation absorbs only.
    Some(MediumDesc {
        loc: mat.loc.clone(),
        sigma_t: SpectrumDesc::Rgb(sigma),
        albedo: VolumeDesc::Constant(SpectrumDesc::Constant(0.0)),
        phase: PhaseDesc::Isotropic,
        sample_emitters: true,
        density: None,
        emission: None,
    })
}

/// The parameters of `KHR_materials_iridescence`, read and checked.
struct Iridescence {
    /// `iridescenceFactor` (> 0).
    factor: f32,
    /// `iridescenceIor`.
    film_ior: f32,
    /// `iridescenceThicknessMaximum`, nm.
    max_nm: f32,
    /// The thickness: `max_nm`, or per texel from `iridescenceThicknessTexture`.
    thickness: TextureDesc,
    /// `iridescenceTexture`, whose red channel multiplies the factor.
    factor_texture: Option<Arc<BitmapDesc>>,
}

/// Reads `KHR_materials_iridescence` (`None` when absent or its factor is 0).
fn read_iridescence(
    cx: &mut Ctx,
    doc: &gltf::Document,
    mat: &Material,
    buffers: &[Vec<u8>],
    r: &mut Report,
) -> Result<Option<Iridescence>, GltfError> {
    let Some(ir) = mat.m.extension_value("KHR_materials_iridescence") else {
        return Ok(None);
    };
    let get = |key, default| texture::ext_f32(Some(ir), key, default);
    let factor = get("iridescenceFactor", 0.0);
    if factor <= 0.0 || factor.is_nan() {
        return Ok(None);
    }
    let film_ior = get("iridescenceIor", 1.3);
    let max_nm = get("iridescenceThicknessMaximum", 400.0);
    if !(max_nm.is_finite() && max_nm >= 0.0 && film_ior.is_finite() && film_ior >= 1.0) {
        return Err(cx.err(format!("{}: KHR_materials_iridescence needs thickness >= 0 and ior >= 1, got {max_nm}, {film_ior}", mat.elem)));
    }
    let mut thickness = TextureDesc::constant(max_nm);
    // iridescenceThicknessTexture: thickness = mix(min, max, green) per texel.
    if let Some(info) = ir.get("iridescenceThicknessTexture") {
        let min_nm = get("iridescenceThicknessMinimum", 100.0);
        if !(min_nm.is_finite() && min_nm >= 0.0) {
            return Err(cx.err(format!(
                "{}: iridescenceThicknessMinimum must be finite and >= 0, got {min_nm}",
                mat.elem
            )));
        }
        let what = format!("{} iridescenceThicknessTexture", mat.label);
        if let Some(t) = texture::json_texture(cx, doc, info, Encoding::Raw, buffers, &what)? {
            r.notes.push(format!("iridescenceThicknessTexture: thickness = {min_nm} + ({max_nm} - {min_nm}) x green, nm, per texel"));
            let (ch, scale) = (Some(TextureChannel::Green), [max_nm - min_nm; 3]);
            thickness = texture::scaled(TextureDesc::Bitmap(t), ch, scale, min_nm);
        }
    }
    let factor_texture = match ir.get("iridescenceTexture") {
        Some(info) => {
            let what = format!("{} iridescenceTexture", mat.label);
            texture::json_texture(cx, doc, info, Encoding::Raw, buffers, &what)?
        }
        None => None,
    };
    r.used.push(format!(
        "KHR_materials_iridescence (factor {factor}, ior {film_ior}, thickness max {max_nm} nm)"
    ));
    Ok(Some(Iridescence {
        factor,
        film_ior,
        max_nm,
        thickness,
        factor_texture,
    }))
}

/// `KHR_materials_iridescence`: the thin film instead of `kind`, or, for a partial factor, a
/// blend of `kind` and the film; `kind` unchanged without iridescence.
fn iridescence(
    cx: &mut Ctx,
    doc: &gltf::Document,
    mat: &Material,
    pbr: &Pbr,
    kind: BsdfKind,
    buffers: &[Vec<u8>],
    r: &mut Report,
) -> Result<BsdfKind, GltfError> {
    let Some(ir) = read_iridescence(cx, doc, mat, buffers, r)? else {
        return Ok(kind);
    };
    let factor = ir.factor;
    // With a partial transmission already blended, nested blends are not supported: factor 1.
    let wants_blend = factor < 1.0 || ir.factor_texture.is_some();
    let partial = wants_blend && !matches!(kind, BsdfKind::Blend { .. });
    if wants_blend && !partial {
        cx.warnings.push(format!("{}: iridescenceFactor {factor} and iridescenceTexture treated as 1: the material already blends a partial transmission (nested blends are not yet implemented)", mat.label));
    }
    if pbr.textured {
        r.notes
            .push("base colour / metallic-roughness textures ignored (thin film)".into());
    }
    let film = thin_film(pbr, ir.thickness, ir.film_ior, ir.max_nm, r);
    if !partial {
        return Ok(film);
    }
    r.notes.push(format!("iridescenceFactor {factor}: blend of {factor} x film and {} x the material without it (approximates glTF's Fresnel mix: see the module doc)", 1.0 - factor));
    r.mapping = format!(
        "blend of {factor} x ({}) and {} x (the material without the film)",
        r.mapping,
        1.0 - factor
    );
    let weight = match ir.factor_texture {
        Some(t) => {
            r.notes.push(
                "iridescenceTexture: its red channel multiplies the blend weight per texel".into(),
            );
            let ch = Some(TextureChannel::Red);
            texture::scaled(TextureDesc::Bitmap(t), ch, [factor; 3], 0.0)
        }
        None => TextureDesc::constant(factor),
    };
    Ok(BsdfKind::Blend {
        weight,
        first: mat.nest(kind),
        second: mat.nest(film),
    })
}

/// The film over an opaque base of the reflectance F0 at normal incidence (n from the base
/// colour with k = 0 for a metal, n = ior for a dielectric), smooth or GGX-rough; the diffuse
/// base is dropped.
fn thin_film(
    pbr: &Pbr,
    thickness: TextureDesc,
    film_ior: f32,
    max_nm: f32,
    r: &mut Report,
) -> BsdfKind {
    let n_of = |f0: f32| {
        let s = f0.clamp(0.0, 0.999).sqrt();
        (1.0 + s) / (1.0 - s)
    };
    let bc = pbr.base_color;
    let eta = if pbr.metallic >= 0.5 {
        SpectrumDesc::Rgb([n_of(bc[0]), n_of(bc[1]), n_of(bc[2])])
    } else {
        SpectrumDesc::Constant(pbr.ior)
    };
    let film =
        format!("{max_nm} nm film of ior {film_ior} over an opaque base of index {eta:?} (k = 0)");
    let base = FilmBaseDesc::Conductor {
        eta: TextureDesc::Constant(eta),
        k: TextureDesc::constant(0.0),
    };
    let alpha = pbr.roughness * pbr.roughness;
    if alpha < SMOOTH_ALPHA {
        r.mapping = format!("thinfilm: {film}; smooth, diffuse dropped");
        BsdfKind::ThinFilm {
            thickness,
            film_ior,
            ext_ior: 1.0,
            base,
        }
    } else {
        r.mapping = format!("roughthinfilm: {film}, GGX alpha {alpha:.4}; diffuse dropped");
        BsdfKind::RoughThinFilm {
            thickness,
            film_ior,
            ext_ior: 1.0,
            base,
            microfacet: ggx(alpha),
        }
    }
}

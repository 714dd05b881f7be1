//! The multiple-importance weights of the bidirectional strategies from partial sums carried
//! along each subpath (Georgiev et al.'s report, eqs. 31-39).

use super::VcmSettings;
use std::f32::consts::PI;

/// The power heuristic's exponent applied to one density or ratio of densities.
#[inline(always)]
fn mis(x: f32) -> f32 {
    x * x
}

/// The iteration's constants that join merging to the connections: with
/// `eta = pi r^2 N` (merging's density over a connection's, per light vertex), `vm`
/// = mis(eta) and `vc` = mis(1 / eta) when merging is on (Georgiev et al.'s report, eq. 20);
/// `conn` = 1 with connections, 0 without: then the terms of the connection strategies,
/// which the report's recursion always carries, are dropped, leaving emission and merging.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Factors {
    vm: f32,
    vc: f32,
    conn: f32,
}

impl Factors {
    /// The factors for `light_paths` light subpaths merged within `radius`.
    pub(crate) fn new(settings: &VcmSettings, radius: f32, light_paths: f32) -> Factors {
        let eta = if settings.merging {
            PI * radius * radius * light_paths
        } else {
            1.0
        };
        Factors {
            vm: if settings.merging { mis(eta) } else { 0.0 },
            vc: if settings.merging {
                mis(1.0 / eta)
            } else {
                0.0
            },
            conn: if settings.connections { 1.0 } else { 0.0 },
        }
    }
}

/// The partial sums of density ratios a subpath carries to its last vertex (Georgiev et al.'s
/// report, sec. 4): with them, the weight of any strategy that uses this vertex follows from
/// the densities at the vertex alone.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SubpathMis {
    /// The strategies that sample this vertex from the other side (`dVCM`).
    pub dvcm: f32,
    /// The connection strategies behind it (`dVC`).
    pub dvc: f32,
    /// The merging strategies behind it (`dVM`).
    pub dvm: f32,
}

impl SubpathMis {
    /// A camera subpath's start: `n_over_pdf` is the number of light subpaths over the
    /// solid-angle density of the camera ray for its pixel.
    pub(crate) fn camera(n_over_pdf: f32) -> Self {
        SubpathMis {
            dvcm: mis(n_over_pdf),
            dvc: 0.0,
            dvm: 0.0,
        }
    }

    /// A light subpath's start: the densities of light sampling (`direct`) and of emission
    /// (`emit`, position times direction), both with the light's selection probability, and
    /// the cosine at the light (1 for point-like and distant lights). A delta light can be
    /// neither hit nor merged at (dVC = dVM = 0).
    pub(crate) fn light(direct: f32, emit: f32, cos_light: f32, delta: bool, f: &Factors) -> Self {
        let dvc = if delta { 0.0 } else { mis(cos_light / emit) };
        SubpathMis {
            dvcm: mis(direct / emit),
            dvc,
            dvm: dvc * f.vc,
        }
    }

    /// The subpath reached its next vertex over a segment of squared length `dist2` (`None`
    /// for a distant light's first segment: its density is per unit area already), meeting
    /// the surface at the geometric cosine `cos`.
    pub(crate) fn arrive(&mut self, dist2: Option<f32>, cos: f32) {
        if let Some(d2) = dist2 {
            self.dvcm *= mis(d2);
        }
        let c = 1.0 / mis(cos);
        self.dvcm *= c;
        self.dvc *= c;
        self.dvm *= c;
    }

    /// The subpath leaves its vertex in a direction sampled with the solid-angle density
    /// `fwd` (reverse: `rev`) at the geometric cosine `cos_out`; `delta` when a delta lobe
    /// was chosen (Georgiev et al.'s report, eqs. 34-38).
    pub(crate) fn scatter(&mut self, cos_out: f32, fwd: f32, rev: f32, delta: bool, f: &Factors) {
        if delta {
            self.dvcm = 0.0;
            self.dvc *= mis(cos_out);
            self.dvm *= mis(cos_out);
        } else {
            let k = mis(cos_out / fwd);
            self.dvc = k * (self.dvc * mis(rev) + self.dvcm * f.conn + f.vm);
            self.dvm = k * (self.dvm * mis(rev) + self.dvcm * f.vc * f.conn + 1.0);
            self.dvcm = mis(1.0 / fwd);
        }
    }
}

/// Weight of a camera subpath meeting an emitter (s = 0): `direct` the area density (solid
/// angle for distant lights) of light sampling choosing the point, `emit` the density of
/// the light emitting towards the previous vertex, both with the selection probability.
#[inline(always)]
pub(crate) fn emission_weight(cam: &SubpathMis, direct: f32, emit: f32, f: &Factors) -> f32 {
    1.0 / (1.0 + mis(direct) * cam.dvcm * f.conn + mis(emit) * cam.dvc)
}

/// Weight of light sampling at a camera vertex (s = 1): `bsdf_fwd` the BSDF's density of the
/// light's direction (0 for a delta light), `direct` the light sampling density (solid
/// angle, with selection), `emit` the light's emission density towards the vertex (with
/// selection), `cos_vertex` and `cos_light` the geometric cosines at both ends, `bsdf_rev`
/// the BSDF's density of the camera side's direction from the light's.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn light_sample_weight(
    cam: &SubpathMis,
    bsdf_fwd: f32,
    direct: f32,
    emit: f32,
    cos_vertex: f32,
    cos_light: f32,
    bsdf_rev: f32,
    f: &Factors,
) -> f32 {
    let w_light = mis(bsdf_fwd / direct);
    let w_camera =
        mis(emit * cos_vertex / (direct * cos_light)) * (f.vm + cam.dvcm + cam.dvc * mis(bsdf_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// Weight of connecting a camera vertex and a light vertex (s, t >= 2): `cam_area` the
/// camera vertex's BSDF density of the light vertex (per unit area there), `light_area` the
/// light vertex's of the camera vertex, `light_rev` / `cam_rev` each BSDF's reverse
/// solid-angle density of its own subpath's previous direction.
#[inline(always)]
pub(crate) fn connection_weight(
    light: &SubpathMis,
    cam: &SubpathMis,
    cam_area: f32,
    light_area: f32,
    light_rev: f32,
    cam_rev: f32,
    f: &Factors,
) -> f32 {
    let w_light = mis(cam_area) * (f.vm + light.dvcm + light.dvc * mis(light_rev));
    let w_camera = mis(light_area) * (f.vm + cam.dvcm + cam.dvc * mis(cam_rev));
    1.0 / (w_light + 1.0 + w_camera)
}

/// Weight of a light vertex splatted to the camera (t = 1): `cam_area_over_n` the camera's
/// density of the vertex for one pixel sample (per unit area there) over the number of light
/// subpaths, `light_rev` the vertex's BSDF density of its previous direction from the camera's.
#[inline(always)]
pub(crate) fn camera_weight(
    light: &SubpathMis,
    cam_area_over_n: f32,
    light_rev: f32,
    f: &Factors,
) -> f32 {
    1.0 / (mis(cam_area_over_n) * (f.vm + light.dvcm + light.dvc * mis(light_rev)) + 1.0)
}

/// Weight of merging a light vertex at a camera vertex: `cam_fwd` the camera vertex's BSDF
/// density of the light vertex's arriving direction, `cam_rev` of the camera side's from it.
#[inline(always)]
pub(crate) fn merge_weight(
    light: &SubpathMis,
    cam: &SubpathMis,
    cam_fwd: f32,
    cam_rev: f32,
    f: &Factors,
) -> f32 {
    let w_light = light.dvcm * f.vc * f.conn + light.dvm * mis(cam_fwd);
    let w_camera = cam.dvcm * f.vc * f.conn + cam.dvm * mis(cam_rev);
    1.0 / (w_light + 1.0 + w_camera)
}

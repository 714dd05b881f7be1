//! Integrators.

use super::*;

impl<'e> Builder<'e> {
    /// `path` (`max_depth` -1, `rr_depth` 5, `hide_emitters` false), `direct` (path with
    /// max_depth 2; one emitter and one BSDF sample) and `moment` (wraps one integrator).
    pub(super) fn integrator(&mut self, el: &'e Element) -> Result<IntegratorDesc> {
        let v = ObjectView::parse(el)?;
        let desc = match v.plugin.as_str() {
            "path" => path_integrator(&v)?,
            "volpath" => IntegratorDesc {
                kind: IntegratorKind::VolPath,
                ..path_integrator(&v)?
            },
            // Mitsuba's `volpathmis` differs from its `volpath` in weighting free flight over
            // the channels by MIS, which pt's `volpath` already does: the same integrator
            // (`use_spectral_mis` accepted).
            "volpathmis" => {
                v.boolean("use_spectral_mis")?;
                IntegratorDesc {
                    kind: IntegratorKind::VolPath,
                    ..path_integrator(&v)?
                }
            }
            // Mitsuba's differentiable path tracers render, in a forward (primal) render, what
            // `path` and `volpath` render: only their defaults differ (max_depth 6), and prb
            // starts Russian roulette one vertex later than path (its test comes before the
            // depth's increment), which rr_depth + 1 reproduces. Their gradient-only options
            // (projective sampling) are accepted and have no effect on the image.
            "prb" | "prb_projective" => {
                if v.plugin == "prb_projective" {
                    projective_options(&v)?;
                }
                differentiable(IntegratorKind::Path, &v)?
            }
            "prbvolpath" => differentiable(IntegratorKind::VolPath, &v)?,
            // Mitsuba's `prb_basic`: BSDF sampling alone, no Russian roulette, emitters always
            // seen (its forward render reads no hide_emitters); max_depth 6 by default.
            "prb_basic" => IntegratorDesc {
                // Read by Mitsuba's base class, unused by prb_basic.
                hide_emitters: {
                    v.boolean("hide_emitters")?;
                    int_in(&v, "rr_depth", 5, 1, u32::MAX as i64)?;
                    false
                },
                kind: IntegratorKind::Path,
                max_depth: int_in(&v, "max_depth", 6, -1, i32::MAX as i64)? as i32,
                rr_depth: u32::MAX,
                light_sampling: false,
                ..default_integrator()
            },
            // Mitsuba's `depth` reads nothing but its base class's `hide_emitters` (no
            // effect on a depth image).
            "depth" => {
                v.boolean("hide_emitters")?;
                IntegratorDesc {
                    kind: IntegratorKind::Depth,
                    ..default_integrator()
                }
            }
            "direct" => direct_integrator(&v)?,
            // Mitsuba's `direct_projective` renders, in a forward (primal) render, what
            // `direct` renders with one emitter and one BSDF sample (measured: the two images'
            // means agree to 6e-6); its gradient-only options and its max_depth and rr_depth
            // (fixed at 2 in Mitsuba) are accepted and change nothing.
            "direct_projective" => {
                projective_options(&v)?;
                int_in(&v, "max_depth", 2, -1, i32::MAX as i64)?;
                int_in(&v, "rr_depth", 2, 1, u32::MAX as i64)?;
                IntegratorDesc {
                    kind: IntegratorKind::Direct {
                        emitter_samples: 1,
                        bsdf_samples: 1,
                    },
                    max_depth: 2,
                    rr_depth: 5,
                    hide_emitters: v.boolean("hide_emitters")?.unwrap_or(false),
                    light_sampling: true,
                    ..default_integrator()
                }
            }
            "moment" => self.moment(&v)?,
            "aov" => self.aov(&v)?,
            "radiosity" => radiosity_integrator(&v)?,
            "ptracer" => ptracer_integrator(&v)?,
            "sppm" => sppm_integrator(&v)?,
            "bdpt" => IntegratorDesc {
                kind: IntegratorKind::Bdpt,
                ..path_integrator(&v)?
            },
            "vcm" => vcm_integrator(&v)?,
            "photonmapper" => photonmapper_integrator(&v)?,
            _ => return Err(plugin_error(el)),
        };
        let desc = IntegratorDesc {
            loc: el.loc.clone(),
            ..desc
        };
        if v.plugin != "moment" && v.plugin != "aov" {
            if let Some(child) = v.children.first() {
                let target = self.resolve(child)?;
                return Err(misplaced(child, target, &v, "no nested objects"));
            }
        }
        v.finish()?;
        Ok(desc)
    }

    /// The one integrator nested in a wrapper (`moment`, `aov`) and its name (Mitsuba names
    /// an unnamed nested object by its position: `_arg_0`), or `None`. A second one is not
    /// implemented; one that `accepts` refuses is an error naming `allowed`.
    fn nested_integrator(
        &mut self,
        v: &ObjectView<'e>,
        allowed: &str,
        accepts: impl Fn(&IntegratorDesc) -> bool,
    ) -> Result<Option<(String, IntegratorDesc)>> {
        let mut inner = None;
        for child in &v.children {
            let target = self.resolve(child)?;
            if target.tag != "integrator" {
                return Err(misplaced(child, target, v, "integrator"));
            }
            let loc = &child.written().loc;
            if inner.is_some() {
                return Err(SceneError::at(
                    loc,
                    format!(
                        "{} with more than one nested integrator is not yet supported (not yet implemented)",
                        v.plugin
                    ),
                ));
            }
            let desc = self.integrator(target)?;
            if !accepts(&desc) {
                return Err(SceneError::at(
                    loc,
                    format!("the integrator nested in {} must be {allowed}", v.plugin),
                ));
            }
            let name = child.written().attr("name").unwrap_or("_arg_0").to_string();
            inner = Some((name, desc));
        }
        Ok(inner)
    }

    pub(super) fn moment(&mut self, v: &ObjectView<'e>) -> Result<IntegratorDesc> {
        let plain = |d: &IntegratorDesc| {
            d.moment.is_none() && d.aov.is_none() && d.kind.is_camera_path_tracer()
        };
        let (name, mut inner) = self
            .nested_integrator(v, "path, volpath or direct", plain)?
            .ok_or_else(|| SceneError::at(&v.el.loc, "moment needs one nested <integrator>"))?;
        inner.moment = Some(name);
        Ok(inner)
    }

    /// Mitsuba's `aov`: `aovs` ("name:type" pairs separated by commas or spaces; required) and
    /// at most one nested integrator (Mitsuba takes several; pt renders one), whose image is
    /// also written under its `name`. Without one, the image's own channels are zero and only
    /// the AOVs are rendered.
    pub(super) fn aov(&mut self, v: &ObjectView<'e>) -> Result<IntegratorDesc> {
        let spec = v.string("aovs")?.ok_or_else(|| {
            SceneError::at(
                &v.el.loc,
                "aov needs <string name=\"aovs\" value=\"name:type, ...\"/>",
            )
        })?;
        let mut outputs = Vec::new();
        for token in spec.split([',', ' ']).filter(|t| !t.is_empty()) {
            let bad = |m: String| Err(v.prop_error("aovs", m));
            let Some((name, kind)) = token
                .split_once(':')
                .filter(|(n, k)| !n.is_empty() && !k.is_empty())
            else {
                return bad(format!("\"{token}\" is not a <name>:<type> pair"));
            };
            let kind = match AovKind::NAMES.iter().find(|(n, _)| *n == kind) {
                Some((_, k)) => *k,
                None if ["duv_dx", "duv_dy", "boundary_test"].contains(&kind) => {
                    return bad(format!(
                        "AOV type \"{kind}\" is not yet supported (not yet implemented)"
                    ))
                }
                None => {
                    let names: Vec<&str> = AovKind::NAMES.iter().map(|(n, _)| *n).collect();
                    return bad(format!(
                        "invalid AOV type \"{kind}\" (pt knows {})",
                        names.join(", ")
                    ));
                }
            };
            outputs.push((name.to_string(), kind));
        }
        let inner = self.nested_integrator(v, "path, volpath, direct or moment", |d| {
            d.aov.is_none() && d.kind.is_camera_path_tracer()
        })?;
        let (image, base) = match inner {
            Some((name, desc)) => (Some(name), desc),
            None => (None, default_integrator()),
        };
        Ok(IntegratorDesc {
            aov: Some(AovDesc { image, outputs }),
            ..base
        })
    }
}

pub(super) fn path_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    Ok(IntegratorDesc {
        kind: IntegratorKind::Path,
        max_depth: int_in(v, "max_depth", -1, -1, i32::MAX as i64)? as i32,
        rr_depth: int_in(v, "rr_depth", 5, 1, u32::MAX as i64)? as u32,
        hide_emitters: v.boolean("hide_emitters")?.unwrap_or(false),
        light_sampling: true,
        moment: None,
        aov: None,
        radiosity: RadiosityOptions::default(),
        loc: SourceLoc::default(),
    })
}

/// Mitsuba's `prb`, `prb_projective` (`kind` Path) and `prbvolpath` (VolPath) in a forward
/// render: `path`'s parameters with `max_depth` 6 by default, Russian roulette from `rr_depth`
/// (default 5) + 1 in pt's counting.
fn differentiable(kind: IntegratorKind, v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    let max_depth = int_in(v, "max_depth", 6, -1, i32::MAX as i64)? as i32;
    let path = path_integrator(v)?;
    Ok(IntegratorDesc {
        kind,
        max_depth,
        rr_depth: path.rr_depth.saturating_add(1),
        ..path
    })
}

/// `prb_projective`'s options for its gradients' projective sampling (Mitsuba 3.9.1: sample
/// counts `sppc`, `sppp`, `sppi`, the guiding settings), read and checked for their types only:
/// a forward render does not use them.
fn projective_options(v: &ObjectView<'_>) -> Result<()> {
    for name in ["sppc", "sppp", "sppi", "guiding_rounds"] {
        v.integer(name)?;
    }
    v.string("guiding")?;
    v.boolean("guiding_proj")?;
    Ok(())
}

/// Mitsuba's `ptracer`: `max_depth`, `rr_depth` and `hide_emitters` as `path`, and
/// `samples_per_pass` (positive; Mitsuba's default -1 means all samples in one pass).
pub(super) fn ptracer_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    let samples_per_pass = match v.integer("samples_per_pass")? {
        None | Some(-1) => None,
        Some(n) if n >= 1 && n <= i64::from(u32::MAX) => Some(n as u32),
        Some(n) => {
            return Err(v.prop_error(
                "samples_per_pass",
                format!("samples_per_pass must be positive (or -1 for one pass), got {n}"),
            ))
        }
    };
    Ok(IntegratorDesc {
        kind: IntegratorKind::PTracer { samples_per_pass },
        ..path_integrator(v)?
    })
}

/// `sppm` (project extension): `max_depth`, `rr_depth` and `hide_emitters` as `path`, and
/// `photons_per_iteration` (positive), `initial_radius` (positive, scene units) and `alpha`
/// (in (0, 1), default 2/3).
pub(super) fn sppm_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    let (initial_radius, alpha) = radius_schedule(v, 2.0 / 3.0)?;
    let photons_per_iteration = match v.integer("photons_per_iteration")? {
        None => None,
        Some(n) if n >= 1 && n <= i64::from(u32::MAX) => Some(n as u32),
        Some(n) => {
            return Err(v.prop_error(
                "photons_per_iteration",
                format!("photons_per_iteration must be positive, got {n}"),
            ))
        }
    };
    Ok(IntegratorDesc {
        kind: IntegratorKind::Sppm {
            photons_per_iteration,
            initial_radius,
            alpha,
        },
        ..path_integrator(v)?
    })
}

/// `vcm` (project extension): `max_depth`, `rr_depth` and `hide_emitters` as `path`, and
/// `initial_radius` (positive, scene units) and `alpha` (in (0, 1), default 3/4).
pub(super) fn vcm_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    let (initial_radius, alpha) = radius_schedule(v, 0.75)?;
    Ok(IntegratorDesc {
        kind: IntegratorKind::Vcm {
            initial_radius,
            alpha,
        },
        ..path_integrator(v)?
    })
}

/// `photonmapper` (project extension): `max_depth`, `rr_depth` and `hide_emitters` as
/// `path`, `global_photons` and `caustic_photons` (>= 0, not both 0), `lookup_size` (>= 1),
/// `lookup_radius` (positive, scene units) and `final_gather` (boolean).
pub(super) fn photonmapper_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    let global_photons = int_in(v, "global_photons", 100_000, 0, i64::from(u32::MAX))? as u32;
    let caustic_photons = int_in(v, "caustic_photons", 100_000, 0, i64::from(u32::MAX))? as u32;
    if global_photons == 0 && caustic_photons == 0 {
        return Err(v.prop_error(
            "global_photons",
            "global_photons and caustic_photons cannot both be 0",
        ));
    }
    let lookup_size = int_in(v, "lookup_size", 50, 1, 100_000)? as u32;
    let lookup_radius = match v.float("lookup_radius")? {
        None => None,
        Some(r) if r > 0.0 && r.is_finite() => Some(r),
        Some(r) => {
            return Err(v.prop_error(
                "lookup_radius",
                format!("lookup_radius must be a positive distance, got {r}"),
            ))
        }
    };
    Ok(IntegratorDesc {
        kind: IntegratorKind::PhotonMapper {
            global_photons,
            caustic_photons,
            lookup_size,
            lookup_radius,
            final_gather: v.boolean("final_gather")?.unwrap_or(true),
        },
        ..path_integrator(v)?
    })
}

/// The photon mappers' `initial_radius` (positive, scene units; optional) and `alpha` (in
/// (0, 1), `default_alpha` when not given).
fn radius_schedule(v: &ObjectView<'_>, default_alpha: f32) -> Result<(Option<f32>, f32)> {
    let initial_radius = match v.float("initial_radius")? {
        None => None,
        Some(r) if r > 0.0 && r.is_finite() => Some(r),
        Some(r) => {
            return Err(v.prop_error(
                "initial_radius",
                format!("initial_radius must be a positive distance, got {r}"),
            ))
        }
    };
    let alpha = match v.float("alpha")? {
        None => default_alpha,
        Some(a) if a > 0.0 && a < 1.0 => a,
        Some(a) => {
            return Err(v.prop_error(
                "alpha",
                format!("alpha must lie strictly between 0 and 1, got {a}"),
            ))
        }
    };
    Ok((initial_radius, alpha))
}

/// `radiosity` (project extension): `patch_size` (float, scene units), `rays_per_patch`,
/// `tolerance`, `max_iterations`, `solver`, `display`, `reciprocity` (strings; checked by the
/// radiosity crate). Renders diffuse scenes by finite elements; see crates/pt-radiosity.
pub(super) fn radiosity_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    let count = |name: &str| -> Result<Option<u32>> {
        match v.integer(name)? {
            None => Ok(None),
            Some(n) if n >= 1 && n <= u32::MAX as i64 => Ok(Some(n as u32)),
            Some(n) => Err(v.prop_error(name, format!("{name} must be at least 1, got {n}"))),
        }
    };
    let radiosity = RadiosityOptions {
        patch_size: v.float("patch_size")?,
        rays_per_patch: count("rays_per_patch")?,
        tolerance: v.float("tolerance")?,
        max_iterations: count("max_iterations")?,
        solver: parsed(v, "solver")?,
        display: parsed(v, "display")?,
        reciprocity: parsed(v, "reciprocity")?,
    };
    Ok(IntegratorDesc {
        kind: IntegratorKind::Radiosity,
        max_depth: -1,
        rr_depth: 5,
        hide_emitters: false,
        light_sampling: true,
        moment: None,
        aov: None,
        radiosity,
        loc: SourceLoc::default(),
    })
}

/// Mitsuba's `direct`: `shading_samples` (default 1) sets both `emitter_samples` and
/// `bsdf_samples`, and may not be given with them; at least one must be positive (Mitsuba
/// refuses a direct integrator that samples nothing).
pub(super) fn direct_integrator(v: &ObjectView<'_>) -> Result<IntegratorDesc> {
    let count = |name: &str, default: u32| -> Result<u32> {
        Ok(int_in(v, name, i64::from(default), 0, 1 << 16)? as u32)
    };
    let shading = count("shading_samples", 1)?;
    if v.has("shading_samples") && (v.has("emitter_samples") || v.has("bsdf_samples")) {
        return Err(v.prop_error(
            "shading_samples",
            "give either shading_samples or emitter_samples/bsdf_samples (Mitsuba refuses both)",
        ));
    }
    let emitter_samples = count("emitter_samples", shading)?;
    let bsdf_samples = count("bsdf_samples", shading)?;
    if emitter_samples == 0 && bsdf_samples == 0 {
        return Err(v.prop_error(
            if v.has("shading_samples") {
                "shading_samples"
            } else {
                "emitter_samples"
            },
            "a direct integrator needs at least one emitter or BSDF sample",
        ));
    }
    Ok(IntegratorDesc {
        kind: IntegratorKind::Direct {
            emitter_samples,
            bsdf_samples,
        },
        max_depth: 2,
        rr_depth: 5,
        hide_emitters: v.boolean("hide_emitters")?.unwrap_or(false),
        light_sampling: true,
        moment: None,
        aov: None,
        radiosity: RadiosityOptions::default(),
        loc: SourceLoc::default(),
    })
}

pub(super) fn default_integrator() -> IntegratorDesc {
    IntegratorDesc {
        radiosity: RadiosityOptions::default(),
        loc: SourceLoc::default(),
        kind: IntegratorKind::Path,
        max_depth: -1,
        rr_depth: 5,
        hide_emitters: false,
        light_sampling: true,
        moment: None,
        aov: None,
    }
}

/// A string property parsed into one of the named options of `T`, the error at the property.
fn parsed<T: std::str::FromStr<Err = String>>(v: &ObjectView<'_>, name: &str) -> Result<Option<T>> {
    match v.string(name)? {
        None => Ok(None),
        Some(s) => s.parse().map(Some).map_err(|e| v.prop_error(name, e)),
    }
}

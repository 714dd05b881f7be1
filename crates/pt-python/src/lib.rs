//! `pt_renderer._pt_renderer`: the compiled half of the Python package `pt_renderer`
//! (`python/pt_renderer/__init__.py` is the typed public API over it; `crates/pt-python/README.md`
//! shows it in use).
//!
//! Everything here calls the library the `pt` command line calls, with the same defaults, so
//! that a render from Python equals `pt render` of the same scene, seed and sample count bit
//! for bit: scenes through [`pt_scene::open`], methods through [`pt_integrators::method`] and
//! [`pt_integrators::Integrator::from_desc`], images through
//! [`pt_integrators::Rendered::channels`], comparisons through [`pt_lab::compare`], BSDFs
//! through [`pt_lab::bsdf`] and convergence through [`pt_lab::converge`].
//!
//! Long work runs with the GIL released. A render runs on its own thread while the calling
//! thread, every [`POLL`], takes the GIL back to run Python's signal handlers (Ctrl-C) and the
//! progress callback; either raising cancels the render, which stops after its current pass
//! (passes are sized to last about a second).
//!
//! Errors become Python exceptions, never a crash: scene and BSDF errors are `SceneError`
//! (a `ValueError`) carrying the loader's `file:line:column: <element>: message`.

use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pt_integrators::{Integrator, Job, Overrides, Progress, Run};
use pt_lab::bsdf::{BsdfModel, BsdfSpec, PropValue};
use pt_math::{Vec2, Vec3, Vec4};
use pt_scene::SceneDesc;
use pt_spectrum::ColorMode;
use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::Duration;

pyo3::create_exception!(
    _pt_renderer,
    SceneError,
    PyValueError,
    "A scene, BSDF or option that pt refuses; the message names the file, line, column and element (file:line:column: <element>: what is wrong)."
);

/// How often a waiting render looks for Ctrl-C and reports progress.
const POLL: Duration = Duration::from_millis(50);

/// A scene refused by the loader, the scene build or a method.
fn scene_error(e: impl std::fmt::Display) -> PyErr {
    SceneError::new_err(e.to_string())
}

/// An image that cannot be read or written.
fn image_error(e: pt_image::ImageError) -> PyErr {
    PyOSError::new_err(e.to_string())
}

/// A loaded scene: the description every render of it starts from.
#[pyclass(frozen, module = "pt_renderer")]
struct Scene {
    desc: SceneDesc,
    warnings: Vec<String>,
    summary: Vec<String>,
}

#[pymethods]
impl Scene {
    /// What the scene contains and how pt reads it (film, sampler, integrator, shapes,
    /// materials, lights, colour mode), as a dict.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = &self.desc;
        let out = PyDict::new(py);
        out.set_item("source", d.source.display().to_string())?;
        out.set_item("width", d.film.width)?;
        out.set_item("height", d.film.height)?;
        out.set_item(
            "film_channels",
            d.film
                .pixel_format
                .channels()
                .iter()
                .map(|c| c.to_string())
                .collect::<Vec<_>>(),
        )?;
        out.set_item("filter", format!("{:?}", d.film.filter))?;
        out.set_item("sampler", d.sampler.kind.plugin())?;
        out.set_item("spp", d.sampler.sample_count)?;
        out.set_item("seed", d.sampler.seed)?;
        out.set_item("integrator", format!("{:?}", d.integrator.kind))?;
        out.set_item("max_depth", d.integrator.max_depth)?;
        out.set_item("shapes", d.shapes.len())?;
        let triangles: usize = d
            .shapes
            .iter()
            .chain(d.groups.iter().flat_map(|g| g.shapes.iter()))
            .map(|s| match &s.geometry {
                pt_scene::Geometry::Mesh(m) => m.indices.len(),
                _ => 0,
            })
            .sum();
        out.set_item("triangles", triangles)?;
        out.set_item("instances", d.instances.len())?;
        out.set_item(
            "materials",
            d.bsdfs
                .iter()
                .map(|b| b.id.clone().unwrap_or_else(|| "-".into()))
                .collect::<Vec<_>>(),
        )?;
        out.set_item(
            "emitters",
            d.lights.len() + d.shapes.iter().filter(|s| s.emitter.is_some()).count(),
        )?;
        let reason = d.spectral_reason();
        out.set_item("mode", if reason.is_some() { "spectral" } else { "rgb" })?;
        out.set_item("mode_reason", reason.map(|r| r.to_string()))?;
        out.set_item("warnings", self.warnings.clone())?;
        out.set_item("gltf", self.summary.clone())?;
        Ok(out)
    }

    /// The scene file (or the built-in box's name).
    #[getter]
    fn source(&self) -> String {
        self.desc.source.display().to_string()
    }

    fn __repr__(&self) -> String {
        format!(
            "<pt_renderer.Scene {} {}x{}, {} spp>",
            self.desc.source.display(),
            self.desc.film.width,
            self.desc.film.height,
            self.desc.sampler.sample_count
        )
    }
}

/// Opens a Mitsuba XML or glTF file (or the built-in Cornell box when `path` is None) with
/// `-D`-style parameters.
#[pyfunction]
#[pyo3(signature = (path, defines, camera=None))]
fn load_file(
    path: Option<PathBuf>,
    defines: Vec<(String, String)>,
    camera: Option<usize>,
) -> PyResult<Scene> {
    let opened = pt_scene::open(path.as_deref(), &defines, camera).map_err(scene_error)?;
    Ok(Scene {
        desc: opened.desc,
        warnings: opened.warnings,
        summary: opened.summary,
    })
}

/// Loads a Mitsuba XML scene from a string; relative file names in it are taken from
/// `base_dir`.
#[pyfunction]
fn load_string(xml: &str, base_dir: PathBuf, defines: Vec<(String, String)>) -> PyResult<Scene> {
    let desc =
        pt_scene::load_str(xml, Path::new("<string>"), &base_dir, &defines).map_err(scene_error)?;
    Ok(Scene {
        desc,
        warnings: Vec::new(),
        summary: Vec::new(),
    })
}

/// Progress of a render, kept in atomics by the workers and read by the waiting thread.
#[derive(Default)]
struct Counters {
    total: AtomicU64,
    done: AtomicU64,
    /// A staged method's (radiosity's) fraction, as f32 bits, and its stage name.
    fraction: AtomicU32,
    stage: Mutex<Option<String>>,
}

impl Progress for Counters {
    fn start_samples(&self, total: u64, done: u64) {
        self.total.store(total, Ordering::Relaxed);
        self.done.store(done, Ordering::Relaxed);
    }

    fn samples(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }

    fn stage(&self, name: &str, fraction: f32) {
        self.fraction.store(fraction.to_bits(), Ordering::Relaxed);
        if let Ok(mut s) = self.stage.lock() {
            if s.as_deref() != Some(name) {
                *s = Some(name.to_string());
            }
        }
    }
}

impl Counters {
    /// (done, total, stage) for the callback: samples, or a staged method's thousandths.
    fn report(&self) -> (u64, u64, String) {
        match self.stage.lock().ok().and_then(|s| s.clone()) {
            Some(stage) => {
                let f = f32::from_bits(self.fraction.load(Ordering::Relaxed));
                ((f.clamp(0.0, 1.0) * 1000.0) as u64, 1000, stage)
            }
            None => (
                self.done.load(Ordering::Relaxed),
                self.total.load(Ordering::Relaxed),
                "sampling".to_string(),
            ),
        }
    }
}

/// The worker threads of one call: `threads` (at least 1), or one per core.
fn thread_pool(threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(t) = threads {
        if t == 0 {
            return Err(PyValueError::new_err("threads must be at least 1"));
        }
        b = b.num_threads(t);
    }
    b.build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start worker threads: {e}")))
}

/// `rgb` / `spectral` / None.
fn color_mode(mode: Option<&str>) -> PyResult<Option<ColorMode>> {
    match mode {
        None => Ok(None),
        Some("rgb") => Ok(Some(ColorMode::Rgb)),
        Some("spectral") => Ok(Some(ColorMode::Spectral)),
        Some(other) => Err(PyValueError::new_err(format!(
            "mode must be 'rgb' or 'spectral', got '{other}'"
        ))),
    }
}

/// A render's results: the image (H, W, C), its variance (H, W, 3), channel names, samples
/// per pixel taken, seconds, warnings.
type RenderResult<'py> = (
    Bound<'py, PyArray3<f32>>,
    Bound<'py, PyArray3<f32>>,
    Vec<String>,
    u32,
    f64,
    Vec<String>,
);

/// Renders `scene` as `pt render` does with the same options (see the module doc).
#[pyfunction]
#[pyo3(signature = (scene, spp=None, seed=None, integrator=None, threads=None, mode=None, max_depth=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &Scene,
    spp: Option<u32>,
    seed: Option<u64>,
    integrator: Option<&str>,
    threads: Option<usize>,
    mode: Option<&str>,
    max_depth: Option<i32>,
    progress: Option<Py<PyAny>>,
) -> PyResult<RenderResult<'py>> {
    let desc = &scene.desc;
    let kind = match integrator {
        None => None,
        Some(name) => Some(pt_integrators::method(name).ok_or_else(|| {
            PyValueError::new_err(format!(
                "unknown integrator '{name}' (known: {})",
                pt_integrators::METHODS.join(", ")
            ))
        })?),
    };
    if spp == Some(0) {
        return Err(PyValueError::new_err("spp must be at least 1"));
    }
    let overrides = Overrides {
        kind,
        max_depth,
        ..Overrides::default()
    };
    let method = Integrator::from_desc(&desc.integrator, &overrides).map_err(scene_error)?;
    method.check_scene(desc).map_err(scene_error)?;
    let job = Job {
        spp: spp.unwrap_or(desc.sampler.sample_count),
        seed: seed.unwrap_or(desc.sampler.seed),
        mode: color_mode(mode)?,
        ..Job::new(desc)
    };
    let pool = thread_pool(threads)?;
    let counters = Counters::default();
    let cancel = AtomicBool::new(false);
    // The error that stopped the render early (Ctrl-C, or the progress callback raising).
    let mut stopped: Option<PyErr> = None;
    let rendered = py.detach(|| {
        std::thread::scope(|s| {
            let worker = s.spawn(|| {
                pool.install(|| {
                    method.render(
                        &job,
                        Run {
                            progress: &counters,
                            cancel: &cancel,
                            ..Run::default()
                        },
                    )
                })
            });
            while !worker.is_finished() {
                std::thread::park_timeout(POLL);
                if stopped.is_some() {
                    continue;
                }
                let interrupted = Python::attach(|py| -> PyResult<()> {
                    py.check_signals()?;
                    if let Some(cb) = &progress {
                        let (done, total, stage) = counters.report();
                        cb.call1(py, (done, total, stage))?;
                    }
                    Ok(())
                });
                if let Err(e) = interrupted {
                    cancel.store(true, Ordering::Relaxed);
                    stopped = Some(e);
                }
            }
            worker.join()
        })
    });
    let rendered = match rendered {
        Ok(r) => r.map_err(scene_error)?,
        Err(_) => return Err(PyRuntimeError::new_err("the render thread panicked")),
    };
    if let Some(e) = stopped {
        return Err(e);
    }
    // A cancelled render comes with the Python error returned above; this guard keeps a
    // partial image from ever being returned as a whole one.
    if !rendered.complete {
        return Err(PyKeyboardInterrupt::new_err("render cancelled"));
    }
    if let Some(cb) = &progress {
        let (done, total, stage) = counters.report();
        cb.call1(py, (done.max(total), total, stage))?;
    }
    let channels = rendered
        .channels(desc.film.pixel_format)
        .map_err(scene_error)?;
    let out = &rendered.output;
    let (w, h) = (out.width as usize, out.height as usize);
    let image = interleave(&channels, w, h)?.into_pyarray(py);
    let variance =
        Array3::from_shape_vec((h, w, 3), out.variance.iter().flatten().copied().collect())
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?
            .into_pyarray(py);
    let names = channels.iter().map(|(n, _)| n.clone()).collect();
    Ok((
        image,
        variance,
        names,
        out.spp,
        out.time.as_secs_f64(),
        rendered.warnings,
    ))
}

/// Row-major planes -> (H, W, C).
fn interleave(planes: &[(String, Vec<f32>)], w: usize, h: usize) -> PyResult<Array3<f32>> {
    let c = planes.len();
    let mut data = vec![0.0f32; w * h * c];
    for (k, (_, p)) in planes.iter().enumerate() {
        if p.len() != w * h {
            return Err(PyRuntimeError::new_err("a channel has the wrong size"));
        }
        for (i, v) in p.iter().enumerate() {
            data[i * c + k] = *v;
        }
    }
    Array3::from_shape_vec((h, w, c), data).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// An (H, W, 3) float32 array -> an image.
fn image_from(a: &PyReadonlyArray2<'_, f32>, w: usize, h: usize) -> PyResult<pt_image::Image> {
    let a = a.as_array();
    if a.shape() != [w * h, 3] {
        return Err(PyValueError::new_err("an image must be (H, W, 3)"));
    }
    Ok(pt_image::Image {
        width: w as u32,
        height: h as u32,
        data: a.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect(),
    })
}

/// Reads an EXR as `pt compare` does: (H, W, 3) linear RGB (a luminance file's Y in all three).
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let (img, _) = pt_image::read_exr(&path).map_err(image_error)?;
    let (w, h) = (img.width as usize, img.height as usize);
    Array3::from_shape_vec((h, w, 3), img.data.iter().flatten().copied().collect())
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
        .map(|a| a.into_pyarray(py))
}

/// Every channel of an EXR: (name, (H, W) plane) in the file's order.
#[pyfunction]
fn read_exr_channels<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<Vec<(String, Bound<'py, PyArray2<f32>>)>> {
    let (w, h, channels) = pt_image::read_exr_channels(&path).map_err(image_error)?;
    channels
        .into_iter()
        .map(|(n, p)| {
            Array2::from_shape_vec((h as usize, w as usize), p)
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))
                .map(|a| (n, a.into_pyarray(py)))
        })
        .collect()
}

/// Writes float32 planes (each H*W, row-major) as named EXR channels, atomically.
#[pyfunction]
fn write_exr(
    path: PathBuf,
    width: u32,
    height: u32,
    channels: Vec<(String, PyReadonlyArray1<'_, f32>)>,
) -> PyResult<()> {
    let planes: Vec<(String, Vec<f32>)> = channels
        .iter()
        .map(|(n, a)| (n.clone(), a.as_array().to_vec()))
        .collect();
    if let Some((n, _)) = planes
        .iter()
        .find(|(_, p)| p.len() != width as usize * height as usize)
    {
        return Err(PyValueError::new_err(format!(
            "channel '{n}' does not hold {width}x{height} values"
        )));
    }
    let refs: Vec<(&str, &[f32])> = planes.iter().map(|(n, p)| (n.as_str(), &p[..])).collect();
    pt_image::write_exr_channels(&path, width, height, &refs, &pt_image::ExrMeta::default())
        .map_err(image_error)
}

/// The figures of `pt compare` (see pt_lab::compare) as a dict. Images are (H*W, 3) float32;
/// `variances` those of the image's and the reference's pixel means.
#[pyfunction]
#[pyo3(signature = (width, height, image, reference, variances, block, alpha, flip_exposure))]
#[allow(clippy::too_many_arguments)]
fn compare<'py>(
    py: Python<'py>,
    width: usize,
    height: usize,
    image: PyReadonlyArray2<'py, f32>,
    reference: PyReadonlyArray2<'py, f32>,
    variances: Option<(PyReadonlyArray2<'py, f32>, PyReadonlyArray2<'py, f32>)>,
    block: u32,
    alpha: f64,
    flip_exposure: f32,
) -> PyResult<Bound<'py, PyDict>> {
    let img = image_from(&image, width, height)?;
    let reference = image_from(&reference, width, height)?;
    let vars = match &variances {
        None => None,
        Some((iv, rv)) => Some((
            image_from(iv, width, height)?,
            image_from(rv, width, height)?,
        )),
    };
    let settings = pt_lab::compare::CompareSettings {
        block,
        alpha,
        flip_exposure,
    };
    let c = py
        .detach(|| {
            pt_lab::compare::compare(
                &img,
                &reference,
                vars.as_ref().map(|(i, r)| (i, r)),
                settings,
            )
        })
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let m = &c.metrics;
    let d = PyDict::new(py);
    d.set_item("relmse", m.relmse.to_vec())?;
    d.set_item("relmse_all", m.relmse_all)?;
    d.set_item("rmse", m.rmse.to_vec())?;
    d.set_item("mae", m.mae.to_vec())?;
    d.set_item("mean_ratio", m.mean_ratio.to_vec())?;
    d.set_item("nonfinite_pixels", c.nonfinite)?;
    d.set_item("flip", c.flip.mean)?;
    d.set_item("flip_exposure", flip_exposure)?;
    d.set_item(
        "flip_map",
        Array2::from_shape_vec((height, width), c.flip.error_map.clone())
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?
            .into_pyarray(py),
    )?;
    d.set_item("fireflies", c.fireflies)?;
    match &c.ztests {
        None => d.set_item("ztest", py.None())?,
        Some(z) => {
            let t = PyDict::new(py);
            let b = &z.block;
            t.set_item("block", block)?;
            t.set_item("alpha", alpha)?;
            t.set_item("max_abs_z", b.max_abs_z)?;
            t.set_item("failed", b.failed)?;
            t.set_item("tests", b.tests)?;
            t.set_item("p_threshold", b.p_threshold)?;
            t.set_item("chi2", b.chi2)?;
            t.set_item("chi2_p", b.chi2_p)?;
            t.set_item("pass", b.pass)?;
            t.set_item("pixel_fraction_failed", z.pixel.fraction_failed)?;
            d.set_item("ztest", t)?;
        }
    }
    d.set_item("agree", c.agree)?;
    Ok(d)
}

/// A parameter value from Python: a flag, a number, an RGB triple or a name.
#[derive(FromPyObject)]
enum Param {
    Flag(bool),
    Number(f64),
    Rgb((f64, f64, f64)),
    Name(String),
}

impl From<Param> for PropValue {
    fn from(p: Param) -> PropValue {
        // Numbers as a scene file's <float>: f64, then rounded to f32.
        match p {
            Param::Flag(b) => PropValue::Boolean(b),
            Param::Number(x) => PropValue::Float(x as f32),
            Param::Rgb((r, g, b)) => PropValue::Rgb([r as f32, g as f32, b as f32]),
            Param::Name(s) => PropValue::String(s),
        }
    }
}

/// A BSDF model with its parameters, in RGB or spectral mode; directions in its local
/// shading frame (z along the normal), both pointing away from the surface.
#[pyclass(frozen, name = "BsdfCore", module = "pt_renderer")]
struct Bsdf {
    model: BsdfModel,
    label: String,
}

/// Builds a BSDF as a scene file's `<bsdf type="model">` with these parameters would be.
#[pyfunction]
#[pyo3(signature = (model, params, two_sided, mode))]
fn bsdf(model: &str, params: Vec<(String, Param)>, two_sided: bool, mode: &str) -> PyResult<Bsdf> {
    let mut spec = BsdfSpec::new(&model.to_ascii_lowercase());
    for (name, value) in params {
        spec = spec.with(&name, PropValue::from(value));
    }
    if two_sided {
        spec = BsdfSpec::two_sided(spec);
    }
    let mode = color_mode(Some(mode))?.unwrap_or(ColorMode::Rgb);
    let model = pt_lab::bsdf::build_model(&spec, mode).map_err(scene_error)?;
    Ok(Bsdf {
        model,
        label: spec.label(),
    })
}

/// Row `i` of an (N, 3) array as a vector.
fn row3(a: &numpy::ndarray::ArrayView2<'_, f64>, i: usize) -> Vec3 {
    Vec3::new(a[[i, 0]] as f32, a[[i, 1]] as f32, a[[i, 2]] as f32)
}

impl Bsdf {
    /// The BSDF for row `i`: at its wavelength in spectral mode (all four lanes; lane 0 read).
    fn at(
        &self,
        lambda: Option<&numpy::ndarray::ArrayView1<'_, f64>>,
        i: usize,
    ) -> pt_bsdf::SurfaceBsdf {
        let l = lambda.map_or(550.0, |l| l[i] as f32);
        self.model.at(Vec4::splat(l))
    }

    /// Lanes of a spectrum as the output row: r, g, b in RGB mode, lane 0 in spectral mode.
    fn lanes(&self, s: pt_spectrum::SampledSpectrum) -> [f32; 3] {
        match self.model.mode() {
            ColorMode::Rgb => [s.0.x, s.0.y, s.0.z],
            ColorMode::Spectral => [s.0.x; 3],
        }
    }

    fn check(&self, n: usize, lambda: &Option<PyReadonlyArray1<'_, f64>>) -> PyResult<()> {
        match (self.model.mode(), lambda) {
            (ColorMode::Spectral, None) => Err(PyValueError::new_err(
                "a spectral BSDF needs wavelengths (nm), one per direction",
            )),
            (ColorMode::Spectral, Some(l)) if l.as_array().len() != n => Err(
                PyValueError::new_err("wavelengths must hold one value per direction"),
            ),
            (ColorMode::Rgb, Some(_)) => Err(PyValueError::new_err(
                "an RGB BSDF takes no wavelengths (build it with mode='spectral')",
            )),
            _ => Ok(()),
        }
    }
}

#[pymethods]
impl Bsdf {
    /// f(wo, wi) per row (no cosine): (N, 3), lane 0 in all three columns in spectral mode.
    #[pyo3(signature = (wo, wi, wavelengths=None))]
    fn eval<'py>(
        &self,
        py: Python<'py>,
        wo: PyReadonlyArray2<'py, f64>,
        wi: PyReadonlyArray2<'py, f64>,
        wavelengths: Option<PyReadonlyArray1<'py, f64>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let (wo, wi) = (wo.as_array(), wi.as_array());
        let n = wo.nrows();
        self.check(n, &wavelengths)?;
        let lambda = wavelengths.as_ref().map(|l| l.as_array());
        let mut out = Array2::<f32>::zeros((n, 3));
        for i in 0..n {
            let f = self.at(lambda.as_ref(), i).eval(row3(&wo, i), row3(&wi, i));
            let v = self.lanes(f);
            for c in 0..3 {
                out[[i, c]] = v[c];
            }
        }
        Ok(out.into_pyarray(py))
    }

    /// Solid-angle pdf of sampling wi given wo, per row: (N,).
    #[pyo3(signature = (wo, wi, wavelengths=None))]
    fn pdf<'py>(
        &self,
        py: Python<'py>,
        wo: PyReadonlyArray2<'py, f64>,
        wi: PyReadonlyArray2<'py, f64>,
        wavelengths: Option<PyReadonlyArray1<'py, f64>>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let (wo, wi) = (wo.as_array(), wi.as_array());
        let n = wo.nrows();
        self.check(n, &wavelengths)?;
        let lambda = wavelengths.as_ref().map(|l| l.as_array());
        let out: Array1<f32> = (0..n)
            .map(|i| self.at(lambda.as_ref(), i).pdf(row3(&wo, i), row3(&wi, i)))
            .collect();
        Ok(out.into_pyarray(py))
    }

    /// Samples wi given wo and uniform numbers u (N, 3: lobe choice, then two for the
    /// direction): (wi (N, 3), weight (N, 3), pdf (N,), delta (N,), valid (N,)).
    #[pyo3(signature = (wo, u, wavelengths=None))]
    #[allow(clippy::type_complexity)]
    fn sample<'py>(
        &self,
        py: Python<'py>,
        wo: PyReadonlyArray2<'py, f64>,
        u: PyReadonlyArray2<'py, f64>,
        wavelengths: Option<PyReadonlyArray1<'py, f64>>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray1<f32>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyArray1<bool>>,
    )> {
        let (wo, u) = (wo.as_array(), u.as_array());
        let n = wo.nrows();
        self.check(n, &wavelengths)?;
        let lambda = wavelengths.as_ref().map(|l| l.as_array());
        let mut wi = Array2::<f32>::zeros((n, 3));
        let mut weight = Array2::<f32>::zeros((n, 3));
        let mut pdf = Array1::<f32>::zeros(n);
        let mut delta = Array1::from_elem(n, false);
        let mut valid = Array1::from_elem(n, false);
        for i in 0..n {
            let b = self.at(lambda.as_ref(), i);
            let uv = Vec2::new(u[[i, 1]] as f32, u[[i, 2]] as f32);
            if let Some(s) = b.sample(row3(&wo, i), u[[i, 0]] as f32, uv) {
                let w = self.lanes(s.weight);
                for c in 0..3 {
                    wi[[i, c]] = s.wi.to_array()[c];
                    weight[[i, c]] = w[c];
                }
                pdf[i] = s.pdf;
                delta[i] = s.delta;
                valid[i] = true;
            }
        }
        Ok((
            wi.into_pyarray(py),
            weight.into_pyarray(py),
            pdf.into_pyarray(py),
            delta.into_pyarray(py),
            valid.into_pyarray(py),
        ))
    }

    /// `rgb` or `spectral`.
    #[getter]
    fn mode(&self) -> &'static str {
        match self.model.mode() {
            ColorMode::Rgb => "rgb",
            ColorMode::Spectral => "spectral",
        }
    }

    fn __repr__(&self) -> String {
        format!("<pt_renderer.Bsdf {} ({})>", self.label, self.mode())
    }
}

/// The models `bsdf` builds and their parameters.
#[pyfunction]
fn bsdf_models() -> Vec<(&'static str, Vec<&'static str>)> {
    pt_lab::bsdf::MODELS
        .iter()
        .map(|m| (m.name, m.params.to_vec()))
        .collect()
}

/// Runs `pt converge`'s analysis; returns (series: [(name, [(spp, seconds, relmse, rmse,
/// flip)])], summary text). Files go to `out`.
#[pyfunction]
#[pyo3(signature = (scene, reference, spp, strategies, integrators, modes, out, threads, max_depth, seed, defines, mitsuba_python, log))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn converge(
    py: Python<'_>,
    scene: PathBuf,
    reference: PathBuf,
    spp: Vec<u32>,
    strategies: Vec<String>,
    integrators: Vec<String>,
    modes: Vec<String>,
    out: PathBuf,
    threads: Option<usize>,
    max_depth: Option<i32>,
    seed: u64,
    defines: Vec<(String, String)>,
    mitsuba_python: Option<PathBuf>,
    log: Option<Py<PyAny>>,
) -> PyResult<(Vec<(String, Vec<(u32, f64, f64, f64, f32)>)>, String)> {
    use pt_lab::converge::{ConvergeSettings, Method, MitsubaRun, MitsubaVariant};
    if spp.is_empty() || spp.contains(&0) {
        return Err(PyValueError::new_err(
            "spp needs sample counts of at least 1",
        ));
    }
    let strategies = strategies
        .iter()
        .map(|s| {
            pt_lab::converge::strategy_named(s).ok_or_else(|| {
                PyValueError::new_err(format!(
                    "unknown strategy '{s}' ({})",
                    pt_lab::converge::STRATEGIES.join(", ")
                ))
            })
        })
        .collect::<PyResult<Vec<_>>>()?;
    let integrators = integrators
        .iter()
        .map(|s| {
            Method::named(s).ok_or_else(|| {
                PyValueError::new_err(format!(
                    "unknown integrator '{s}' ({})",
                    Method::NAMES.join(", ")
                ))
            })
        })
        .collect::<PyResult<Vec<_>>>()?;
    let modes = modes
        .iter()
        .map(|m| color_mode(Some(m)).map(|m| m.unwrap_or(ColorMode::Rgb)))
        .collect::<PyResult<Vec<_>>>()?;
    let mitsuba = match mitsuba_python {
        None => None,
        Some(python) => Some(MitsubaRun {
            script: pt_lab::converge::mitsuba::script()
                .map_err(|e| PyValueError::new_err(e.to_string()))?,
            python,
            variant: MitsubaVariant::LlvmAdRgb,
            threads,
        }),
    };
    let settings = ConvergeSettings {
        scene,
        defines,
        reference,
        spp,
        strategies,
        integrators,
        modes,
        out,
        max_depth,
        seed,
        mitsuba,
        radiosity_patch_sizes: Vec::new(),
        radiosity_rays: 1024,
    };
    let pool = thread_pool(threads)?;
    let result = py.detach(|| {
        pool.install(|| {
            pt_lab::converge::run(&settings, &|line| {
                if let Some(cb) = &log {
                    Python::attach(|py| {
                        // A failing logger must not stop the measurement; Python reports it.
                        if let Err(e) = cb.call1(py, (line,)) {
                            e.write_unraisable(py, None);
                        }
                    });
                }
            })
        })
    });
    let c = result.map_err(scene_error)?;
    let series = c
        .series
        .iter()
        .map(|s| {
            (
                s.name.clone(),
                s.points
                    .iter()
                    .map(|p| (p.spp, p.seconds, p.relmse, p.rmse, p.flip))
                    .collect(),
            )
        })
        .collect();
    Ok((series, c.summary))
}

/// The compiled module.
#[pymodule]
fn _pt_renderer(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("METHODS", pt_integrators::METHODS.to_vec())?;
    m.add("VERSION", env!("CARGO_PKG_VERSION"))?;
    m.add("BUILTIN_CORNELL", pt_scene::BUILTIN_CORNELL)?;
    m.add_class::<Scene>()?;
    m.add_class::<Bsdf>()?;
    m.add_function(wrap_pyfunction!(load_file, m)?)?;
    m.add_function(wrap_pyfunction!(load_string, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr_channels, m)?)?;
    m.add_function(wrap_pyfunction!(write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(bsdf, m)?)?;
    m.add_function(wrap_pyfunction!(bsdf_models, m)?)?;
    m.add_function(wrap_pyfunction!(converge, m)?)?;
    Ok(())
}

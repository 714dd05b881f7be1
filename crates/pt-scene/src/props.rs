//! Property elements (`<float>`, `<rgb>`, `<transform>`, ...) and the per-object property list
//! that plugins read from. Every read marks the property as used, so that properties a plugin
//! never reads are reported as errors, as Mitsuba 3 does.

use crate::error::{Result, SceneError};
use crate::ir::SpectrumDesc;
use crate::transform;
use crate::xml::Element;
use glam::{Mat4, Vec3};
use std::cell::Cell;

/// Tags of property elements.
const PROPERTY_TAGS: &[&str] = &[
    "float",
    "integer",
    "boolean",
    "string",
    "rgb",
    "spectrum",
    "point",
    "vector",
    "transform",
];

/// Tags of transform operations, valid only inside `<transform>`.
const TRANSFORM_OPS: &[&str] = &["translate", "rotate", "scale", "matrix", "lookat"];

/// A parsed property value.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    Float(f64),
    Integer(i64),
    Boolean(bool),
    Str(String),
    Rgb([f32; 3]),
    /// A constant spectrum (`<spectrum value="0.5"/>`).
    Spectrum(f32),
    /// `wavelength:value` pairs (nm, value), sorted by wavelength (from `value` or `filename`).
    SpectrumPairs(Vec<(f32, f32)>),
    /// A spectrum plugin (`<spectrum type="blackbody">`, `type="d65"`, ...).
    SpectrumPlugin(SpectrumDesc),
    /// `<point>` or `<vector>`.
    Vec3(Vec3),
    Transform(Mat4),
}

impl Value {
    fn type_name(&self) -> &'static str {
        match self {
            Value::Float(_) => "float",
            Value::Integer(_) => "integer",
            Value::Boolean(_) => "boolean",
            Value::Str(_) => "string",
            Value::Rgb(_) => "rgb",
            Value::Spectrum(_) | Value::SpectrumPairs(_) | Value::SpectrumPlugin(_) => "spectrum",
            Value::Vec3(_) => "point/vector",
            Value::Transform(_) => "transform",
        }
    }
}

/// A property value given in code rather than read from a file: what a `<float>`, `<rgb>`,
/// `<string>` or `<boolean>` element holds (see [`crate::bsdf_from_properties`]).
#[derive(Clone, Debug, PartialEq)]
pub enum PropValue {
    /// A number (`<float>`); also read where a spectrum is expected, as in a file.
    Float(f32),
    /// A linear sRGB colour (`<rgb>`).
    Rgb([f32; 3]),
    /// A name (`<string>`): `variant="full"`, `material="Au"`, `int_ior="bk7"`, ...
    String(String),
    /// A flag (`<boolean>`).
    Boolean(bool),
}

impl From<f32> for PropValue {
    fn from(x: f32) -> Self {
        PropValue::Float(x)
    }
}

impl From<[f32; 3]> for PropValue {
    fn from(c: [f32; 3]) -> Self {
        PropValue::Rgb(c)
    }
}

impl From<&str> for PropValue {
    fn from(s: &str) -> Self {
        PropValue::String(s.to_string())
    }
}

impl From<bool> for PropValue {
    fn from(b: bool) -> Self {
        PropValue::Boolean(b)
    }
}

impl PropValue {
    /// The parsed value, checked as the parser checks written ones (finite numbers).
    fn value(&self) -> std::result::Result<Value, String> {
        let finite = |x: f32| {
            if x.is_finite() {
                Ok(f64::from(x))
            } else {
                Err(format!("number '{x}' is not finite"))
            }
        };
        Ok(match self {
            PropValue::Float(x) => Value::Float(finite(*x)?),
            PropValue::Rgb(c) => {
                for &x in c {
                    finite(x)?;
                }
                Value::Rgb(*c)
            }
            PropValue::String(s) => Value::Str(s.clone()),
            PropValue::Boolean(b) => Value::Boolean(*b),
        })
    }
}

/// One property of an object, remembering whether the plugin read it.
struct Prop<'e> {
    name: String,
    value: Value,
    el: &'e Element,
    used: Cell<bool>,
}

/// A nested object element or a `<ref>` to one, in document order.
#[derive(Clone, Copy)]
pub(crate) enum Child<'e> {
    /// An object written inline.
    Object(&'e Element),
    /// `<ref id="..."/>`: the element is the `<ref>` itself.
    Ref(&'e Element),
}

impl<'e> Child<'e> {
    /// The element written in the parent (the object or the `<ref>`), for error locations.
    pub fn written(&self) -> &'e Element {
        match self {
            Child::Object(e) | Child::Ref(e) => e,
        }
    }
}

/// An object element split into its properties and its nested objects.
pub(crate) struct ObjectView<'e> {
    /// The object element.
    pub el: &'e Element,
    /// The plugin name (`type` attribute).
    pub plugin: String,
    props: Vec<Prop<'e>>,
    /// Nested objects and references, in document order.
    pub children: Vec<Child<'e>>,
}

impl<'e> ObjectView<'e> {
    /// Splits the object element `el` (checks its attributes and parses its properties).
    pub fn parse(el: &'e Element) -> Result<Self> {
        el.check_attrs(&["type", "id", "name"], &["type"])?;
        let plugin = el.attr("type").unwrap_or_default().to_string();
        let mut view = ObjectView {
            el,
            plugin,
            props: Vec::new(),
            children: Vec::new(),
        };
        for child in &el.children {
            view.add_child(child)?;
        }
        Ok(view)
    }

    /// An object given in code: `el` (no children) names the plugin and stands for the object
    /// and each of its `props` in error messages. Names must be unique and numbers finite, as
    /// in a file.
    pub fn from_props(el: &'e Element, props: &[(String, PropValue)]) -> Result<Self> {
        let mut view = ObjectView::parse(el)?;
        for (name, value) in props {
            if view.props.iter().any(|p| p.name == *name) {
                return Err(SceneError::at(
                    &el.loc,
                    format!("property '{name}' is given twice"),
                ));
            }
            let value = value
                .value()
                .map_err(|m| SceneError::at(&el.loc, format!("property '{name}': {m}")))?;
            view.props.push(Prop {
                name: name.clone(),
                value,
                el,
                used: Cell::new(false),
            });
        }
        Ok(view)
    }

    /// Like [`ObjectView::parse`] for the root `<scene>`, which has no `type`.
    pub fn parse_scene(el: &'e Element) -> Result<Self> {
        let mut view = ObjectView {
            el,
            plugin: "scene".into(),
            props: Vec::new(),
            children: Vec::new(),
        };
        for child in &el.children {
            view.add_child(child)?;
        }
        Ok(view)
    }

    fn add_child(&mut self, child: &'e Element) -> Result<()> {
        let tag = child.tag.as_str();
        if child.is_object() {
            if tag == "scene" {
                return Err(SceneError::at(
                    &child.loc,
                    "<scene> can only be the root element",
                ));
            }
            self.children.push(Child::Object(child));
        } else if tag == "ref" {
            child.check_attrs(&["id", "name"], &["id"])?;
            no_children(child)?;
            self.children.push(Child::Ref(child));
        } else if PROPERTY_TAGS.contains(&tag) {
            self.add_prop(child)?;
        } else if tag == "alias" {
            // A second name for an object, registered with the ids before building
            // (`build::collect_ids`); nothing of its own here.
        } else {
            return Err(misplaced(child));
        }
        Ok(())
    }

    fn add_prop(&mut self, el: &'e Element) -> Result<()> {
        let value = parse_value(el)?;
        let name = el.attr("name").unwrap_or_default().to_string();
        if let Some(first) = self.props.iter().find(|p| p.name == name) {
            let l = &first.el.loc;
            return Err(SceneError::at(
                &el.loc,
                format!(
                    "property '{name}' is given twice (first at line {}, column {})",
                    l.line, l.col
                ),
            ));
        }
        self.props.push(Prop {
            name,
            value,
            el,
            used: Cell::new(false),
        });
        Ok(())
    }

    /// How messages name this object, e.g. `sensor "perspective"`.
    pub fn what(&self) -> String {
        if self.el.tag == "scene" {
            return "the scene".into();
        }
        format!("{} \"{}\"", self.el.tag, self.plugin)
    }

    /// Whether property `name` is present (does not mark it used).
    pub fn has(&self, name: &str) -> bool {
        self.props.iter().any(|p| p.name == name)
    }

    /// Looks a property up and marks it used.
    fn get(&self, name: &str) -> Option<&Prop<'e>> {
        let prop = self.props.iter().find(|p| p.name == name)?;
        prop.used.set(true);
        Some(prop)
    }

    fn type_error(&self, prop: &Prop<'_>, expected: &str) -> SceneError {
        SceneError::at(
            &prop.el.loc,
            format!(
                "property '{}' of {} must be {expected}, not {}",
                prop.name,
                self.what(),
                prop.value.type_name()
            ),
        )
    }

    /// An error about property `name` (at its element), e.g. for an out-of-range value.
    pub fn prop_error(&self, name: &str, message: impl Into<String>) -> SceneError {
        let loc = self
            .props
            .iter()
            .find(|p| p.name == name)
            .map_or(&self.el.loc, |p| &p.el.loc);
        SceneError::at(loc, message)
    }

    /// A float property; integers are accepted too, as in Mitsuba.
    pub fn float(&self, name: &str) -> Result<Option<f32>> {
        let Some(prop) = self.get(name) else {
            return Ok(None);
        };
        let wide = match prop.value {
            Value::Float(v) => v,
            Value::Integer(v) => v as f64,
            _ => return Err(self.type_error(prop, "a float")),
        };
        let narrow = wide as f32;
        if !narrow.is_finite() {
            return Err(SceneError::at(
                &prop.el.loc,
                format!("value {wide} does not fit a 32-bit float"),
            ));
        }
        Ok(Some(narrow))
    }

    /// An integer property.
    pub fn integer(&self, name: &str) -> Result<Option<i64>> {
        let Some(prop) = self.get(name) else {
            return Ok(None);
        };
        match prop.value {
            Value::Integer(v) => Ok(Some(v)),
            _ => Err(self.type_error(prop, "an integer")),
        }
    }

    /// A boolean property.
    pub fn boolean(&self, name: &str) -> Result<Option<bool>> {
        let Some(prop) = self.get(name) else {
            return Ok(None);
        };
        match prop.value {
            Value::Boolean(v) => Ok(Some(v)),
            _ => Err(self.type_error(prop, "a boolean")),
        }
    }

    /// A property that may be a number or a name (Mitsuba's `int_ior="bk7"` or `1.5`).
    pub fn float_or_string(&self, name: &str) -> Result<Option<std::result::Result<f32, String>>> {
        let Some(prop) = self.props.iter().find(|p| p.name == name) else {
            return Ok(None);
        };
        match &prop.value {
            Value::Str(v) => {
                prop.used.set(true);
                Ok(Some(Err(v.clone())))
            }
            _ => Ok(self.float(name)?.map(Ok)),
        }
    }

    /// A string property.
    pub fn string(&self, name: &str) -> Result<Option<String>> {
        let Some(prop) = self.get(name) else {
            return Ok(None);
        };
        match &prop.value {
            Value::Str(v) => Ok(Some(v.clone())),
            _ => Err(self.type_error(prop, "a string")),
        }
    }

    /// A spectrum-valued property: `<rgb>`, `<spectrum>` (one number, pairs, a file, a plugin
    /// such as a blackbody or a named illuminant), or a plain number.
    pub fn spectrum(&self, name: &str) -> Result<Option<SpectrumDesc>> {
        let Some(prop) = self.get(name) else {
            return Ok(None);
        };
        match prop.value {
            Value::Rgb(c) => Ok(Some(SpectrumDesc::Rgb(c))),
            Value::Spectrum(v) => Ok(Some(SpectrumDesc::Uniform(v))),
            Value::SpectrumPairs(ref pairs) => Ok(Some(SpectrumDesc::Tabulated(
                std::sync::Arc::new(pairs.clone()),
            ))),
            Value::SpectrumPlugin(ref s) => Ok(Some(s.clone())),
            Value::Float(v) => Ok(Some(SpectrumDesc::Constant(v as f32))),
            Value::Integer(v) => Ok(Some(SpectrumDesc::Constant(v as f32))),
            _ => Err(self.type_error(prop, "an rgb, spectrum or float")),
        }
    }

    /// A `<point>` or `<vector>` property.
    pub fn vec3(&self, name: &str) -> Result<Option<Vec3>> {
        let Some(prop) = self.get(name) else {
            return Ok(None);
        };
        match prop.value {
            Value::Vec3(v) => Ok(Some(v)),
            _ => Err(self.type_error(prop, "a point or vector")),
        }
    }

    /// A `<transform>` property.
    pub fn transform(&self, name: &str) -> Result<Option<Mat4>> {
        let Some(prop) = self.get(name) else {
            return Ok(None);
        };
        match prop.value {
            Value::Transform(m) => Ok(Some(m)),
            _ => Err(self.type_error(prop, "a transform")),
        }
    }

    /// Errors on the first property (in document order) that the plugin never read: a typo or
    /// a parameter this renderer does not support. Mitsuba 3 rejects those too.
    pub fn finish(&self) -> Result<()> {
        match self.props.iter().find(|p| !p.used.get()) {
            Some(p) => Err(SceneError::at(
                &p.el.loc,
                format!(
                    "unused property '{}': {} does not have this parameter",
                    p.name,
                    self.what()
                ),
            )),
            None => Ok(()),
        }
    }
}

fn no_children(el: &Element) -> Result<()> {
    match el.children.first() {
        Some(c) => Err(SceneError::at(
            &c.loc,
            format!("<{}> cannot contain elements", el.tag),
        )),
        None => Ok(()),
    }
}

/// The error for an element that has no place where it occurs.
fn misplaced(el: &Element) -> SceneError {
    let tag = el.tag.as_str();
    let message = match tag {
        t if TRANSFORM_OPS.contains(&t) => format!("<{t}> can only occur inside a <transform>"),
        "default" | "include" | "path" => format!("<{tag}> cannot occur inside a property"),
        "lookAt" => "unknown element <lookAt> (write <lookat>; camelCase is only \
                     accepted in scenes with version < 2.0.0)"
            .to_string(),
        _ => format!("unknown element <{tag}>"),
    };
    SceneError::at(&el.loc, message)
}

/// Parses a property element's value.
fn parse_value(el: &Element) -> Result<Value> {
    let tag = el.tag.as_str();
    if tag != "transform" && !(tag == "spectrum" && el.attr("type").is_some()) {
        no_children(el)?;
    }
    let value = || el.attr("value").unwrap_or_default();
    let err = |m: String| SceneError::at(&el.loc, m);
    match tag {
        "float" => {
            el.check_attrs(&["name", "value"], &["name", "value"])?;
            parse_f64(value()).map(Value::Float).map_err(err)
        }
        "integer" => {
            el.check_attrs(&["name", "value"], &["name", "value"])?;
            parse_int(value()).map(Value::Integer).map_err(err)
        }
        "boolean" => {
            el.check_attrs(&["name", "value"], &["name", "value"])?;
            parse_bool(value()).map(Value::Boolean).map_err(err)
        }
        "string" => {
            el.check_attrs(&["name", "value"], &["name", "value"])?;
            Ok(Value::Str(value().to_string()))
        }
        "rgb" => {
            el.check_attrs(&["name", "value"], &["name", "value"])?;
            parse_rgb(value()).map(Value::Rgb).map_err(err)
        }
        "spectrum" => parse_spectrum(el),
        "point" | "vector" => {
            el.check_attrs(&["name", "value", "x", "y", "z"], &["name"])?;
            transform::xyz(el, 0.0).map(Value::Vec3)
        }
        _ => {
            el.check_attrs(&["name"], &["name"])?;
            transform::parse_transform(el).map(Value::Transform)
        }
    }
}

/// `<spectrum>`: `value` (one number or `wavelength:value` pairs), `filename` (a file of pairs),
/// or `type` (a spectrum plugin, see [`parse_spectrum_plugin`]).
fn parse_spectrum(el: &Element) -> Result<Value> {
    if el.attr("type").is_some() {
        return parse_spectrum_plugin(el).map(Value::SpectrumPlugin);
    }
    el.check_attrs(&["name", "value", "filename"], &["name"])?;
    if let Some(name) = el.attr("filename") {
        if el.attr("value").is_some() {
            return Err(SceneError::at(
                &el.loc,
                "give either 'value' or 'filename', not both",
            ));
        }
        return read_spectrum_file(el, name).map(Value::SpectrumPairs);
    }
    let text = el
        .attr("value")
        .ok_or_else(|| SceneError::at(&el.loc, "missing attribute 'value'"))?;
    if text.contains(':') {
        return parse_pairs(text)
            .map(Value::SpectrumPairs)
            .map_err(|m| SceneError::at(&el.loc, m));
    }
    match parse_floats(text).map_err(|m| SceneError::at(&el.loc, m))?[..] {
        [v] => Ok(Value::Spectrum(v)),
        _ => Err(SceneError::at(
            &el.loc,
            format!("expected one number or wavelength:value pairs in '{text}'"),
        )),
    }
}

/// Mitsuba's `<spectrum filename="..."/>`: an ASCII file with one `wavelength value` pair per
/// line (nm; separated by whitespace or a comma), `#` starting a comment, blank lines ignored;
/// wavelengths strictly increasing, at least two pairs. Zero outside the tabulated range, as the
/// `value` pairs. The name is resolved relative to the XML file that contains the element
/// (absolute names as they are); `<path>` folders are not searched for spectrum files.
fn read_spectrum_file(el: &Element, name: &str) -> Result<Vec<(f32, f32)>> {
    let path = crate::xml::resolve_file(name, &el.dir, &[], &[]);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        SceneError::at(
            &el.loc,
            format!(
                "cannot read spectrum file '{name}' ({}): {e}",
                path.display()
            ),
        )
    })?;
    let mut pairs: Vec<(f32, f32)> = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let data = line.split('#').next().unwrap_or_default().trim();
        if data.is_empty() {
            continue;
        }
        let at = |m: String| {
            SceneError::at(
                &el.loc,
                format!("spectrum file '{}', line {}: {m}", path.display(), i + 1),
            )
        };
        let nums = parse_floats(data).map_err(at)?;
        let [l, v] = nums[..] else {
            return Err(at(format!("expected 'wavelength value', got '{data}'")));
        };
        if !(l > 0.0) {
            return Err(at(format!("wavelength {l} nm must be positive")));
        }
        if let Some(&(prev, _)) = pairs.last() {
            if l <= prev {
                return Err(at(format!(
                    "wavelengths must increase: {l} nm after {prev} nm"
                )));
            }
        }
        pairs.push((l, v));
    }
    if pairs.len() < 2 {
        return Err(SceneError::at(
            &el.loc,
            format!(
                "spectrum file '{}' has {} wavelength/value pairs; at least two are needed",
                path.display(),
                pairs.len()
            ),
        ));
    }
    Ok(pairs)
}

/// `<spectrum type="..">` plugins:
/// - `blackbody` with `<float name="temperature">` (K, required, > 0): Planck's law,
///   unnormalised, as Mitsuba 3.9's `blackbody` (which has no other parameter);
/// - `d65` with `<float name="scale">` (default 1): CIE D65 of luminance Y = scale, as
///   Mitsuba's `d65` (whose `color` parameter is not supported);
/// - project extension, same form as `d65`: `a` (CIE illuminant A) and `f1` .. `f12` (the CIE
///   fluorescent lamps). Mitsuba has no plugin of these names, so such scenes render only in pt.
fn parse_spectrum_plugin(el: &Element) -> Result<SpectrumDesc> {
    el.check_attrs(&["name", "type"], &["name", "type"])?;
    let plugin = el.attr("type").unwrap_or_default().to_ascii_lowercase();
    let mut temperature = None;
    let mut scale = None;
    for c in &el.children {
        c.check_attrs(&["name", "value"], &["name", "value"])?;
        no_children(c)?;
        let pname = c.attr("name").unwrap_or_default();
        let slot = match (plugin.as_str(), pname) {
            ("blackbody", "temperature") => &mut temperature,
            (p, "scale") if p != "blackbody" => &mut scale,
            _ => {
                return Err(SceneError::at(
                    &c.loc,
                    format!(
                    "unused property '{pname}': spectrum \"{plugin}\" does not have this parameter"
                ),
                ))
            }
        };
        if c.tag != "float" && c.tag != "integer" {
            return Err(SceneError::at(
                &c.loc,
                format!("property '{pname}' must be a float, not {}", c.tag),
            ));
        }
        if slot.is_some() {
            return Err(SceneError::at(
                &c.loc,
                format!("property '{pname}' is given twice"),
            ));
        }
        *slot = Some(
            parse_f32(c.attr("value").unwrap_or_default())
                .map_err(|m| SceneError::at(&c.loc, m))?,
        );
    }
    match plugin.as_str() {
        "blackbody" => {
            let t = temperature.ok_or_else(|| {
                SceneError::at(
                    &el.loc,
                    "spectrum \"blackbody\" needs <float name=\"temperature\"> (K)",
                )
            })?;
            if !(t > 0.0) {
                return Err(SceneError::at(
                    &el.loc,
                    format!("blackbody temperature must be positive, got {t} K"),
                ));
            }
            Ok(SpectrumDesc::Blackbody { temperature: t })
        }
        "d65" | "a" => Ok(SpectrumDesc::Illuminant {
            name: plugin,
            scale: checked_scale(el, scale)?,
        }),
        p if p
            .strip_prefix('f')
            .and_then(|k| k.parse::<u8>().ok())
            .is_some_and(|k| (1..=12).contains(&k) && p == format!("f{k}")) =>
        {
            Ok(SpectrumDesc::Illuminant {
                name: plugin,
                scale: checked_scale(el, scale)?,
            })
        }
        _ => Err(SceneError::at(
            &el.loc,
            format!("unknown spectrum type '{plugin}' (known: blackbody, d65, a, f1 .. f12)"),
        )),
    }
}

/// An illuminant's `scale` (luminance), default 1, must be >= 0.
fn checked_scale(el: &Element, scale: Option<f32>) -> Result<f32> {
    let s = scale.unwrap_or(1.0);
    if !(s >= 0.0) {
        return Err(SceneError::at(
            &el.loc,
            format!("illuminant scale must not be negative, got {s}"),
        ));
    }
    Ok(s)
}

/// Parses Mitsuba's `"400:0.1, 500:0.5"`: wavelengths in nm, strictly increasing, at least two
/// pairs, all values finite.
fn parse_pairs(text: &str) -> std::result::Result<Vec<(f32, f32)>, String> {
    let mut pairs = Vec::new();
    for item in text.split(',').map(str::trim).filter(|t| !t.is_empty()) {
        let (l, v) = item
            .split_once(':')
            .ok_or_else(|| format!("expected wavelength:value, got '{item}'"))?;
        let (l, v) = (parse_f32(l)?, parse_f32(v)?);
        if !(l > 0.0) {
            return Err(format!("wavelength {l} nm must be positive"));
        }
        if let Some(&(prev, _)) = pairs.last() {
            if l <= prev {
                return Err(format!("wavelengths must increase: {l} nm after {prev} nm"));
            }
        }
        pairs.push((l, v));
    }
    if pairs.len() < 2 {
        return Err(format!(
            "a tabulated spectrum needs at least two wavelength:value pairs, got '{text}'"
        ));
    }
    Ok(pairs)
}

/// Parses one finite number. NaN and infinities are errors: they would poison the render.
pub(crate) fn parse_f64(text: &str) -> std::result::Result<f64, String> {
    let t = text.trim();
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("number '{t}' is not finite")),
        Err(_) => Err(format!("cannot parse '{t}' as a number")),
    }
}

/// Parses one finite number that fits an `f32`.
pub(crate) fn parse_f32(text: &str) -> std::result::Result<f32, String> {
    let wide = parse_f64(text)?;
    let narrow = wide as f32;
    if narrow.is_finite() {
        Ok(narrow)
    } else {
        Err(format!(
            "number '{}' does not fit a 32-bit float",
            text.trim()
        ))
    }
}

/// Parses a list of numbers separated by commas and/or whitespace.
pub(crate) fn parse_floats(text: &str) -> std::result::Result<Vec<f32>, String> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(parse_f32)
        .collect()
}

fn parse_int(text: &str) -> std::result::Result<i64, String> {
    let t = text.trim();
    t.parse::<i64>()
        .map_err(|_| format!("cannot parse '{t}' as an integer"))
}

fn parse_bool(text: &str) -> std::result::Result<bool, String> {
    match text.trim().to_ascii_lowercase().as_str() {
        "true" => Ok(true),
        "false" => Ok(false),
        _ => Err(format!(
            "cannot parse '{}' as a boolean (expected true or false)",
            text.trim()
        )),
    }
}

/// `value="r, g, b"` or one number for all three channels.
fn parse_rgb(text: &str) -> std::result::Result<[f32; 3], String> {
    match parse_floats(text)?[..] {
        [v] => Ok([v; 3]),
        [r, g, b] => Ok([r, g, b]),
        _ => Err(format!("expected one or three numbers in '{text}'")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        assert_eq!(parse_f64(" 1.5 ").unwrap(), 1.5);
        assert!(parse_f64("nan").unwrap_err().contains("not finite"));
        assert!(parse_f64("inf").is_err());
        assert!(parse_f64("-infinity").is_err());
        assert!(parse_f64("1.0.0").unwrap_err().contains("cannot parse"));
        assert!(parse_f32("1e300").is_err());
        assert_eq!(parse_floats("1, 2 3,,4").unwrap(), vec![1.0, 2.0, 3.0, 4.0]);
        assert_eq!(parse_rgb("0.5").unwrap(), [0.5; 3]);
        assert!(parse_rgb("1 2").is_err());
        assert_eq!(parse_int("-3").unwrap(), -3);
        assert!(parse_int("3.5").is_err());
        assert!(parse_bool("TRUE").unwrap());
        assert!(parse_bool("yes").is_err());
    }
}

//! Reading Mitsuba XML into a plain element tree, and the file-level preprocessing that Mitsuba
//! does before it looks at plugins: `<default>` and `$name` substitution, `<include>`, `<path>`
//! and the in-memory upgrade of Mitsuba 0.x scenes (camelCase property names).
//!
//! The result is a tree of [`Element`]s in which every attribute value is final, every included
//! file is spliced in, and every element knows the file, line and column it came from.

use crate::error::{io_message, Result, SceneError};
use crate::ir::SourceLoc;
use std::path::{Path, PathBuf};

/// Tags that create objects (plugins with a `type`). `scene` is the root object.
pub(crate) const OBJECT_TAGS: &[&str] = &[
    "scene",
    "shape",
    "bsdf",
    "emitter",
    "sensor",
    "integrator",
    "film",
    "sampler",
    "rfilter",
    "texture",
    "medium",
    "phase",
    "volume",
];

/// Deepest element nesting accepted; real scenes use fewer than ten levels, and the limit keeps
/// the recursive passes from overflowing the stack on hostile input.
const MAX_DEPTH: usize = 64;

/// Mitsuba's limit on nested `<include>`s; it also ends include cycles.
const MAX_INCLUDE_DEPTH: usize = 15;

/// One XML element after preprocessing.
#[derive(Clone, Debug)]
pub(crate) struct Element {
    /// Tag name, e.g. `shape`.
    pub tag: String,
    /// Attributes in document order, values with `$name` already substituted.
    pub attrs: Vec<(String, String)>,
    /// Child elements (comments and processing instructions dropped).
    pub children: Vec<Element>,
    /// Where the element starts.
    pub loc: SourceLoc,
    /// Directory of the file the element was read from; relative filenames start here.
    pub dir: PathBuf,
}

impl Element {
    /// The value of attribute `name`, if present.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    /// Errors unless every attribute is in `allowed` and every one of `required` is present.
    pub fn check_attrs(&self, allowed: &[&str], required: &[&str]) -> Result<()> {
        if let Some((k, _)) = self
            .attrs
            .iter()
            .find(|(k, _)| !allowed.contains(&k.as_str()))
        {
            return Err(SceneError::at(
                &self.loc,
                format!(
                    "unexpected attribute '{k}' (allowed here: {})",
                    allowed.join(", ")
                ),
            ));
        }
        match required.iter().find(|r| self.attr(r).is_none()) {
            Some(r) => Err(SceneError::at(
                &self.loc,
                format!("missing attribute '{r}'"),
            )),
            None => Ok(()),
        }
    }

    /// Whether this element creates an object (has a plugin type).
    pub fn is_object(&self) -> bool {
        OBJECT_TAGS.contains(&self.tag.as_str())
    }
}

/// The preprocessed scene: the root `<scene>` element and the folders added by `<path>`.
pub(crate) struct Document {
    /// The root `<scene>` element with includes spliced in.
    pub root: Element,
    /// Folders from `<path>` elements, most recent first (Mitsuba prepends them).
    pub search_paths: Vec<PathBuf>,
}

/// Parses and preprocesses a scene. `params` are the command-line `-D` pairs; they take
/// precedence over the file's `<default>`s.
pub(crate) fn read_document(
    xml: &str,
    file: &Path,
    dir: &Path,
    params: &[(String, String)],
) -> Result<Document> {
    for (name, _) in params {
        if !is_param_name(name) {
            return Err(SceneError::global(format!(
                "invalid parameter name '{name}' (expected letters, digits and '_')"
            )));
        }
    }
    let mut raw = parse_raw(xml, file, dir)?;
    if raw.tag != "scene" {
        return Err(SceneError::at(&raw.loc, "the root element must be <scene>"));
    }
    let version = take_version(&mut raw)?
        .ok_or_else(|| SceneError::at(&raw.loc, "missing attribute 'version'"))?;
    raw.check_attrs(&[], &[])?;
    upgrade(&mut raw, version);
    let mut expander = Expander {
        params: params.to_vec(),
        used: vec![false; params.len()],
        main_dir: dir.to_path_buf(),
        search_paths: Vec::new(),
        includes: 0,
    };
    let children = std::mem::take(&mut raw.children);
    raw.children = expander.expand_children(children, 1)?;
    // Mitsuba 3 refuses a parameter given to the loader that the scene never substitutes
    // (even one it declares with <default>): a misspelt -D name would otherwise change nothing.
    let unused: Vec<String> = params
        .iter()
        .zip(&expander.used)
        .filter(|(_, used)| !**used)
        .map(|((k, v), _)| format!("${k}={v}"))
        .collect();
    if !unused.is_empty() {
        return Err(SceneError::global(format!(
            "{}: unused parameter{} {} (the scene never uses {}; Mitsuba 3 refuses {} too)",
            file.display(),
            if unused.len() == 1 { "" } else { "s" },
            unused.join(", "),
            if unused.len() == 1 { "it" } else { "them" },
            if unused.len() == 1 { "it" } else { "them" },
        )));
    }
    Ok(Document {
        root: raw,
        search_paths: expander.search_paths,
    })
}

fn is_param_name(name: &str) -> bool {
    !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

// ---------------------------------------------------------------------------------------------
// Raw XML -> Element

/// Maps byte offsets to 1-based line and column (in characters). Computing positions with a
/// line table keeps this linear in the file size (roxmltree's own lookup rescans the text).
struct LineIndex<'a> {
    text: &'a str,
    starts: Vec<usize>,
}

impl<'a> LineIndex<'a> {
    fn new(text: &'a str) -> Self {
        let mut starts = vec![0];
        starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        LineIndex { text, starts }
    }

    fn position(&self, offset: usize) -> (u32, u32) {
        let line = self.starts.partition_point(|&s| s <= offset).max(1) - 1;
        let start = self.starts.get(line).copied().unwrap_or(0);
        let col = self
            .text
            .get(start..offset)
            .map_or(0, |s| s.chars().count());
        (saturate(line + 1), saturate(col + 1))
    }
}

fn saturate(v: usize) -> u32 {
    u32::try_from(v).unwrap_or(u32::MAX)
}

fn parse_raw(xml: &str, file: &Path, dir: &Path) -> Result<Element> {
    let options = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(xml, options).map_err(|e| {
        let pos = e.pos();
        let loc = SourceLoc {
            file: file.to_path_buf(),
            line: pos.row,
            col: pos.col,
            element: "xml".into(),
        };
        SceneError::at(&loc, format!("malformed XML: {e}"))
    })?;
    let lines = LineIndex::new(xml);
    convert(doc.root_element(), &lines, file, dir, 0)
}

fn convert(
    node: roxmltree::Node<'_, '_>,
    lines: &LineIndex<'_>,
    file: &Path,
    dir: &Path,
    depth: usize,
) -> Result<Element> {
    let tag = node.tag_name().name().to_string();
    let attrs: Vec<(String, String)> = node
        .attributes()
        .map(|a| (a.name().to_string(), a.value().to_string()))
        .collect();
    let (line, col) = lines.position(node.range().start);
    let loc = SourceLoc {
        file: file.to_path_buf(),
        line,
        col,
        element: describe(&tag, &attrs),
    };
    if depth > MAX_DEPTH {
        return Err(SceneError::at(
            &loc,
            format!("elements nested deeper than {MAX_DEPTH} levels"),
        ));
    }
    let mut children = Vec::new();
    for child in node.children() {
        if child.is_element() {
            children.push(convert(child, lines, file, dir, depth + 1)?);
        } else if child.is_text() && child.text().is_some_and(|t| !t.trim().is_empty()) {
            return Err(SceneError::at(
                &loc,
                "unexpected text content inside the element",
            ));
        }
    }
    Ok(Element {
        tag,
        attrs,
        children,
        loc,
        dir: dir.to_path_buf(),
    })
}

/// The element as it is named in messages: the tag plus the attribute that identifies it
/// (`type` for objects, `name` for properties, ...), with the value as written in the file.
fn describe(tag: &str, attrs: &[(String, String)]) -> String {
    let key = match tag {
        "ref" => "id",
        "include" => "filename",
        "path" => "value",
        t if OBJECT_TAGS.contains(&t) => "type",
        _ => "name",
    };
    match attrs.iter().find(|(k, _)| k == key) {
        Some((_, v)) => format!("{tag} {key}=\"{v}\""),
        None => tag.to_string(),
    }
}

// ---------------------------------------------------------------------------------------------
// Versions and the Mitsuba 0.x upgrade

/// A scene format version `major.minor.patch`.
type Version = (u32, u32, u32);

/// Removes and parses the `version` attribute, if present.
fn take_version(el: &mut Element) -> Result<Option<Version>> {
    let Some(pos) = el.attrs.iter().position(|(k, _)| k == "version") else {
        return Ok(None);
    };
    let (_, text) = el.attrs.remove(pos);
    let parts: Vec<&str> = text.split(['.', ' ']).filter(|s| !s.is_empty()).collect();
    let nums: Vec<u32> = parts.iter().filter_map(|p| p.parse().ok()).collect();
    match nums[..] {
        [a, b, c] if parts.len() == 3 => Ok(Some((a, b, c))),
        _ => Err(SceneError::at(
            &el.loc,
            format!("cannot parse version '{text}' (expected major.minor.patch, e.g. 3.0.0)"),
        )),
    }
}

/// Mitsuba 3 upgrades pre-2.0 scenes in memory: camelCase property names become snake_case,
/// `<lookAt>` becomes `<lookat>`, and diffuse's `diffuse_reflectance` becomes `reflectance`.
fn upgrade(el: &mut Element, version: Version) {
    if version < (2, 0, 0) {
        upgrade_v1(el);
    }
}

fn upgrade_v1(el: &mut Element) {
    if el.tag == "lookAt" {
        el.tag = "lookat".into();
    }
    // `<default name>` names parameters, not properties: Mitsuba leaves them alone.
    if el.tag != "default" {
        for (k, v) in el.attrs.iter_mut() {
            if k == "name" {
                *v = camel_to_snake(v);
            }
        }
    }
    for child in &mut el.children {
        upgrade_v1(child);
    }
    if el.tag == "bsdf" && el.attr("type") == Some("diffuse") {
        for child in &mut el.children {
            for (k, v) in child.attrs.iter_mut() {
                if k == "name" && v == "diffuse_reflectance" {
                    *v = "reflectance".into();
                }
            }
        }
    }
}

/// Mitsuba's rule: an underscore goes between a lower-case letter and the upper-case run that
/// follows it, and that run is lower-cased (`toWorld` -> `to_world`, `intIOR` -> `int_ior`).
pub(crate) fn camel_to_snake(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        out.push(c);
        let next_upper = chars.get(i + 1).is_some_and(|n| n.is_ascii_uppercase());
        i += 1;
        if c.is_ascii_lowercase() && next_upper {
            out.push('_');
            while let Some(u) = chars.get(i).filter(|u| u.is_ascii_uppercase()) {
                out.push(u.to_ascii_lowercase());
                i += 1;
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Expansion: defaults, substitution, include, path

struct Expander {
    /// Known parameters, first definition wins (command line first, then `<default>`s).
    params: Vec<(String, String)>,
    /// Whether each of `params` was substituted somewhere.
    used: Vec<bool>,
    /// The main scene file's folder: where Mitsuba's file resolver starts.
    main_dir: PathBuf,
    /// Folders from `<path>`, most recent first.
    search_paths: Vec<PathBuf>,
    /// Current `<include>` nesting.
    includes: usize,
}

impl Expander {
    /// Expands the children of an object element. `depth` is 1 for children of the root.
    fn expand_children(&mut self, children: Vec<Element>, depth: usize) -> Result<Vec<Element>> {
        let mut out = Vec::with_capacity(children.len());
        for child in children {
            self.expand_child(child, depth, &mut out)?;
        }
        Ok(out)
    }

    fn expand_child(
        &mut self,
        mut el: Element,
        depth: usize,
        out: &mut Vec<Element>,
    ) -> Result<()> {
        self.substitute_attrs(&mut el)?;
        match el.tag.as_str() {
            "default" => self.define(&el),
            "path" => self.add_path(&el, depth),
            "include" => self.include(&el, depth, out),
            _ => {
                let children = std::mem::take(&mut el.children);
                el.children = if el.is_object() {
                    self.expand_children(children, depth + 1)?
                } else {
                    // Properties and transforms hold no defaults or includes; still substitute.
                    self.expand_plain(children)?
                };
                out.push(el);
                Ok(())
            }
        }
    }

    /// Substitutes inside non-object elements, leaving `<default>` etc. for the plugin
    /// builder to reject (they cannot occur inside a property).
    fn expand_plain(&mut self, children: Vec<Element>) -> Result<Vec<Element>> {
        let mut out = Vec::with_capacity(children.len());
        for mut child in children {
            self.substitute_attrs(&mut child)?;
            let grand = std::mem::take(&mut child.children);
            child.children = self.expand_plain(grand)?;
            out.push(child);
        }
        Ok(out)
    }

    fn substitute_attrs(&mut self, el: &mut Element) -> Result<()> {
        for (_, value) in el.attrs.iter_mut() {
            if value.contains('$') {
                let (text, used) =
                    substitute(value, &self.params).map_err(|m| SceneError::at(&el.loc, m))?;
                *value = text;
                for i in used {
                    self.used[i] = true;
                }
            }
        }
        Ok(())
    }

    fn define(&mut self, el: &Element) -> Result<()> {
        el.check_attrs(&["name", "value"], &["name", "value"])?;
        let name = el.attr("name").unwrap_or_default();
        if !is_param_name(name) {
            return Err(SceneError::at(
                &el.loc,
                format!("invalid parameter name '{name}'"),
            ));
        }
        if !self.params.iter().any(|(k, _)| k == name) {
            let value = el.attr("value").unwrap_or_default();
            self.params.push((name.to_string(), value.to_string()));
            self.used.push(false);
        }
        Ok(())
    }

    /// `<path value="..."/>`: a folder put first on the resolver. A relative value is looked
    /// up as a file name is (the naming file's folder, the main scene's folder, the `<path>`
    /// folders so far), so a `<path>` in an included file works from where that file is.
    fn add_path(&mut self, el: &Element, depth: usize) -> Result<()> {
        el.check_attrs(&["value"], &["value"])?;
        if depth != 1 {
            return Err(SceneError::at(
                &el.loc,
                "<path> can only be a child of the root <scene>",
            ));
        }
        let value = el.attr("value").unwrap_or_default();
        let folder = resolve_in(
            value,
            &el.dir,
            &[&self.main_dir],
            &self.search_paths,
            Path::is_dir,
        );
        let Some(folder) = folder else {
            return Err(SceneError::at(
                &el.loc,
                format!(
                    "folder '{value}' not found (looked in '{}', the scene's folder and the \
                     <path> folders)",
                    el.dir.display()
                ),
            ));
        };
        self.search_paths.insert(0, folder);
        Ok(())
    }

    fn include(&mut self, el: &Element, depth: usize, out: &mut Vec<Element>) -> Result<()> {
        el.check_attrs(&["filename"], &["filename"])?;
        if self.includes >= MAX_INCLUDE_DEPTH {
            return Err(SceneError::at(
                &el.loc,
                format!("more than {MAX_INCLUDE_DEPTH} nested <include>s (an include cycle?)"),
            ));
        }
        let name = el.attr("filename").unwrap_or_default();
        let path = resolve_file(name, &el.dir, &[&self.main_dir], &self.search_paths);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            SceneError::at(
                &el.loc,
                format!("cannot open included file '{name}': {}", io_message(&e)),
            )
        })?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut raw = parse_raw(&text, &path, &dir)?;
        let version = take_version(&mut raw)?;
        if let Some(v) = version {
            upgrade(&mut raw, v);
        }
        self.includes += 1;
        let result = if raw.tag == "scene" {
            // The included scene's children take the place of the <include> element.
            raw.check_attrs(&[], &[])?;
            self.expand_children(raw.children, depth)
                .map(|c| out.extend(c))
        } else {
            self.expand_child(raw, depth, out)
        };
        self.includes -= 1;
        result
    }
}

/// Replaces each `$name` by its parameter value. Like Mitsuba, the longest defined name that
/// follows the `$` wins (so `$spp` and `$spp_max` can coexist), `\$` stands for a `$`, and any
/// other `$` left over is an error. Also returns the indices in `params` of the parameters
/// used.
pub(crate) fn substitute(
    value: &str,
    params: &[(String, String)],
) -> std::result::Result<(String, Vec<usize>), String> {
    let mut out = String::with_capacity(value.len());
    let mut used = Vec::new();
    let mut rest = value;
    while let Some(pos) = rest.find('$') {
        // `\$` is a literal dollar sign (Mitsuba's escape).
        if rest[..pos].ends_with('\\') {
            out.push_str(&rest[..pos - 1]);
            out.push('$');
            rest = &rest[pos + 1..];
            continue;
        }
        out.push_str(&rest[..pos]);
        let after = &rest[pos + 1..];
        let best = params
            .iter()
            .enumerate()
            .filter(|(_, (k, _))| after.starts_with(k.as_str()))
            .max_by_key(|(_, (k, _))| k.len());
        match best {
            Some((i, (k, v))) => {
                used.push(i);
                out.push_str(v);
                rest = &after[k.len()..];
            }
            None => {
                let name: String = after
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                return Err(format!(
                    "undefined parameter '${name}' (define it with <default name=\"{name}\" \
                     value=\"...\"/> or on the command line with -D {name}=...)"
                ));
            }
        }
    }
    out.push_str(rest);
    Ok((out, used))
}

/// Finds a file named in the scene: absolute names as they are; relative names in the
/// directory of the file that names them, then in `extra` folders (the main scene's folder),
/// then in the `<path>` folders, as Mitsuba's file resolver searches (its list starts with the
/// main scene's folder; `<path>` puts folders in front). If the file exists nowhere, returns
/// the first candidate so that opening it reports a sensible error.
pub(crate) fn resolve_file(name: &str, dir: &Path, extra: &[&Path], search: &[PathBuf]) -> PathBuf {
    resolve_in(name, dir, extra, search, Path::is_file).unwrap_or_else(|| dir.join(name))
}

/// The first of `dir/name`, `extra/name`, `search/name` that `exists` accepts (`name` itself if
/// it is absolute and accepted).
fn resolve_in(
    name: &str,
    dir: &Path,
    extra: &[&Path],
    search: &[PathBuf],
    exists: impl Fn(&Path) -> bool,
) -> Option<PathBuf> {
    let relative = Path::new(name);
    if relative.is_absolute() {
        return exists(relative).then(|| relative.to_path_buf());
    }
    std::iter::once(dir)
        .chain(extra.iter().copied())
        .chain(search.iter().map(PathBuf::as_path))
        .map(|d| d.join(relative))
        .find(|p| exists(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs
            .iter()
            .map(|(a, b)| (a.to_string(), b.to_string()))
            .collect()
    }

    #[test]
    fn camel_case_names_become_snake_case() {
        assert_eq!(camel_to_snake("toWorld"), "to_world");
        assert_eq!(camel_to_snake("fovAxis"), "fov_axis");
        assert_eq!(camel_to_snake("sampleCount"), "sample_count");
        assert_eq!(camel_to_snake("intIOR"), "int_ior");
        assert_eq!(camel_to_snake("max_depth"), "max_depth");
        assert_eq!(camel_to_snake("Radiance"), "Radiance");
        assert_eq!(camel_to_snake(""), "");
    }

    #[test]
    fn substitution_prefers_the_longest_name() {
        let p = params(&[("spp", "16"), ("spp_max", "64")]);
        assert_eq!(substitute("$spp", &p).unwrap().0, "16");
        assert_eq!(substitute("$spp_max", &p).unwrap().0, "64");
        assert_eq!(substitute("a $spp b $spp", &p).unwrap().0, "a 16 b 16");
        assert_eq!(substitute("no dollars", &p).unwrap().0, "no dollars");
        let err = substitute("$nope", &p).unwrap_err();
        assert!(err.contains("'$nope'"), "{err}");
        assert!(substitute("$", &p).is_err());
        assert_eq!(
            substitute(r"cost \$5 at $spp", &p).unwrap().0,
            "cost $5 at 16"
        );
    }

    #[test]
    fn line_index_positions() {
        let idx = LineIndex::new("ab\ncdé\nf");
        assert_eq!(idx.position(0), (1, 1));
        assert_eq!(idx.position(3), (2, 1));
        assert_eq!(idx.position(8), (3, 1));
        assert_eq!(idx.position(5), (2, 3));
        assert_eq!(idx.position(999), (3, 1));
    }

    #[test]
    fn version_parsing() {
        let mut el = parse_raw(
            r#"<scene version="0.6.0"/>"#,
            Path::new("x"),
            Path::new("."),
        )
        .unwrap();
        assert_eq!(take_version(&mut el).unwrap(), Some((0, 6, 0)));
        let mut bad =
            parse_raw(r#"<scene version="3.x"/>"#, Path::new("x"), Path::new(".")).unwrap();
        assert!(take_version(&mut bad).is_err());
    }
}

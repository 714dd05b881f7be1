//! The scene format's documentation, `scenes/README.md`, cannot go stale: every ```` ```xml ````
//! block in it is loaded with pt-scene and built with pt-render, as `pt info` and `pt render` do
//! (so a snippet that parses but could not render fails too), and every plugin the loader supports
//! must appear in at least one snippet.
//!
//! - A snippet that is not a whole `<scene>` is wrapped in `<scene version="3.0.0">...</scene>`,
//!   on the same line, so that line numbers in errors map onto the README.
//! - Snippets are loaded with `scenes/` as the base directory: file names in them are files under
//!   `scenes/`.
//! - A snippet may be marked by an HTML comment on the last non-blank line before its fence:
//!   `<!-- error: TEXT -->` (or `<!-- error -->`): it must fail to load or build, with TEXT in
//!   the message; `<!-- load-only: REASON -->`: it must load, and is not built (REASON says
//!   why, e.g. no file under `scenes/` has what it needs to render).
//! - Failures name the README line of the snippet (and of the element at fault, when the loader
//!   names one), all at once.
//!
//! The supported plugins are read from the loader's `PLUGINS` table
//! (`crates/pt-scene/src/build/mod.rs`), so that a plugin added there without documentation fails
//! here; [`NOT_IN_PLUGINS`] adds what the table does not list.

use crate::common;

use pt_render::{BvhKind, LightSelection, Scene};
use std::collections::BTreeSet;
use std::path::Path;

/// How the README names itself in messages (and the source name snippets are loaded under).
const README: &str = "scenes/README.md";

/// Plugins the loader builds that its `PLUGINS` table does not list, so that their documentation
/// is required too: `fluorescent` and `phosphorescent` are built in `build/materials.rs` but
/// missing from the table (whose lists only feed error messages), and spectra are properties, not
/// objects with a table entry. One CIE fluorescent lamp (`f11`) stands for `f1` .. `f12`.
const NOT_IN_PLUGINS: &[(&str, &str)] = &[
    ("bsdf", "fluorescent"),
    ("bsdf", "phosphorescent"),
    ("spectrum", "blackbody"),
    ("spectrum", "d65"),
    ("spectrum", "a"),
    ("spectrum", "f11"),
];

/// What a snippet is expected to do.
#[derive(Debug, PartialEq)]
enum Expect {
    /// Load and build.
    Works,
    /// Load; not built.
    LoadOnly,
    /// Fail to load or build, with this text in the message (if given).
    Error(Option<String>),
}

/// One ```` ```xml ```` block.
#[derive(Debug)]
struct Snippet {
    /// 1-based README line of the snippet's first line (the line after the fence).
    line: usize,
    text: String,
    expect: Expect,
}

/// The ```` ```xml ```` blocks of a Markdown text with their markers, or a message naming the
/// line of a malformed block or marker.
fn snippets(markdown: &str) -> Result<Vec<Snippet>, String> {
    let lines: Vec<&str> = markdown.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        if lines[i].trim() != "```xml" {
            i += 1;
            continue;
        }
        let fence = i;
        let previous = lines[..fence].iter().rev().find(|l| !l.trim().is_empty());
        let expect = match previous.map(|l| l.trim()) {
            Some(c) if c.starts_with("<!--") && c.ends_with("-->") => {
                marker(c[4..c.len() - 3].trim()).map_err(|m| format!("{README}:{fence}: {m}"))?
            }
            _ => Expect::Works,
        };
        let end = (fence + 1..lines.len())
            .find(|&j| lines[j].trim() == "```")
            .ok_or_else(|| format!("{README}:{}: ```xml block is not closed", fence + 1))?;
        out.push(Snippet {
            line: fence + 2,
            text: lines[fence + 1..end].join("\n"),
            expect,
        });
        i = end + 1;
    }
    Ok(out)
}

/// Reads a marker comment's text; comments that are not markers leave the snippet as `Works`.
fn marker(comment: &str) -> Result<Expect, String> {
    let (word, rest) = match comment.split_once(':') {
        Some((w, r)) => (w.trim(), Some(r.trim())),
        None => (comment, None),
    };
    Ok(match word {
        "error" => Expect::Error(rest.filter(|r| !r.is_empty()).map(str::to_string)),
        "load-only" if rest.is_some_and(|r| !r.is_empty()) => Expect::LoadOnly,
        "load-only" => return Err("<!-- load-only: REASON --> needs a reason".into()),
        _ => Expect::Works,
    })
}

/// Whether a snippet is a whole scene (after an optional XML declaration and comments).
fn is_whole_scene(text: &str) -> bool {
    let mut rest = text.trim_start();
    loop {
        if let Some(r) = rest.strip_prefix("<?") {
            rest = r.split_once("?>").map_or("", |(_, r)| r).trim_start();
        } else if let Some(r) = rest.strip_prefix("<!--") {
            rest = r.split_once("-->").map_or("", |(_, r)| r).trim_start();
        } else {
            return rest.starts_with("<scene");
        }
    }
}

/// An error message with the snippet's location on the README: `file:line:col` of a loader
/// error in the snippet itself becomes the README's line.
fn located(snippet: &Snippet, loc: Option<&pt_scene::SourceLoc>, message: &str) -> String {
    match loc {
        Some(l) if l.file == Path::new(README) => format!(
            "{README}:{}: <{}>: {message}",
            snippet.line + l.line as usize - 1,
            l.element
        ),
        Some(l) => format!("{l}: {message}"),
        None => message.to_string(),
    }
}

/// Loads (and, unless load-only, builds) one snippet: `Err` with the error's text.
fn load(snippet: &Snippet, scenes: &Path) -> Result<(), String> {
    let xml = if is_whole_scene(&snippet.text) {
        snippet.text.clone()
    } else {
        format!("<scene version=\"3.0.0\">{}</scene>", snippet.text)
    };
    let desc = pt_scene::load_str(&xml, Path::new(README), scenes, &[])
        .map_err(|e| located(snippet, e.loc.as_ref(), &e.message))?;
    if snippet.expect != Expect::LoadOnly {
        Scene::build(&desc, BvhKind::Auto, LightSelection::Power)
            .map_err(|e| located(snippet, Some(&e.loc), &e.message))?;
    }
    Ok(())
}

/// Every problem with the snippets of `markdown`, each naming its README line.
fn check(markdown: &str, scenes: &Path) -> Vec<String> {
    let snippets = match snippets(markdown) {
        Ok(s) => s,
        Err(m) => return vec![m],
    };
    let mut failures = Vec::new();
    if snippets.is_empty() {
        failures.push(format!("{README}: no ```xml snippets found"));
    }
    for s in &snippets {
        let at = format!("{README}:{}", s.line);
        match (&s.expect, load(s, scenes)) {
            (Expect::Works | Expect::LoadOnly, Ok(())) => {}
            (Expect::Works | Expect::LoadOnly, Err(e)) => {
                failures.push(format!("{at}: snippet does not load: {e}"))
            }
            (Expect::Error(_), Ok(())) => failures.push(format!(
                "{at}: snippet marked <!-- error --> loads and builds without error"
            )),
            (Expect::Error(Some(text)), Err(e)) if !e.contains(text.as_str()) => {
                failures.push(format!("{at}: snippet fails, but not with \"{text}\": {e}"))
            }
            (Expect::Error(_), Err(_)) => {}
        }
    }
    failures
}

/// The (tag, plugin) pairs of every element with a `type` in the snippets that are expected to
/// load (a plugin shown only failing is not documented).
fn plugins_shown(markdown: &str) -> BTreeSet<(String, String)> {
    let mut shown = BTreeSet::new();
    for s in snippets(markdown).unwrap_or_default() {
        if matches!(s.expect, Expect::Error(_)) {
            continue;
        }
        let mut rest = s.text.as_str();
        while let Some(start) = rest.find('<') {
            rest = &rest[start + 1..];
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            let tag_text = rest.split('>').next().unwrap_or_default();
            if let Some((_, after)) = tag_text.split_once(" type=\"") {
                if let Some((plugin, _)) = after.split_once('"') {
                    shown.insert((name, plugin.to_string()));
                }
            }
        }
    }
    shown
}

/// The supported plugins of the loader's `PLUGINS` table: (tag, plugin) for each name in the
/// second element of each `("tag", &[supported], &[known])` entry.
fn supported_plugins(source: &str) -> Result<Vec<(String, String)>, String> {
    let start = source
        .find("const PLUGINS")
        .ok_or("no `const PLUGINS` in crates/pt-scene/src/build/mod.rs")?;
    let table = &source[start..];
    let end = table
        .find("\n];")
        .ok_or("`const PLUGINS` does not end with `];`")?;
    let mut rest = &table[..end];
    let quoted = |s: &str| -> Vec<String> {
        s.split('"')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    };
    let mut out = Vec::new();
    while let Some(open) = rest.find("(\"") {
        rest = &rest[open + 2..];
        let (tag, after) = rest.split_once('"').ok_or("unterminated tag in PLUGINS")?;
        let list = after
            .split_once("&[")
            .and_then(|(_, l)| l.split_once(']'))
            .ok_or_else(|| format!("no supported list for \"{tag}\" in PLUGINS"))?;
        out.extend(quoted(list.0).into_iter().map(|p| (tag.to_string(), p)));
        // Skip the entry's second list (the known-but-unsupported plugins).
        rest = list
            .1
            .split_once("&[")
            .and_then(|(_, l)| l.split_once(']'))
            .map_or(list.1, |(_, r)| r);
    }
    if out.len() < 20 {
        return Err(format!(
            "read only {} supported plugins from PLUGINS: has its layout changed?",
            out.len()
        ));
    }
    Ok(out)
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("read {}: {e}", path.display()))
}

#[test]
fn every_snippet_of_the_scene_format_loads() {
    let repo = common::repo();
    let failures = check(&read(&repo.join(README)), &repo.join("scenes"));
    assert!(failures.is_empty(), "\n{}\n", failures.join("\n"));
}

#[test]
fn every_supported_plugin_has_a_snippet() {
    let repo = common::repo();
    let shown = plugins_shown(&read(&repo.join(README)));
    let table = read(&repo.join("crates/pt-scene/src/build/mod.rs"));
    let mut required = supported_plugins(&table).unwrap_or_else(|e| panic!("{e}"));
    required.extend(
        NOT_IN_PLUGINS
            .iter()
            .map(|(t, p)| (t.to_string(), p.to_string())),
    );
    let missing: Vec<String> = required
        .iter()
        .filter(|p| !shown.contains(*p))
        .map(|(t, p)| format!("<{t} type=\"{p}\">"))
        .collect();
    assert!(
        missing.is_empty(),
        "{README} has no working ```xml snippet with {}",
        missing.join(", ")
    );
}

/// The checks above fail when they should: a snippet that does not load, an error snippet that
/// loads, an error with other text, a load-only snippet (and the same one built), an unclosed
/// block, a table that does not parse.
#[test]
fn the_checks_catch_broken_snippets() {
    let repo = common::repo();
    let scenes = repo.join("scenes");
    // Line numbers matter: the expected messages below name them.
    let markdown = r#"# Test
```xml
<shape type="sphere"><bsdf type="diffuse"/></shape>
```

```xml
<shape type="sphere">
    <float name="radius" value="one"/>
</shape>
```
<!-- error -->
```xml
<shape type="sphere"/>
```
<!-- error: no such text -->
```xml
<shape type="ply"/>
```
<!-- load-only: the texture needs a mesh attribute, which a rectangle does not have -->
```xml
<shape type="rectangle"><bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
    <string name="name" value="vertex_color"/></texture></bsdf></shape>
```
```xml
<shape type="rectangle"><bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">
    <string name="name" value="vertex_color"/></texture></bsdf></shape>
```
"#;
    let failures = check(markdown, &scenes);
    let expected = [
        r#"scenes/README.md:7: snippet does not load: scenes/README.md:8: <float name="radius">"#,
        "scenes/README.md:13: snippet marked <!-- error --> loads",
        r#"scenes/README.md:17: snippet fails, but not with "no such text""#,
        "scenes/README.md:25: snippet does not load",
    ];
    assert_eq!(failures.len(), expected.len(), "{failures:#?}");
    for (f, e) in failures.iter().zip(expected) {
        assert!(
            f.starts_with(e),
            "expected a failure starting with\n  {e}\ngot\n  {f}"
        );
    }
    let shown = plugins_shown(markdown);
    assert!(shown.contains(&("bsdf".to_string(), "diffuse".to_string())));
    assert!(shown.contains(&("texture".to_string(), "mesh_attribute".to_string())));
    assert!(!shown.contains(&("shape".to_string(), "ply".to_string())));
    let unclosed = check("```xml\n<shape type=\"sphere\"/>\n", &scenes);
    assert_eq!(unclosed, ["scenes/README.md:1: ```xml block is not closed"]);
    let table = r#"const PLUGINS: &[(&str, &[&str], &[&str])] = &[
    ("shape", &["obj"], &["ply"]),
];"#;
    assert!(
        supported_plugins(table).is_err(),
        "a table this small is suspect"
    );
}

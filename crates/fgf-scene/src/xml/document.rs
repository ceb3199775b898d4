//! Stage 1 of the loader: XML text -> an owned tree of [`XNode`]s with
//! `<include>` expanded, `<default>`s applied and every `$name` substituted.
//! Each node remembers its file and line so that later errors can name them.

use crate::error::{SceneError, SceneErrorKind};
use std::cell::{Cell, RefCell};
use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Nesting deeper than this is refused. Real Mitsuba scenes nest about six
/// levels (scene > shape > medium > volume > transform > scale); the limit
/// keeps the recursive stages' stack use bounded on hostile input.
const MAX_DEPTH: usize = 32;
/// Include nesting limit (an include chain this long is certainly a mistake).
const MAX_INCLUDE_DEPTH: usize = 16;
/// Total elements over the scene and all its includes: bounds the memory an
/// include "diamond" (a file including another one many times) can take.
const MAX_NODES: usize = 2_000_000;
/// Longest attribute value after `$name` substitution, in bytes.
pub(crate) const MAX_ATTR_BYTES: usize = 16 << 20;
/// Total bytes that `$name` substitution may produce over the scene and its
/// includes: a large `<default>` used in many attributes would otherwise grow
/// the document without bound (a 1 MB value used 24,000 times is 24 GB).
pub(crate) const MAX_SUBSTITUTED_BYTES: usize = 256 << 20;

/// One XML element, owned, with substituted attribute values.
#[derive(Debug)]
pub(crate) struct XNode {
    pub tag: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<XNode>,
    /// The file this element was written in (the scene or an included file).
    pub file: Arc<PathBuf>,
    /// Directory of the file this element was written in.
    pub dir: Arc<PathBuf>,
    /// Mitsuba's file resolver at instantiation time: the `<path>`
    /// directories (the last declared first), then the scene's directory.
    /// Filled in once the whole document is parsed.
    pub search: Arc<Vec<PathBuf>>,
    pub line: u32,
    pub col: u32,
}

impl XNode {
    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    /// The tag as the user wrote it, with its identifying attributes:
    /// `<shape type="obj">`, `<float name="fov">`, `<ref id="glass">`.
    pub fn label(&self) -> String {
        let mut s = format!("<{}", self.tag);
        for key in ["type", "name", "id"] {
            if let Some(v) = self.attr(key) {
                s.push_str(&format!(" {key}=\"{v}\""));
            }
        }
        s.push('>');
        s
    }

    pub fn err_kind(&self, kind: SceneErrorKind, message: impl Into<String>) -> SceneError {
        SceneError {
            kind,
            file: self.file.as_ref().clone(),
            pos: Some((self.line, self.col)),
            tag: Some(self.label()),
            message: message.into(),
        }
    }

    /// An [`SceneErrorKind::Invalid`] error at this element.
    pub fn err(&self, message: impl Into<String>) -> SceneError {
        self.err_kind(SceneErrorKind::Invalid, message)
    }

    /// Reject attributes other than `allowed`.
    pub fn check_attrs(&self, allowed: &[&str]) -> Result<(), SceneError> {
        for (k, _) in &self.attrs {
            if !allowed.contains(&k.as_str()) {
                return Err(self.err(format!(
                    "unknown attribute '{k}' (allowed here: {})",
                    allowed.join(", ")
                )));
            }
        }
        Ok(())
    }

    /// A required attribute.
    pub fn req_attr(&self, key: &str) -> Result<&str, SceneError> {
        self.attr(key)
            .ok_or_else(|| self.err(format!("missing attribute '{key}'")))
    }

    /// Resolve a file name written in this element as Mitsuba's file
    /// resolver does: an absolute name as is; a relative one against the
    /// `<path>` directories (the last declared first), then the scene's
    /// directory, then (an fgf extension, for included files kept in another
    /// directory) the directory of the file this element is in, then the
    /// working directory. The first candidate that exists wins; when none
    /// exists the name is joined to the element's own directory, for the
    /// error message.
    pub fn resolve(&self, file: &str) -> PathBuf {
        let p = Path::new(file);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        let candidates = self
            .search
            .iter()
            .map(|d| d.join(p))
            .chain(std::iter::once(self.dir.join(p)))
            .chain(std::iter::once(p.to_path_buf()));
        for c in candidates {
            if c.exists() {
                return c;
            }
        }
        self.dir.join(p)
    }
}

struct Builder<'c> {
    /// `$name` values: the caller's defines, then `<default>`s for names the
    /// caller did not define.
    params: HashMap<String, String>,
    /// Names declared by a `<default>` in any file, and names some `$name`
    /// used: a caller's define in neither is a typo (`-D kernal=...`).
    declared: HashSet<String>,
    used: RefCell<HashSet<String>>,
    /// Canonical paths of the files being included (cycle detection).
    stack: Vec<PathBuf>,
    /// Directories of the files being included, innermost last: an
    /// `<include>` is resolved against them first, as Mitsuba does.
    dir_stack: Vec<PathBuf>,
    /// The scene file's directory.
    scene_dir: PathBuf,
    /// `<path value>` directories, in the order they were declared.
    paths: Vec<PathBuf>,
    /// The file being read is older than Mitsuba 2.0: its names are
    /// upgraded ([`upgrade_v1`]).
    upgrade: bool,
    nodes: usize,
    /// Bytes produced by `$name` substitution so far.
    substituted: Cell<usize>,
    /// Set by the caller to stop the load (Ctrl-C); polled per element.
    cancel: Option<&'c AtomicBool>,
}

/// Parse `xml` (the scene named `source_name`) into the top-level elements of
/// its `<scene>`, includes spliced in place. Also returns the error for the
/// first caller define that no `<default>` declares and no `$name` uses, for
/// the caller to report once the scene itself has been checked.
pub(crate) fn build(
    xml: &str,
    source_name: &str,
    base_dir: &Path,
    defines: &[(String, String)],
    cancel: Option<&AtomicBool>,
) -> Result<(Vec<XNode>, Option<SceneError>), SceneError> {
    let mut b = Builder {
        params: HashMap::new(),
        declared: HashSet::new(),
        used: RefCell::new(HashSet::new()),
        stack: Vec::new(),
        dir_stack: Vec::new(),
        scene_dir: base_dir.to_path_buf(),
        paths: Vec::new(),
        upgrade: false,
        nodes: 0,
        substituted: Cell::new(0),
        cancel,
    };
    for (k, v) in defines {
        if !is_ident(k) {
            return Err(SceneError::new(
                SceneErrorKind::Invalid,
                source_name,
                format!("invalid define name '{k}' (must be letters, digits or '_', not starting with a digit)"),
            ));
        }
        b.params.insert(k.clone(), v.clone());
    }
    if let Ok(canon) = std::fs::canonicalize(source_name) {
        b.stack.push(canon);
    }
    let file = Arc::new(PathBuf::from(source_name));
    let dir = Arc::new(base_dir.to_path_buf());
    let mut out = Vec::new();
    b.file(xml, &file, &dir, &mut out)?;
    // Every element resolves its file names with the final resolver: in
    // Mitsuba the plugins are instantiated after the whole document (every
    // `<path>`) has been read.
    let search: Arc<Vec<PathBuf>> = Arc::new(b.search_dirs());
    for n in &mut out {
        set_search(n, &search);
    }
    for (k, _) in defines {
        if !b.declared.contains(k) && !b.used.borrow().contains(k) {
            let mut known: Vec<&str> = b.declared.iter().map(|s| s.as_str()).collect();
            known.sort_unstable();
            let e = SceneError::new(
                SceneErrorKind::Invalid,
                source_name,
                format!(
                    "define '{k}' is not a parameter of this scene: no <default name=\"{k}\"/> and no ${k} (its defaults: {})",
                    if known.is_empty() { "none".to_string() } else { known.join(", ") }
                ),
            );
            return Ok((out, Some(e)));
        }
    }
    Ok((out, None))
}

fn set_search(n: &mut XNode, search: &Arc<Vec<PathBuf>>) {
    n.search = search.clone();
    for c in &mut n.children {
        set_search(c, search);
    }
}

/// Mitsuba 3's upgrade of a pre-2.0 property name: camelCase to
/// snake_case (an underscore before an upper-case letter that follows a
/// lower-case one, and that run of capitals in lower case: `intIOR` →
/// `int_ior`, `toWorld` → `to_world`, `maxDepth` → `max_depth`).
pub(crate) fn camel_to_snake(name: &str) -> String {
    let c: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    let mut i = 0;
    while i < c.len() {
        if i > 0 && c[i - 1].is_ascii_lowercase() && c[i].is_ascii_uppercase() {
            out.push('_');
            out.push(c[i].to_ascii_lowercase());
            while i + 1 < c.len() && c[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(c[i].to_ascii_lowercase());
            }
        } else {
            out.push(c[i]);
        }
        i += 1;
    }
    out
}

/// The major and minor numbers of a `version="x.y.z"` attribute.
fn parse_version(v: &str) -> Option<(u32, u32)> {
    let mut it = v.trim().split('.');
    let major = it.next()?.trim().parse().ok()?;
    let minor = match it.next() {
        Some(m) => m.trim().parse().ok()?,
        None => 0,
    };
    for rest in it {
        rest.trim().parse::<u32>().ok()?;
    }
    Some((major, minor))
}

/// Mitsuba 3's upgrade of an element of a pre-2.0 file: every property
/// name of a plugin goes from camelCase to snake_case, and a `diffuse`
/// BSDF's `diffuse_reflectance` becomes `reflectance`. Texture offsets
/// (`uoffset` ...), which Mitsuba turns into a `to_uv` transform, are left
/// to the texture's own parameter check.
fn upgrade_v1(node: &mut XNode) {
    let is_diffuse = node.tag == "bsdf" && node.attr("type") == Some("diffuse");
    for c in &mut node.children {
        if let Some((_, v)) = c.attrs.iter_mut().find(|(k, _)| k == "name") {
            let mut new = camel_to_snake(v);
            if is_diffuse && new == "diffuse_reflectance" {
                new = "reflectance".to_string();
            }
            *v = new;
        }
    }
}

fn is_ident(s: &str) -> bool {
    let mut c = s.chars();
    matches!(c.next(), Some(ch) if ch.is_ascii_alphabetic() || ch == '_')
        && c.all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
}

/// The line and column (from 1; the column in characters) of byte offsets
/// in one file's text, as `roxmltree::Document::text_pos_at` gives them,
/// each found by scanning on from the offset asked for last. The loader
/// asks in document order, once per element, so each pass over the
/// elements scans the text once; `text_pos_at` scans from the start each
/// time, which made a scene of 20,000 shapes take 5 s to load.
struct Positions<'a> {
    text: &'a [u8],
    /// The last offset asked for, and its line and column.
    last: Cell<(usize, u32, u32)>,
}

impl<'a> Positions<'a> {
    fn new(text: &'a str) -> Self {
        Positions {
            text: text.as_bytes(),
            last: Cell::new((0, 1, 1)),
        }
    }

    /// The line and column of the character at byte offset `at`.
    fn at(&self, at: usize) -> (u32, u32) {
        let at = at.min(self.text.len());
        let (mut from, mut line, mut col) = self.last.get();
        if at < from {
            (from, line, col) = (0, 1, 1);
        }
        for &b in &self.text[from..at] {
            if b == b'\n' {
                line += 1;
                col = 1;
            } else if b & 0xC0 != 0x80 {
                // The first byte of a character (not a UTF-8 continuation).
                col += 1;
            }
        }
        self.last.set((at, line, col));
        (line, col)
    }
}

fn pos_of(positions: &Positions, node: roxmltree::Node) -> (u32, u32) {
    positions.at(node.range().start)
}

impl Builder<'_> {
    /// Parse one file's text and append its `<scene>`'s children to `out`.
    fn file(
        &mut self,
        xml: &str,
        file: &Arc<PathBuf>,
        dir: &Arc<PathBuf>,
        out: &mut Vec<XNode>,
    ) -> Result<(), SceneError> {
        let opts = roxmltree::ParsingOptions {
            allow_dtd: false,
            nodes_limit: MAX_NODES as u32,
            ..Default::default()
        };
        let doc = roxmltree::Document::parse_with_options(xml, opts).map_err(|e| {
            let p = e.pos();
            SceneError {
                kind: SceneErrorKind::Syntax,
                file: file.as_ref().clone(),
                pos: Some((p.row, p.col)),
                tag: None,
                message: format!("malformed XML: {e}"),
            }
        })?;
        let root = doc.root_element();
        let positions = Positions::new(xml);
        let (line, col) = pos_of(&positions, root);
        let here = |tag: Option<String>, msg: String| SceneError {
            kind: SceneErrorKind::Invalid,
            file: file.as_ref().clone(),
            pos: Some((line, col)),
            tag,
            message: msg,
        };
        if root.tag_name().name() != "scene" {
            return Err(here(
                Some(format!("<{}>", root.tag_name().name())),
                "the root element must be <scene version=\"3.0.0\">".into(),
            ));
        }
        let upgrade = match root.attribute("version") {
            None => {
                return Err(here(
                    Some("<scene>".into()),
                    "missing attribute 'version' (write <scene version=\"3.0.0\">)".into(),
                ))
            }
            Some(v) => match parse_version(v) {
                None => {
                    return Err(here(
                        Some("<scene>".into()),
                        format!("invalid version number \"{v}\" (write major.minor.patch, e.g. \"3.0.0\")"),
                    ))
                }
                Some((major, _)) if major > 3 => {
                    return Err(here(
                        Some("<scene>".into()),
                        format!("version \"{v}\" is newer than this loader, which reads Mitsuba 3 scenes (and older ones, upgraded as Mitsuba 3 does)"),
                    ))
                }
                // Mitsuba 3 upgrades the files older than 2.0 (camelCase
                // names); 2.x files are read as they are.
                Some((major, _)) => major < 2,
            },
        };
        let outer_upgrade = std::mem::replace(&mut self.upgrade, upgrade);
        let r = self.file_body(&positions, root, file, dir, out);
        self.upgrade = outer_upgrade;
        r
    }

    /// The `<scene>` element of one file: its attributes, `<default>`s,
    /// `<path>`s, includes and objects.
    fn file_body(
        &mut self,
        positions: &Positions,
        root: roxmltree::Node,
        file: &Arc<PathBuf>,
        dir: &Arc<PathBuf>,
        out: &mut Vec<XNode>,
    ) -> Result<(), SceneError> {
        let (line, col) = pos_of(positions, root);
        let here = |tag: Option<String>, msg: String| SceneError {
            kind: SceneErrorKind::Invalid,
            file: file.as_ref().clone(),
            pos: Some((line, col)),
            tag,
            message: msg,
        };
        for a in root.attributes() {
            if a.name() != "version" {
                return Err(here(
                    Some("<scene>".into()),
                    format!("unknown attribute '{}' (allowed here: version)", a.name()),
                ));
            }
        }
        // `<default>`s first, so that a `$name` may be used before the
        // `<default>` that defines it, as in Mitsuba. The caller's defines win.
        for child in root.children().filter(|n| n.is_element()) {
            if child.tag_name().name() == "default" {
                let node = self.convert(positions, child, file, dir, 0)?;
                node.check_attrs(&["name", "value"])?;
                let name = node.req_attr("name")?;
                let value = node.req_attr("value")?;
                if !is_ident(name) {
                    return Err(node.err(format!(
                        "invalid default name '{name}' (must be letters, digits or '_', not starting with a digit)"
                    )));
                }
                if !node.children.is_empty() {
                    return Err(node.err("<default> takes no children"));
                }
                self.declared.insert(name.to_string());
                self.params
                    .entry(name.to_string())
                    .or_insert_with(|| value.to_string());
            }
        }
        for child in root.children() {
            if child.is_text() && !child.text().unwrap_or("").trim().is_empty() {
                let (l, c) = pos_of(positions, child);
                return Err(SceneError {
                    kind: SceneErrorKind::Invalid,
                    file: file.as_ref().clone(),
                    pos: Some((l, c)),
                    tag: Some("<scene>".into()),
                    message: "unexpected text inside <scene>".into(),
                });
            }
            if !child.is_element() {
                continue;
            }
            match child.tag_name().name() {
                "default" => {}
                "include" => {
                    let node = self.convert(positions, child, file, dir, 0)?;
                    self.include(&node, out)?;
                }
                "path" => {
                    let node = self.convert(positions, child, file, dir, 0)?;
                    self.path(&node)?;
                }
                _ => {
                    let node = self.convert(positions, child, file, dir, 0)?;
                    out.push(node);
                }
            }
        }
        Ok(())
    }

    fn include(&mut self, node: &XNode, out: &mut Vec<XNode>) -> Result<(), SceneError> {
        node.check_attrs(&["filename"])?;
        if !node.children.is_empty() {
            return Err(node.err("<include> takes no children"));
        }
        if self.stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(node.err(format!(
                "includes nested more than {MAX_INCLUDE_DEPTH} deep"
            )));
        }
        let name = node.req_attr("filename")?;
        let path = self.resolve_include(node, name);
        let bytes = fgf_io::read_regular(&path).map_err(|e| {
            node.err_kind(
                SceneErrorKind::Io,
                format!("cannot read included file '{}': {e}", path.display()),
            )
        })?;
        let canon = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
        if self.stack.contains(&canon) {
            return Err(node.err(format!(
                "include cycle: '{}' includes itself (through: {})",
                path.display(),
                self.stack
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(" -> ")
            )));
        }
        let text = String::from_utf8(bytes).map_err(|_| {
            node.err_kind(
                SceneErrorKind::Format,
                format!("included file '{}' is not valid UTF-8", path.display()),
            )
        })?;
        let file = Arc::new(path.clone());
        let dir = Arc::new(match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        });
        self.stack.push(canon);
        self.dir_stack.push(node.dir.as_ref().clone());
        let r = self.file(&text, &file, &dir, out);
        self.dir_stack.pop();
        self.stack.pop();
        // Name the including line too: the included file's own error is
        // complete, but the user needs to know where it was included from.
        r.map_err(|mut e| {
            e.message = format!(
                "{} (included from {}:{}:{})",
                e.message,
                node.file.display(),
                node.line,
                node.col
            );
            e
        })
    }

    /// The resolver's directories after the scene directory's own: the
    /// `<path>`s, the last declared first, then the scene's directory.
    fn search_dirs(&self) -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = self.paths.iter().rev().cloned().collect();
        v.push(self.scene_dir.clone());
        v
    }

    /// An `<include>`'s file, found as Mitsuba finds it: against the
    /// including file's directory (and those of the files including it),
    /// then the `<path>`s read so far, the scene's directory and the working
    /// directory.
    fn resolve_include(&self, node: &XNode, name: &str) -> PathBuf {
        let p = Path::new(name);
        if p.is_absolute() {
            return p.to_path_buf();
        }
        let dirs = std::iter::once(node.dir.as_ref().clone())
            .chain(self.dir_stack.iter().rev().cloned())
            .chain(self.search_dirs());
        for d in dirs {
            let c = d.join(p);
            if c.exists() {
                return c;
            }
        }
        if p.exists() {
            return p.to_path_buf();
        }
        node.dir.join(p)
    }

    /// `<path value="dir"/>`: a directory added to the file resolver, as in
    /// Mitsuba: relative to the file it is written in, else found through
    /// the resolver; it must exist.
    fn path(&mut self, node: &XNode) -> Result<(), SceneError> {
        node.check_attrs(&["value"])?;
        if !node.children.is_empty() {
            return Err(node.err("<path> takes no children"));
        }
        let value = node.req_attr("value")?;
        let p = Path::new(value);
        let mut dir = if p.is_absolute() {
            p.to_path_buf()
        } else {
            node.dir.join(p)
        };
        if !dir.is_dir() && !p.is_absolute() {
            dir = self.resolve_include(node, value);
        }
        if !dir.is_dir() {
            return Err(node.err_kind(
                SceneErrorKind::Io,
                format!("<path>: directory '{}' not found", dir.display()),
            ));
        }
        self.paths.push(dir);
        Ok(())
    }

    /// Convert an element and its descendants, substituting `$name`s.
    fn convert(
        &mut self,
        positions: &Positions,
        n: roxmltree::Node,
        file: &Arc<PathBuf>,
        dir: &Arc<PathBuf>,
        depth: usize,
    ) -> Result<XNode, SceneError> {
        let (line, col) = pos_of(positions, n);
        self.nodes += 1;
        let mut node = XNode {
            tag: n.tag_name().name().to_string(),
            attrs: Vec::new(),
            children: Vec::new(),
            file: file.clone(),
            dir: dir.clone(),
            search: Arc::new(Vec::new()),
            line,
            col,
        };
        if n.tag_name().namespace().is_some() {
            return Err(node.err("XML namespaces are not supported in Mitsuba scenes"));
        }
        if self.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(node.err_kind(SceneErrorKind::Cancelled, "loading cancelled"));
        }
        if self.nodes > MAX_NODES {
            return Err(node.err(format!(
                "the scene has more than {MAX_NODES} elements (with its includes)"
            )));
        }
        if depth > MAX_DEPTH {
            return Err(node.err(format!("elements nested more than {MAX_DEPTH} deep")));
        }
        for a in n.attributes() {
            let v = self.substitute(&node, a.name(), a.value())?;
            node.attrs.push((a.name().to_string(), v));
        }
        for c in n.children() {
            if c.is_element() {
                if matches!(c.tag_name().name(), "default" | "include" | "path") {
                    let child = self.convert(positions, c, file, dir, depth + 1)?;
                    return Err(child.err(format!(
                        "<{}> is only allowed directly inside <scene>",
                        child.tag
                    )));
                }
                let child = self.convert(positions, c, file, dir, depth + 1)?;
                node.children.push(child);
            } else if c.is_text() && !c.text().unwrap_or("").trim().is_empty() {
                return Err(node.err(format!(
                    "unexpected text '{}' inside the element (values go in a value=\"...\" attribute)",
                    c.text().unwrap_or("").trim().chars().take(40).collect::<String>()
                )));
            }
        }
        if self.upgrade {
            upgrade_v1(&mut node);
        }
        Ok(node)
    }

    /// Replace every `$name` (longest identifier after the `$`) by its value.
    /// A `$` not followed by an identifier is kept as is.
    fn substitute(&self, node: &XNode, attr: &str, value: &str) -> Result<String, SceneError> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut out = String::with_capacity(value.len());
        let mut rest = value;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after
                .char_indices()
                .take_while(|(j, ch)| {
                    ch.is_ascii_alphanumeric() && !(*j == 0 && ch.is_ascii_digit()) || *ch == '_'
                })
                .map(|(j, ch)| j + ch.len_utf8())
                .last()
                .unwrap_or(0);
            if len == 0 {
                out.push('$');
                rest = after;
                continue;
            }
            let name = &after[..len];
            self.used.borrow_mut().insert(name.to_string());
            match self.params.get(name) {
                Some(v) => {
                    let total = self.substituted.get() + v.len();
                    self.substituted.set(total);
                    if out.len() + v.len() > MAX_ATTR_BYTES {
                        return Err(node.err(format!(
                            "attribute {attr} grows past {} MiB after substituting ${name} (the limit of one attribute value)",
                            MAX_ATTR_BYTES >> 20
                        )));
                    }
                    if total > MAX_SUBSTITUTED_BYTES {
                        return Err(node.err(format!(
                            "$name substitution has produced more than {} MiB over the scene (at ${name} in attribute {attr}); use shorter <default> values",
                            MAX_SUBSTITUTED_BYTES >> 20
                        )));
                    }
                    out.push_str(v)
                }
                None => {
                    let mut known: Vec<&str> = self.params.keys().map(|s| s.as_str()).collect();
                    known.sort_unstable();
                    return Err(node.err(format!(
                        "attribute {attr}=\"{}\" uses ${name}, which has no <default name=\"{name}\" .../> and was not defined by the caller (defined: {})",
                        crate::error::clip(value),
                        if known.is_empty() { "none".to_string() } else { known.join(", ") }
                    )));
                }
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::Positions;

    /// Each element's line and column are those roxmltree computes, over
    /// lines of several lengths, CRLF endings, characters of two to four
    /// bytes before elements on one line, and offsets asked for in document
    /// order, then again from the start, then backwards.
    #[test]
    fn positions_match_roxmltree() {
        let xml = "<scene version=\"3.0.0\">\r\n  <!-- é ü 水 🙂 -->\n\t<a x=\"ß\"/><b/>\n\n<c>\
                   <d y=\"水🙂\"/>text é<e/></c>\r\n<f/>  <g/></scene>";
        let doc = roxmltree::Document::parse(xml).unwrap();
        let starts: Vec<usize> = doc
            .descendants()
            .filter(|n| n.is_element())
            .map(|n| n.range().start)
            .collect();
        assert_eq!(starts.len(), 8);
        let want = |at: usize| {
            let p = doc.text_pos_at(at);
            (p.row, p.col)
        };
        let positions = Positions::new(xml);
        let order = starts.iter().chain(&starts).chain(starts.iter().rev());
        for &at in order {
            assert_eq!(positions.at(at), want(at), "offset {at}");
        }
        assert_eq!(positions.at(xml.len() + 5), want(xml.len()));
    }
}

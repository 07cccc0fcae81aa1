//! No two files of a crate import each other, directly or around a circle (STYLE.md, habit
//! 17): shared types sink into a leaf module. This test reads every workspace crate's sources
//! and fails on a circle of imports between its files, and on a circle between the crate
//! root's modules taken whole (a module with the files below it), which a re-export can hide
//! from the file view.
//!
//! ## What counts as an import
//!
//! The module tree is found from each crate root (`src/lib.rs`, `src/main.rs`, the
//! integration tests' roots) through its `mod NAME;` declarations. A file imports another
//! when it names an item of the other's module by path: in a `use` (`use crate::a::B`,
//! `use super::b`, `use self::c::D`, or a child module's name), or inline in code
//! (`crate::a::f(…)`, `super::B`, `child::g`). A name is followed to the module that
//! defines it: through re-exports (`pub use x::Y` in `lib.rs` leads to `x`), and into the
//! sources of glob imports. A `pub use` is the crate's façade, not a dependency of the file
//! that holds it, unless the file's own code uses the name. Declaring a child module
//! (`mod x;`) is not an import, so a child's `use super::…` is no circle by itself; nor is a
//! file's use of its own items (`super::` inside an inline `mod tests`).
//!
//! A few-hundred-line tokenizer stands in for a Rust parser: it skips comments, strings and
//! character literals, and understands `use` trees; that is all the test needs.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Circles that are being removed: skipped while a re-shaping is under way, by crate and the
/// files of the circle (under `src/`) or its modules (names under the crate root). None today; delete an entry when its circle is gone.
const KNOWN: &[(&str, &[&str])] = &[];

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let mut circles = Vec::new();
    let mut crates = 0;
    for dir in crate_dirs(workspace) {
        let name = dir.file_name().unwrap().to_string_lossy().to_string();
        for root in roots(&dir) {
            crates += 1;
            let graph = Crate::read(&root);
            for circle in graph.circles() {
                let files: BTreeSet<String> = circle
                    .iter()
                    .map(|f| relative(f, &dir.join("src")))
                    .collect();
                let known = KNOWN.iter().any(|(c, known)| {
                    *c == name && files.iter().all(|f| known.contains(&f.as_str()))
                });
                if !known {
                    let shown: Vec<String> = circle.iter().map(|f| relative(f, &dir)).collect();
                    circles.push(format!("{name}: {}", shown.join(" → ")));
                }
            }
            for circle in graph.module_circles() {
                let known = KNOWN.iter().any(|(c, known)| {
                    *c == name && circle.iter().all(|m| known.contains(&m.as_str()))
                });
                if !known {
                    circles.push(format!("{name}: modules {}", circle.join(" → ")));
                }
            }
        }
    }
    assert!(crates >= 13, "read only {crates} crate roots");
    assert!(
        circles.is_empty(),
        "files that import each other (move the shared items down into a leaf module):\n{}",
        circles.join("\n")
    );
}

/// The tokenizer and the resolver find the edges and circles they should, on sources written
/// here.
#[test]
fn the_reader_finds_a_circle_and_follows_re_exports() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    std::fs::create_dir_all(src.join("b")).unwrap();
    let write = |p: &str, s: &str| std::fs::write(src.join(p), s).unwrap();
    write(
        "lib.rs",
        "//! use crate::a;\nmod a;\nmod b;\nmod c;\n#[path = \"elsewhere/d.rs\"]\nmod d;\npub use b::Thing;\npub fn top() {}\n",
    );
    std::fs::create_dir_all(src.join("elsewhere")).unwrap();
    write(
        "elsewhere/d.rs",
        "fn f() { let c = '\"'; super::c::g(); }\n",
    );
    write(
        "a.rs",
        "use crate::Thing; // use crate::c;\nfn f() { let s = \"crate::c::g\"; }\n",
    );
    write("b/mod.rs", "mod inner;\npub use inner::Thing;\n");
    write(
        "b/inner.rs",
        "pub struct Thing;\nfn g() { crate::c::g(); }\n#[cfg(test)]\nmod tests { use super::*; }\n",
    );
    write(
        "c.rs",
        "pub fn g() {}\nfn h() -> crate::a::X { todo!() }\nfn t() { crate::top(); }\n",
    );
    let graph = Crate::read(&src.join("lib.rs"));
    let name = |p: &PathBuf| relative(p, &src);
    assert_edges(
        &graph,
        &src,
        &[
            ("a.rs", "b/inner.rs"),
            ("b/inner.rs", "c.rs"),
            ("c.rs", "a.rs"),
            ("c.rs", "lib.rs"),
            ("elsewhere/d.rs", "c.rs"),
        ],
    );
    let circles: Vec<Vec<String>> = graph
        .circles()
        .iter()
        .map(|c| c.iter().map(name).collect())
        .collect();
    assert_eq!(circles, [["a.rs", "b/inner.rs", "c.rs"]]);
    assert_eq!(graph.module_circles(), [["a", "b", "c"]]);
}

/// A module named inside a `use crate::{…}` tree and then used through its path is an
/// import; and two modules whose files import each other only through a re-export (here
/// `limit.rs` takes `Structure` through `structure/mod.rs`, which defines none of it) are a
/// circle of modules, though no two files import each other. This is the form that
/// `truss-core`'s `structure/mod.rs` and `limit.rs` had.
#[test]
fn a_circle_through_a_re_export_is_a_circle_of_modules() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    std::fs::create_dir_all(src.join("structure")).unwrap();
    let write = |p: &str, s: &str| std::fs::write(src.join(p), s).unwrap();
    write(
        "lib.rs",
        "mod structure;\npub mod limit;\npub struct ModelError;\n",
    );
    write(
        "structure/mod.rs",
        "mod compiled;\npub use compiled::Structure;\nuse crate::{ModelError, limit};\n\
         fn new() -> Result<Structure, ModelError> { limit::framed(); todo!() }\n",
    );
    write("structure/compiled.rs", "pub struct Structure;\n");
    write(
        "limit.rs",
        "use crate::structure::Structure;\npub fn framed(s: &Structure) {}\n",
    );
    let graph = Crate::read(&src.join("lib.rs"));
    assert_edges(
        &graph,
        &src,
        &[
            ("limit.rs", "structure/compiled.rs"),
            ("structure/mod.rs", "limit.rs"),
            ("structure/mod.rs", "lib.rs"),
            ("structure/mod.rs", "structure/compiled.rs"),
        ],
    );
    assert!(graph.circles().is_empty());
    assert_eq!(graph.module_circles(), [["limit", "structure"]]);
}

/// The graph's edges between files, named under `src`, are exactly `expect`.
fn assert_edges(graph: &Crate, src: &Path, expect: &[(&str, &str)]) {
    let name = |p: &PathBuf| relative(p, src);
    let edges: BTreeSet<(String, String)> = graph
        .edges
        .iter()
        .flat_map(|(a, bs)| bs.iter().map(move |b| (name(a), name(b))))
        .collect();
    let expect: BTreeSet<(String, String)> = expect
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    assert_eq!(edges, expect);
}

/// `crates/*` and the workspace's own test crate.
fn crate_dirs(workspace: &Path) -> Vec<PathBuf> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(workspace.join("crates"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("Cargo.toml").is_file())
        .collect();
    dirs.push(workspace.join("tests"));
    dirs.sort();
    dirs
}

/// The crate roots of a package: its library and binary, and each integration test.
fn roots(dir: &Path) -> Vec<PathBuf> {
    let mut roots: Vec<PathBuf> = ["src/lib.rs", "src/main.rs"]
        .iter()
        .map(|r| dir.join(r))
        .filter(|p| p.is_file())
        .collect();
    if let Ok(entries) = std::fs::read_dir(dir.join("tests")) {
        for e in entries {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|e| e == "rs") {
                roots.push(p);
            } else if p.join("main.rs").is_file() {
                roots.push(p.join("main.rs"));
            }
        }
    }
    roots.sort();
    roots
}

fn relative(file: &Path, base: &Path) -> String {
    file.strip_prefix(base)
        .unwrap_or(file)
        .to_string_lossy()
        .to_string()
}

/// A token of Rust source: a word (identifier, keyword, number) or a punctuation mark, with
/// `::` as one.
#[derive(Debug, Clone, PartialEq)]
enum Token {
    Word(String),
    Punct(&'static str),
    /// A string literal's text (escapes left as written).
    Str(String),
    Other,
}

/// The words and punctuation of `source`, without comments, strings or character literals.
fn tokens(source: &str) -> Vec<Token> {
    let s: Vec<char> = source.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < s.len() {
        let c = s[i];
        let next = s.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < s.len() && s[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < s.len() {
                if s[i] == '/' && s.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if s[i] == '*' && s.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if c == '"' {
            let end = skip_string(&s, i + 1);
            out.push(Token::Str(s[i + 1..end - 1].iter().collect()));
            i = end;
        } else if (c == 'r' || c == 'b')
            && let Some(end) = raw_string_end(&s, i)
        {
            i = end;
            out.push(Token::Other);
        } else if c == 'b' && next == Some('"') {
            i = skip_string(&s, i + 2);
            out.push(Token::Other);
        } else if c == '\'' {
            // A character literal ('a', '\n', '\u{1F600}') or a lifetime ('a).
            if next == Some('\\') {
                i += 2;
                while i < s.len() && s[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if s.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
                while i < s.len() && (s[i].is_alphanumeric() || s[i] == '_') {
                    i += 1;
                }
            }
            out.push(Token::Other);
        } else if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < s.len() && (s[i].is_alphanumeric() || s[i] == '_') {
                i += 1;
            }
            out.push(Token::Word(s[start..i].iter().collect()));
        } else if c == ':' && next == Some(':') {
            out.push(Token::Punct("::"));
            i += 2;
        } else {
            let p = match c {
                '{' => "{",
                '}' => "}",
                ';' => ";",
                ',' => ",",
                '*' => "*",
                '#' => "#",
                '[' => "[",
                ']' => "]",
                '(' => "(",
                ')' => ")",
                '!' => "!",
                _ => "",
            };
            if !c.is_whitespace() {
                out.push(if p.is_empty() {
                    Token::Other
                } else {
                    Token::Punct(p)
                });
            }
            i += 1;
        }
    }
    out
}

/// The index after a string's closing quote, from just inside its opening quote.
fn skip_string(s: &[char], mut i: usize) -> usize {
    while i < s.len() {
        match s[i] {
            '\\' => i += 2,
            '"' => return i + 1,
            _ => i += 1,
        }
    }
    i
}

/// The index after a raw string (`r"…"`, `r#"…"#`, `br"…"`) starting at `i`, if one does.
fn raw_string_end(s: &[char], i: usize) -> Option<usize> {
    if i > 0 && (s[i - 1].is_alphanumeric() || s[i - 1] == '_') {
        return None;
    }
    let mut j = i;
    if s[j] == 'b' {
        j += 1;
    }
    if s.get(j) != Some(&'r') {
        return None;
    }
    j += 1;
    let mut hashes = 0;
    while s.get(j) == Some(&'#') {
        hashes += 1;
        j += 1;
    }
    if s.get(j) != Some(&'"') {
        return None;
    }
    j += 1;
    while j < s.len() {
        if s[j] == '"' && (1..=hashes).all(|k| s.get(j + k) == Some(&'#')) {
            return Some(j + 1 + hashes);
        }
        j += 1;
    }
    Some(j)
}

/// A module path from the crate root (`[]` is the root).
type ModPath = Vec<String>;

/// A name a module imports: the path it stands for, as written, and whether it is public.
#[derive(Debug, Clone)]
struct Import {
    path: Vec<String>,
    public: bool,
}

/// One module (a file's, or an inline `mod x { … }`).
#[derive(Debug, Default)]
struct Module {
    file: PathBuf,
    children: BTreeSet<String>,
    imports: BTreeMap<String, Import>,
    globs: Vec<Vec<String>>,
    defined: BTreeSet<String>,
    /// Paths named in code or in private `use`s, with the module they were named in.
    uses: Vec<Vec<String>>,
    /// Words of the module's code outside `use` items: whether a `pub use` name is used.
    words: BTreeSet<String>,
}

/// A crate's modules and the imports between its files.
struct Crate {
    modules: BTreeMap<ModPath, Module>,
    edges: BTreeMap<PathBuf, BTreeSet<PathBuf>>,
}

impl Crate {
    /// Reads the crate whose root file is `root`.
    fn read(root: &Path) -> Crate {
        let mut modules = BTreeMap::new();
        let mut pending = vec![(Vec::new(), root.to_path_buf())];
        while let Some((path, file)) = pending.pop() {
            let source = std::fs::read_to_string(&file)
                .unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            // A file's child modules live beside it (`lib.rs`, `main.rs`, `mod.rs`) or in the
            // folder of its own name.
            let stem = file.file_stem().unwrap().to_string_lossy().to_string();
            let dir = if path.is_empty() || stem == "mod" {
                file.parent().unwrap().to_path_buf()
            } else {
                file.parent().unwrap().join(&stem)
            };
            read_module(
                &tokens(&source),
                &path,
                &file,
                &dir,
                &mut modules,
                &mut pending,
            );
        }
        let mut graph = Crate {
            modules,
            edges: BTreeMap::new(),
        };
        let mut edges: BTreeMap<PathBuf, BTreeSet<PathBuf>> = BTreeMap::new();
        for (path, module) in &graph.modules {
            let mut named: Vec<Vec<String>> = module.uses.clone();
            for (name, import) in &module.imports {
                if !import.public || module.words.contains(name) {
                    named.push(import.path.clone());
                }
            }
            named.extend(module.globs.iter().cloned());
            for p in named {
                if let Some(target) = graph.resolve(path, &p, 0)
                    && let Some(to) = graph.modules.get(&target).map(|m| m.file.clone())
                    && to != module.file
                {
                    edges.entry(module.file.clone()).or_default().insert(to);
                }
            }
        }
        graph.edges = edges;
        graph
    }

    /// The module that defines what `path`, named in module `at`, stands for; `None` for
    /// something outside the crate (another crate, a local variable, a type's associated
    /// item).
    fn resolve(&self, at: &ModPath, path: &[String], depth: usize) -> Option<ModPath> {
        if depth > 16 || path.is_empty() {
            return None;
        }
        let mut module: ModPath;
        let mut rest = path;
        match path[0].as_str() {
            "crate" => {
                module = Vec::new();
                rest = &path[1..];
            }
            "self" => {
                module = at.clone();
                rest = &path[1..];
            }
            "super" => {
                module = at.clone();
                while rest.first().is_some_and(|s| s == "super") {
                    module.pop()?;
                    rest = &rest[1..];
                }
            }
            first => {
                let here = self.modules.get(at)?;
                if here.children.contains(first) || here.imports.contains_key(first) {
                    module = at.clone();
                } else {
                    return None;
                }
            }
        }
        // Walk the remaining segments: into child modules, through imports, to the module
        // that defines the first name that is not a module.
        for (k, seg) in rest.iter().enumerate() {
            let m = self.modules.get(&module)?;
            if m.children.contains(seg) {
                module.push(seg.clone());
                continue;
            }
            if let Some(import) = m.imports.get(seg) {
                let mut target = import.path.clone();
                target.extend(rest[k + 1..].iter().cloned());
                return self.resolve(&module, &target, depth + 1);
            }
            if !m.defined.contains(seg) {
                for glob in &m.globs {
                    let mut target = glob.clone();
                    target.extend(rest[k..].iter().cloned());
                    if let Some(found) = self.resolve(&module, &target, depth + 1)
                        && self.names(&found, seg)
                    {
                        return Some(found);
                    }
                }
            }
            return Some(module);
        }
        Some(module)
    }

    /// Whether module `m` defines, imports or holds `name`.
    fn names(&self, m: &ModPath, name: &str) -> bool {
        self.modules.get(m).is_some_and(|m| {
            m.defined.contains(name) || m.imports.contains_key(name) || m.children.contains(name)
        })
    }

    /// The circles between files: each strongly connected set of more than one file, in
    /// name order (Tarjan's algorithm).
    fn circles(&self) -> Vec<Vec<PathBuf>> {
        let files: BTreeSet<PathBuf> = self.modules.values().map(|m| m.file.clone()).collect();
        strongly_connected(&files, &self.edges)
    }

    /// The circles between the crate root's modules, each taken whole with the files below
    /// it (`structure/` with `structure/compiled.rs`): a file of module `a` that imports a
    /// file of module `b`, while a file of `b` imports one of `a`, is a circle between `a`
    /// and `b` even where no two files import each other (a name taken through `b`'s
    /// re-export from one of its children). The root's own file belongs to none.
    fn module_circles(&self) -> Vec<Vec<String>> {
        let top: BTreeMap<&PathBuf, String> = self
            .modules
            .iter()
            .filter_map(|(path, m)| path.first().map(|t| (&m.file, t.clone())))
            .collect();
        let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (from, tos) in &self.edges {
            for to in tos {
                if let (Some(a), Some(b)) = (top.get(from), top.get(to))
                    && a != b
                {
                    edges.entry(a.clone()).or_default().insert(b.clone());
                }
            }
        }
        let names: BTreeSet<String> = top.values().cloned().collect();
        strongly_connected(&names, &edges)
    }
}

/// Each strongly connected set of more than one of `nodes` under `edges`, sorted, in order
/// (Tarjan's algorithm).
fn strongly_connected<T: Ord + Clone>(
    nodes: &BTreeSet<T>,
    edges: &BTreeMap<T, BTreeSet<T>>,
) -> Vec<Vec<T>> {
    let nodes: Vec<&T> = nodes.iter().collect();
    let index: BTreeMap<&T, usize> = nodes.iter().enumerate().map(|(i, f)| (*f, i)).collect();
    let next: Vec<Vec<usize>> = nodes
        .iter()
        .map(|f| {
            edges
                .get(*f)
                .into_iter()
                .flatten()
                .filter_map(|t| index.get(t).copied())
                .collect()
        })
        .collect();
    let mut tarjan = Tarjan {
        next: &next,
        index: vec![None; nodes.len()],
        low: vec![0; nodes.len()],
        on_stack: vec![false; nodes.len()],
        stack: Vec::new(),
        counter: 0,
        found: Vec::new(),
    };
    for v in 0..nodes.len() {
        if tarjan.index[v].is_none() {
            tarjan.visit(v);
        }
    }
    let mut circles: Vec<Vec<T>> = tarjan
        .found
        .into_iter()
        .filter(|c| c.len() > 1)
        .map(|c| {
            let mut c: Vec<T> = c.into_iter().map(|v| nodes[v].clone()).collect();
            c.sort();
            c
        })
        .collect();
    circles.sort();
    circles
}

struct Tarjan<'a> {
    next: &'a [Vec<usize>],
    index: Vec<Option<usize>>,
    low: Vec<usize>,
    on_stack: Vec<bool>,
    stack: Vec<usize>,
    counter: usize,
    found: Vec<Vec<usize>>,
}

impl Tarjan<'_> {
    fn visit(&mut self, v: usize) {
        self.index[v] = Some(self.counter);
        self.low[v] = self.counter;
        self.counter += 1;
        self.stack.push(v);
        self.on_stack[v] = true;
        for &w in &self.next[v] {
            match self.index[w] {
                None => {
                    self.visit(w);
                    self.low[v] = self.low[v].min(self.low[w]);
                }
                Some(iw) if self.on_stack[w] => self.low[v] = self.low[v].min(iw),
                Some(_) => {}
            }
        }
        if Some(self.low[v]) == self.index[v] {
            let mut component = Vec::new();
            while let Some(w) = self.stack.pop() {
                self.on_stack[w] = false;
                component.push(w);
                if w == v {
                    break;
                }
            }
            self.found.push(component);
        }
    }
}

/// Reads the tokens of the file `file`, module `path`, whose child module files live in
/// `dir`: records its modules (inline ones too) and queues its child module files.
fn read_module(
    t: &[Token],
    path: &ModPath,
    file: &Path,
    dir: &Path,
    modules: &mut BTreeMap<ModPath, Module>,
    pending: &mut Vec<(ModPath, PathBuf)>,
) {
    let word = |i: usize| match t.get(i) {
        Some(Token::Word(w)) => Some(w.as_str()),
        _ => None,
    };
    let punct = |i: usize, p: &str| t.get(i) == Some(&Token::Punct(leak(p)));
    // A `#[path = "…"]` on the next `mod NAME;`: its file, beside this one.
    let mut path_attribute: Option<PathBuf> = None;
    // The inline modules open at each point: (module path, brace depth inside it).
    let mut open: Vec<(ModPath, usize)> = vec![(path.clone(), 0)];
    modules.entry(path.clone()).or_default().file = file.to_path_buf();
    let mut depth = 0;
    let mut i = 0;
    while i < t.len() {
        let here = open.last().unwrap().0.clone();
        // Attributes (`#[cfg(test)]`, `#[derive(…)]`) are skipped whole.
        if punct(i, "#") {
            let mut j = i + 1;
            if punct(j, "!") {
                j += 1;
            }
            if punct(j, "[") {
                if word(j + 1) == Some("path")
                    && let Some(Token::Str(p)) = t.get(j + 3)
                {
                    path_attribute = Some(file.parent().unwrap().join(p));
                }
                let mut d = 0;
                while j < t.len() {
                    if punct(j, "[") {
                        d += 1;
                    } else if punct(j, "]") {
                        d -= 1;
                        if d == 0 {
                            break;
                        }
                    }
                    j += 1;
                }
                i = j + 1;
                continue;
            }
        }
        match &t[i] {
            Token::Punct("{") => depth += 1,
            Token::Punct("}") => {
                depth -= 1;
                if open.len() > 1 && open.last().unwrap().1 == depth {
                    open.pop();
                }
            }
            Token::Word(w) if w == "mod" => {
                if let Some(name) = word(i + 1) {
                    let mut child = here.clone();
                    child.push(name.to_string());
                    modules
                        .entry(here.clone())
                        .or_default()
                        .children
                        .insert(name.to_string());
                    if punct(i + 2, ";") {
                        // Inline modules' files are nested under the folder of each inline
                        // module's name.
                        let mut folder = dir.to_path_buf();
                        for inline in &here[path.len()..] {
                            folder.push(inline);
                        }
                        let flat = folder.join(format!("{name}.rs"));
                        let nested = folder.join(name).join("mod.rs");
                        let found = match path_attribute.take() {
                            Some(p) => p,
                            None if flat.is_file() => flat,
                            None => nested,
                        };
                        pending.push((child, found));
                        i += 3;
                        continue;
                    }
                    if punct(i + 2, "{") {
                        modules.entry(child.clone()).or_default().file = file.to_path_buf();
                        depth += 1;
                        open.push((child, depth));
                        i += 3;
                        continue;
                    }
                }
            }
            Token::Word(w) if w == "use" && !punct(i + 1, "::") => {
                let public = i > 0 && (word(i - 1) == Some("pub") || punct(i - 1, ")"));
                let end = (i..t.len()).find(|&j| punct(j, ";")).unwrap_or(t.len());
                let module = modules.entry(here.clone()).or_default();
                use_tree(&t[i + 1..end], Vec::new(), public, module);
                i = end + 1;
                continue;
            }
            Token::Word(w)
                if matches!(
                    w.as_str(),
                    "fn" | "struct" | "enum" | "const" | "static" | "type" | "trait" | "union"
                ) =>
            {
                if let Some(name) = word(i + 1) {
                    let module = modules.entry(here.clone()).or_default();
                    module.defined.insert(name.to_string());
                }
            }
            Token::Word(first) if punct(i + 1, "::") && (i == 0 || !punct(i - 1, "::")) => {
                let mut p = vec![first.clone()];
                let mut j = i + 1;
                while punct(j, "::")
                    && let Some(next) = word(j + 1)
                {
                    p.push(next.to_string());
                    j += 2;
                }
                let module = modules.entry(here.clone()).or_default();
                module.words.insert(first.clone());
                module.uses.push(p);
                i = j;
                continue;
            }
            Token::Word(w) => {
                modules
                    .entry(here.clone())
                    .or_default()
                    .words
                    .insert(w.clone());
            }
            _ => {}
        }
        i += 1;
    }
}

/// `"::"` and the other marks as the `'static` strings [`Token::Punct`] holds.
fn leak(p: &str) -> &'static str {
    ["::", "{", "}", ";", ",", "*", "#", "[", "]", "(", ")", "!"]
        .into_iter()
        .find(|q| *q == p)
        .unwrap_or("")
}

/// Records the names a `use` tree (the tokens between `use` and `;`) imports into `module`,
/// each under `prefix`.
fn use_tree(t: &[Token], prefix: Vec<String>, public: bool, module: &mut Module) {
    let mut path = prefix;
    let mut i = 0;
    if t.first() == Some(&Token::Punct("::")) {
        // `use ::name`: always another crate.
        return;
    }
    while i < t.len() {
        match &t[i] {
            Token::Word(w) if w == "as" => {
                if let Some(Token::Word(alias)) = t.get(i + 1)
                    && alias != "_"
                {
                    module.imports.insert(
                        alias.clone(),
                        Import {
                            path: path.clone(),
                            public,
                        },
                    );
                }
                return;
            }
            Token::Word(w) => {
                path.push(w.clone());
                i += 1;
            }
            Token::Punct("::") => i += 1,
            Token::Punct("*") => {
                module.globs.push(path);
                return;
            }
            Token::Punct("{") => {
                // Split the group at its top-level commas.
                let mut d = 0;
                let mut start = i + 1;
                for j in i..t.len() {
                    match t[j] {
                        Token::Punct("{") => d += 1,
                        Token::Punct("}") => {
                            d -= 1;
                            if d == 0 {
                                use_tree(&t[start..j], path.clone(), public, module);
                                return;
                            }
                        }
                        Token::Punct(",") if d == 1 => {
                            use_tree(&t[start..j], path.clone(), public, module);
                            start = j + 1;
                        }
                        _ => {}
                    }
                }
                return;
            }
            _ => i += 1,
        }
    }
    if let Some(last) = path.last().cloned() {
        // `use a::b::{self}` imports `b`.
        let name = if last == "self" {
            path.pop();
            match path.last() {
                Some(n) => n.clone(),
                None => return,
            }
        } else {
            last
        };
        module.imports.insert(name, Import { path, public });
    }
}

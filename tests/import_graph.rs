//! The import graph of `src/`: no file may depend on itself through other files.
//!
//! A small, dependency-free reader of the crate's own source. It walks the module tree from
//! `src/lib.rs` (following `mod` declarations to `x.rs` or `x/mod.rs`, and inline `mod x { .. }`
//! blocks), and collects, per file, every item it names from elsewhere in the crate:
//! `use` trees (`use crate::a::{b, c::{D, E}}`, `use super::..`, `use self::..`, uniform paths
//! through a child module or an earlier import, `as` renames, globs) and inline paths
//! (`crate::a::b::Item::new()`, `super::x::Y`, `alias::Item` through an imported module).
//! Each name is resolved to the file that *defines* it: `pub use` re-exports are followed, and a
//! module reached on the way costs nothing, so a `mod.rs` that only declares and re-exports is
//! transparent. A `macro_rules!` macro used below its definition is an edge to the defining file.
//! Declaring a child module (`mod x;`) is not an edge. Method calls are not seen (they name no
//! path); a glob import of another file's module counts as naming everything it exports.
//!
//! The file graph must have no cycle (a strongly connected component of more than one file);
//! every cycle is printed as `a.rs -> b.rs -> a.rs` with the line that makes each edge. A
//! `crate::`/`super::`/`self::` path the reader cannot resolve fails the test too, so a gap in
//! the reader cannot pass silently. The checker is itself tested on small synthetic trees.

use std::collections::{BTreeMap, BTreeSet, HashMap, HashSet, VecDeque};
use std::fs;
use std::path::{Path, PathBuf};

/// Cycles tolerated while a redesign is under way: each entry is a set of files (relative to
/// `src/`), and a cycle is tolerated while all its files lie in one entry. Only files of
/// `effects`, `integrate`, `collide` and `sim` may be named here (checked below). Empty: the
/// import graph has no cycle (in the core, mesh or scene).
const KNOWN_CYCLES: &[&[&str]] = &[];

/// Cycles outside the core tolerated the same way; empty.
const LEFT_TO_ANOTHER_BRANCH: &[&[&str]] = &[];

/// Module folders whose internal cycles may be listed in `KNOWN_CYCLES`.
const CORE_WITH_KNOWN_CYCLES: &[&str] = &["effects/", "integrate/", "collide/", "sim/"];

// ---------------------------------------------------------------------------------------------
// Tokens

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    /// `::`
    PathSep,
    Open(char),
    Close(char),
    Punct(char),
    /// A literal or lifetime: its content never names an item.
    Lit,
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    line: usize,
}

/// Splits Rust source into the tokens the reader needs; comments, strings, chars and
/// lifetimes never produce identifiers.
fn tokenize(src: &str) -> Vec<Token> {
    let c: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let mut line = 1;
    let n = c.len();
    let is_id_start = |ch: char| ch.is_alphabetic() || ch == '_';
    let is_id = |ch: char| ch.is_alphanumeric() || ch == '_';
    while i < n {
        let ch = c[i];
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && i + 1 < n && c[i + 1] == '/' {
            while i < n && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && i + 1 < n && c[i + 1] == '*' {
            let mut depth = 1;
            i += 2;
            while i < n && depth > 0 {
                if c[i] == '\n' {
                    line += 1;
                }
                if c[i] == '/' && i + 1 < n && c[i + 1] == '*' {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && i + 1 < n && c[i + 1] == '/' {
                    depth -= 1;
                    i += 2;
                } else {
                    i += 1;
                }
            }
        } else if ch == '"' {
            let start_line = line;
            i = skip_string(&c, i, &mut line);
            out.push(Token {
                tok: Tok::Lit,
                line: start_line,
            });
        } else if ch == '\'' {
            // Char literal ('a', '\n', '\u{1F}') or lifetime ('a).
            if i + 1 < n && c[i + 1] == '\\' {
                i += 2;
                while i < n && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if i + 2 < n && c[i + 2] == '\'' {
                i += 3;
            } else {
                i += 1;
                while i < n && is_id(c[i]) {
                    i += 1;
                }
            }
            out.push(Token {
                tok: Tok::Lit,
                line,
            });
        } else if ch.is_ascii_digit() {
            while i < n && (is_id(c[i]) || (c[i] == '.' && i + 1 < n && c[i + 1].is_ascii_digit()))
            {
                i += 1;
            }
            out.push(Token {
                tok: Tok::Lit,
                line,
            });
        } else if is_id_start(ch) {
            let s = i;
            while i < n && is_id(c[i]) {
                i += 1;
            }
            let word: String = c[s..i].iter().collect();
            let raw_prefix = matches!(word.as_str(), "r" | "br" | "cr");
            let str_prefix = matches!(word.as_str(), "b" | "c") || raw_prefix;
            if raw_prefix && i < n && c[i] == '#' && i + 1 < n && is_id_start(c[i + 1]) {
                // Raw identifier r#name.
                let s2 = i + 1;
                i += 1;
                while i < n && is_id(c[i]) {
                    i += 1;
                }
                let name: String = c[s2..i].iter().collect();
                out.push(Token {
                    tok: Tok::Ident(name),
                    line,
                });
            } else if raw_prefix && i < n && (c[i] == '"' || c[i] == '#') {
                let mut hashes = 0;
                while i < n && c[i] == '#' {
                    hashes += 1;
                    i += 1;
                }
                // c[i] == '"'
                i += 1;
                let start_line = line;
                loop {
                    if i >= n {
                        break;
                    }
                    if c[i] == '\n' {
                        line += 1;
                    }
                    if c[i] == '"' && (0..hashes).all(|k| i + 1 + k < n && c[i + 1 + k] == '#') {
                        i += 1 + hashes;
                        break;
                    }
                    i += 1;
                }
                out.push(Token {
                    tok: Tok::Lit,
                    line: start_line,
                });
            } else if str_prefix && i < n && c[i] == '"' {
                let start_line = line;
                i = skip_string(&c, i, &mut line);
                out.push(Token {
                    tok: Tok::Lit,
                    line: start_line,
                });
            } else if word == "b" && i < n && c[i] == '\'' {
                // Byte literal b'x'.
                i += 1;
                if i < n && c[i] == '\\' {
                    i += 1;
                }
                while i < n && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
                out.push(Token {
                    tok: Tok::Lit,
                    line,
                });
            } else {
                out.push(Token {
                    tok: Tok::Ident(word),
                    line,
                });
            }
        } else if ch == ':' && i + 1 < n && c[i + 1] == ':' {
            out.push(Token {
                tok: Tok::PathSep,
                line,
            });
            i += 2;
        } else if matches!(ch, '{' | '(' | '[') {
            out.push(Token {
                tok: Tok::Open(ch),
                line,
            });
            i += 1;
        } else if matches!(ch, '}' | ')' | ']') {
            out.push(Token {
                tok: Tok::Close(ch),
                line,
            });
            i += 1;
        } else {
            out.push(Token {
                tok: Tok::Punct(ch),
                line,
            });
            i += 1;
        }
    }
    out
}

/// Skips a `"..."` string starting at `c[i] == '"'`; returns the index after its end.
fn skip_string(c: &[char], mut i: usize, line: &mut usize) -> usize {
    i += 1;
    while i < c.len() {
        match c[i] {
            '\\' => i += 2,
            '"' => return i + 1,
            '\n' => {
                *line += 1;
                i += 1;
            }
            _ => i += 1,
        }
    }
    i
}

// ---------------------------------------------------------------------------------------------
// Modules and the names they bind

#[derive(Default, Debug)]
struct Module {
    file: usize,
    parent: Option<usize>,
    /// Directory where this module's child files live.
    dir: PathBuf,
    children: HashMap<String, usize>,
    /// Items defined here (struct, enum, fn, trait, type, const, static, union).
    items: HashSet<String>,
    /// `use` bindings: name -> path, relative to this module.
    uses: HashMap<String, Vec<String>>,
    /// Glob imports: paths, relative to this module.
    globs: Vec<Vec<String>>,
    /// `macro_rules!` defined here.
    macros: HashSet<String>,
    /// A macro invoked at module level may define items the reader cannot see.
    has_item_macros: bool,
}

/// One place where a file names something: a use leaf, a glob, an inline path, a macro call.
#[derive(Debug, Clone)]
struct Ref {
    module: usize,
    line: usize,
    path: Vec<String>,
    kind: RefKind,
    /// For a `pub use`: the name it binds. A re-export is an edge only if the file itself
    /// uses that name too.
    reexport: Option<String>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum RefKind {
    Use,
    Glob,
    Inline,
    Macro,
}

#[derive(Debug, Clone, PartialEq)]
enum Res {
    /// An item defined in this file.
    Item(usize),
    Module(usize),
    /// Outside the crate (std, a dependency, a generic parameter, `Self`).
    External,
    Unresolved,
}

#[derive(Default, Debug)]
struct Crate {
    /// File paths relative to the source root.
    files: Vec<String>,
    modules: Vec<Module>,
    refs: Vec<(usize, Ref)>,
    /// Per file, the identifiers that occur outside its `use` declarations.
    idents: Vec<HashSet<String>>,
    /// Problems reading the tree (missing module files).
    problems: Vec<String>,
}

impl Crate {
    fn read(root: &Path) -> Crate {
        let mut k = Crate::default();
        let lib = root.join("lib.rs");
        k.files.push("lib.rs".to_string());
        k.modules.push(Module {
            file: 0,
            parent: None,
            dir: root.to_path_buf(),
            ..Default::default()
        });
        let mut todo = vec![(0usize, 0usize, lib)];
        while let Some((file, module, path)) = todo.pop() {
            let src = match fs::read_to_string(&path) {
                Ok(s) => s,
                Err(e) => {
                    k.problems.push(format!("{}: {e}", path.display()));
                    continue;
                }
            };
            let toks = tokenize(&src);
            if k.idents.len() <= file {
                k.idents.resize_with(file + 1, HashSet::new);
            }
            for (name, child_mod) in k.parse_file(file, module, &toks) {
                let dir = k.modules[child_mod].dir.clone();
                let parent_dir = k.modules[module].dir.clone();
                let flat = parent_dir.join(format!("{name}.rs"));
                let nested = parent_dir.join(&name).join("mod.rs");
                let found = if flat.is_file() {
                    Some(flat)
                } else if nested.is_file() {
                    Some(nested)
                } else {
                    None
                };
                let Some(p) = found else {
                    k.problems.push(format!(
                        "{}: module `{name}` has no file {}/{name}.rs or {name}/mod.rs",
                        k.files[file],
                        dir.display()
                    ));
                    continue;
                };
                let rel = p
                    .strip_prefix(root)
                    .unwrap_or(&p)
                    .to_string_lossy()
                    .replace('\\', "/");
                let idx = k.files.len();
                k.files.push(rel);
                k.modules[child_mod].file = idx;
                todo.push((idx, child_mod, p));
            }
        }
        k
    }

    fn new_module(&mut self, parent: usize, name: &str, file: usize) -> usize {
        let dir = self.modules[parent].dir.join(name);
        let id = self.modules.len();
        self.modules.push(Module {
            file,
            parent: Some(parent),
            dir,
            ..Default::default()
        });
        self.modules[parent].children.insert(name.to_string(), id);
        id
    }

    /// Reads one file's tokens into the module tree; returns the child modules declared with
    /// `mod name;` (their files still to be read).
    fn parse_file(&mut self, file: usize, module: usize, t: &[Token]) -> Vec<(String, usize)> {
        let mut file_children = Vec::new();
        // (module, brace depth of its body)
        let mut stack: Vec<(usize, usize)> = vec![(module, 0)];
        let mut depth = 0usize;
        let mut i = 0;
        let ident = |k: usize| match t.get(k).map(|x| &x.tok) {
            Some(Tok::Ident(s)) => Some(s.as_str()),
            _ => None,
        };
        let is = |k: usize, tok: &Tok| t.get(k).map(|x| &x.tok) == Some(tok);
        while i < t.len() {
            let (scope, base) = *stack.last().expect("module stack");
            let at_module_level = depth == base;
            match &t[i].tok {
                Tok::Open('{') => {
                    depth += 1;
                    i += 1;
                    continue;
                }
                Tok::Close('}') => {
                    if depth == base && stack.len() > 1 {
                        stack.pop();
                    }
                    depth = depth.saturating_sub(1);
                    i += 1;
                    continue;
                }
                _ => {}
            }
            let Some(word) = ident(i) else {
                i += 1;
                continue;
            };
            if word != "use" {
                self.idents[file].insert(word.to_string());
            }
            let after_sep = i > 0 && is(i - 1, &Tok::PathSep);
            if word == "use" && !after_sep && !is(i + 1, &Tok::Punct('<')) {
                let line = t[i].line;
                let public = is_public(t, i);
                let mut j = i + 1;
                let mut leaves = Vec::new();
                parse_use_tree(t, &mut j, Vec::new(), &mut leaves);
                for leaf in leaves {
                    match leaf {
                        UseLeaf::Bind(name, path) => {
                            if name != "_" {
                                self.modules[scope].uses.insert(name.clone(), path.clone());
                            }
                            let reexport = public.then_some(name);
                            self.refs.push((
                                file,
                                Ref {
                                    module: scope,
                                    line,
                                    path,
                                    kind: RefKind::Use,
                                    reexport,
                                },
                            ));
                        }
                        UseLeaf::Glob(path) => {
                            self.modules[scope].globs.push(path.clone());
                            let reexport = public.then(|| "*".to_string());
                            self.refs.push((
                                file,
                                Ref {
                                    module: scope,
                                    line,
                                    path,
                                    kind: RefKind::Glob,
                                    reexport,
                                },
                            ));
                        }
                    }
                }
                while j < t.len() && !is(j, &Tok::Punct(';')) {
                    j += 1;
                }
                i = j + 1;
                continue;
            }
            if at_module_level && word == "mod" && !after_sep {
                if let Some(name) = ident(i + 1) {
                    let name = name.to_string();
                    if is(i + 2, &Tok::Punct(';')) {
                        let id = self.new_module(scope, &name, usize::MAX);
                        file_children.push((name, id));
                        i += 3;
                        continue;
                    }
                    if is(i + 2, &Tok::Open('{')) {
                        let id = self.new_module(scope, &name, file);
                        depth += 1;
                        stack.push((id, depth));
                        i += 3;
                        continue;
                    }
                }
            }
            if at_module_level && !after_sep {
                let item_kw = matches!(
                    word,
                    "struct" | "enum" | "trait" | "type" | "fn" | "const" | "static"
                ) || (word == "union"
                    && matches!(
                        t.get(i + 2).map(|x| &x.tok),
                        Some(Tok::Open('{')) | Some(Tok::Punct('<'))
                    ));
                if item_kw {
                    // `static mut X`, `const fn f`, `unsafe fn`: the name is the next free identifier.
                    let mut j = i + 1;
                    while matches!(ident(j), Some("mut" | "fn" | "unsafe" | "async" | "extern")) {
                        j += 1;
                    }
                    if let Some(name) = ident(j) {
                        if name != "_" {
                            self.modules[scope].items.insert(name.to_string());
                        }
                    }
                    i = j + 1;
                    continue;
                }
                if word == "macro_rules" && is(i + 1, &Tok::Punct('!')) {
                    if let Some(name) = ident(i + 2) {
                        self.modules[scope].macros.insert(name.to_string());
                    }
                    // Skip the macro's body: its tokens are a template, not code.
                    let mut j = i + 3;
                    while j < t.len() && !matches!(t[j].tok, Tok::Open(_)) {
                        j += 1;
                    }
                    i = skip_group(t, j);
                    continue;
                }
            }
            if is(i + 1, &Tok::Punct('!')) && !after_sep && !is(i + 2, &Tok::Punct('=')) {
                if at_module_level {
                    self.modules[scope].has_item_macros = true;
                }
                self.refs.push((
                    file,
                    Ref {
                        module: scope,
                        line: t[i].line,
                        path: vec![word.to_string()],
                        kind: RefKind::Macro,
                        reexport: None,
                    },
                ));
                i += 2;
                continue;
            }
            if !after_sep && is(i + 1, &Tok::PathSep) {
                let line = t[i].line;
                let mut path = vec![word.to_string()];
                let mut j = i + 1;
                while is(j, &Tok::PathSep) {
                    match ident(j + 1) {
                        Some(s) => {
                            path.push(s.to_string());
                            j += 2;
                        }
                        None => break,
                    }
                }
                self.refs.push((
                    file,
                    Ref {
                        module: scope,
                        line,
                        path,
                        kind: RefKind::Inline,
                        reexport: None,
                    },
                ));
                i = j;
                continue;
            }
            i += 1;
        }
        file_children
    }

    fn parent(&self, m: usize) -> Option<usize> {
        self.modules[m].parent
    }

    /// Resolves `path` as written in module `scope`.
    fn resolve(&self, scope: usize, path: &[String], guard: &mut HashSet<(usize, String)>) -> Res {
        let Some(first) = path.first() else {
            return Res::Module(scope);
        };
        let (mut cur, rest) = match first.as_str() {
            "crate" => (Res::Module(0), &path[1..]),
            "self" => (Res::Module(scope), &path[1..]),
            "super" => match self.parent(scope) {
                Some(p) => (Res::Module(p), &path[1..]),
                None => return Res::Unresolved,
            },
            "Self" => return Res::External,
            name => match self.lookup(scope, name, guard) {
                Some(r) => (r, &path[1..]),
                None => return Res::External,
            },
        };
        for seg in rest {
            match cur {
                Res::Module(m) => {
                    cur = if seg == "super" {
                        match self.parent(m) {
                            Some(p) => Res::Module(p),
                            None => return Res::Unresolved,
                        }
                    } else if seg == "self" {
                        Res::Module(m)
                    } else {
                        match self.lookup(m, seg, guard) {
                            Some(r) => r,
                            None if self.modules[m].has_item_macros => {
                                Res::Item(self.modules[m].file)
                            }
                            None => return Res::Unresolved,
                        }
                    };
                }
                // An enum's variant, a type's associated item: the item's file is the answer.
                Res::Item(_) | Res::External | Res::Unresolved => break,
            }
        }
        cur
    }

    /// What `name` means inside module `m` (its children, items, imports and globs).
    fn lookup(&self, m: usize, name: &str, guard: &mut HashSet<(usize, String)>) -> Option<Res> {
        let md = &self.modules[m];
        if let Some(&c) = md.children.get(name) {
            return Some(Res::Module(c));
        }
        if md.items.contains(name) {
            return Some(Res::Item(md.file));
        }
        if !guard.insert((m, name.to_string())) {
            return None;
        }
        let found = if let Some(p) = md.uses.get(name) {
            Some(self.resolve(m, p, guard))
        } else {
            md.globs
                .iter()
                .find_map(|g| match self.resolve(m, g, guard) {
                    Res::Module(gm) if gm != m => self.lookup(gm, name, guard),
                    _ => None,
                })
        };
        guard.remove(&(m, name.to_string()));
        found
    }

    /// The files whose items a glob import of module `m` brings in.
    fn glob_files(&self, m: usize) -> BTreeSet<usize> {
        let md = &self.modules[m];
        let mut out = BTreeSet::new();
        if !md.items.is_empty() || md.has_item_macros {
            out.insert(md.file);
        }
        for p in md.uses.values() {
            if let Res::Item(f) = self.resolve(m, p, &mut HashSet::new()) {
                out.insert(f);
            }
        }
        out
    }

    /// Whether module `m` is `anc` or lies inside it.
    fn within(&self, mut m: usize, anc: usize) -> bool {
        loop {
            if m == anc {
                return true;
            }
            match self.parent(m) {
                Some(p) => m = p,
                None => return false,
            }
        }
    }

    /// The file graph: edges `from -> to` with, for each, the first line that makes it.
    fn graph(&self) -> Graph {
        let mut g = Graph {
            files: self.files.clone(),
            ..Default::default()
        };
        let mut macro_defs: Vec<(usize, &str)> = Vec::new();
        for (id, m) in self.modules.iter().enumerate() {
            for name in &m.macros {
                macro_defs.push((id, name.as_str()));
            }
        }
        for (file, r) in &self.refs {
            if let Some(name) = &r.reexport {
                // A glob re-export, or a re-exported name the file does not use itself, only
                // passes the item on.
                if name == "*" || !self.idents[*file].contains(name) {
                    continue;
                }
            }
            let targets: Vec<usize> = match r.kind {
                RefKind::Macro => macro_defs
                    .iter()
                    .filter(|(m, name)| *name == r.path[0] && self.within(r.module, *m))
                    .map(|(m, _)| self.modules[*m].file)
                    .collect(),
                RefKind::Glob => match self.resolve(r.module, &r.path, &mut HashSet::new()) {
                    Res::Module(m) if self.modules[m].file != *file => {
                        self.glob_files(m).into_iter().collect()
                    }
                    Res::Item(f) => vec![f],
                    Res::Unresolved => {
                        g.unresolved.push(format!(
                            "{}:{}: use {}::*",
                            self.files[*file],
                            r.line,
                            r.path.join("::")
                        ));
                        vec![]
                    }
                    _ => vec![],
                },
                RefKind::Use | RefKind::Inline => {
                    match self.resolve(r.module, &r.path, &mut HashSet::new()) {
                        Res::Item(f) => vec![f],
                        Res::Unresolved => {
                            g.unresolved.push(format!(
                                "{}:{}: {}",
                                self.files[*file],
                                r.line,
                                r.path.join("::")
                            ));
                            vec![]
                        }
                        _ => vec![],
                    }
                }
            };
            for to in targets {
                if to != *file {
                    g.edges
                        .entry(*file)
                        .or_default()
                        .entry(to)
                        .or_insert_with(|| {
                            format!("{}:{} {}", self.files[*file], r.line, r.path.join("::"))
                        });
                }
            }
        }
        g.unresolved.extend(self.problems.iter().cloned());
        g
    }
}

/// Whether the `use` at `t[i]` is `pub` or `pub(..)`.
fn is_public(t: &[Token], i: usize) -> bool {
    let Some(prev) = i.checked_sub(1) else {
        return false;
    };
    match &t[prev].tok {
        Tok::Ident(s) => s == "pub",
        Tok::Close(')') => {
            let mut k = prev;
            let mut depth = 0usize;
            loop {
                match t[k].tok {
                    Tok::Close(_) => depth += 1,
                    Tok::Open(_) => {
                        depth -= 1;
                        if depth == 0 {
                            break;
                        }
                    }
                    _ => {}
                }
                if k == 0 {
                    return false;
                }
                k -= 1;
            }
            k > 0 && t[k - 1].tok == Tok::Ident("pub".to_string())
        }
        _ => false,
    }
}

/// Skips a balanced group starting at the opening token `t[j]`; returns the index after it.
fn skip_group(t: &[Token], j: usize) -> usize {
    let mut depth = 0usize;
    let mut k = j;
    while k < t.len() {
        match t[k].tok {
            Tok::Open(_) => depth += 1,
            Tok::Close(_) => {
                depth -= 1;
                if depth == 0 {
                    return k + 1;
                }
            }
            _ => {}
        }
        k += 1;
    }
    k
}

enum UseLeaf {
    /// A binding: the name it binds and the full path.
    Bind(String, Vec<String>),
    Glob(Vec<String>),
}

/// Parses one use tree at `t[*j]` (after `use`, or inside a `{ .. }` group), with `prefix`.
fn parse_use_tree(t: &[Token], j: &mut usize, prefix: Vec<String>, out: &mut Vec<UseLeaf>) {
    let mut path = prefix;
    if t.get(*j).map(|x| &x.tok) == Some(&Tok::PathSep) {
        // `use ::dep::..`: outside the crate.
        path.push("::".to_string());
        *j += 1;
    }
    loop {
        match t.get(*j).map(|x| &x.tok) {
            Some(Tok::Open('{')) => {
                *j += 1;
                loop {
                    match t.get(*j).map(|x| &x.tok) {
                        Some(Tok::Close('}')) => {
                            *j += 1;
                            return;
                        }
                        Some(Tok::Punct(',')) => *j += 1,
                        None => return,
                        _ => parse_use_tree(t, j, path.clone(), out),
                    }
                }
            }
            Some(Tok::Punct('*')) => {
                *j += 1;
                out.push(UseLeaf::Glob(path));
                return;
            }
            Some(Tok::Ident(s)) => {
                let s = s.clone();
                *j += 1;
                if t.get(*j).map(|x| &x.tok) == Some(&Tok::PathSep) {
                    path.push(s);
                    *j += 1;
                    continue;
                }
                let (name, full) = if s == "self" {
                    (path.last().cloned().unwrap_or_default(), path.clone())
                } else {
                    let mut full = path.clone();
                    full.push(s.clone());
                    (s, full)
                };
                let name = if matches!(t.get(*j).map(|x| &x.tok), Some(Tok::Ident(a)) if a == "as")
                {
                    *j += 1;
                    let alias = match t.get(*j).map(|x| &x.tok) {
                        Some(Tok::Ident(a)) => a.clone(),
                        _ => "_".to_string(),
                    };
                    *j += 1;
                    alias
                } else {
                    name
                };
                if full.first().map(String::as_str) != Some("::") {
                    out.push(UseLeaf::Bind(name, full));
                }
                return;
            }
            _ => return,
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The graph and its cycles

#[derive(Default, Debug)]
struct Graph {
    files: Vec<String>,
    /// from -> (to -> the first place that makes the edge)
    edges: BTreeMap<usize, BTreeMap<usize, String>>,
    unresolved: Vec<String>,
}

impl Graph {
    fn succ(&self, n: usize) -> impl Iterator<Item = usize> + '_ {
        self.edges
            .get(&n)
            .into_iter()
            .flat_map(|m| m.keys().copied())
    }

    /// Strongly connected components of more than one file (Tarjan), each sorted by file name.
    fn cycles(&self) -> Vec<Vec<usize>> {
        struct T<'a> {
            g: &'a Graph,
            index: Vec<Option<usize>>,
            low: Vec<usize>,
            on: Vec<bool>,
            stack: Vec<usize>,
            next: usize,
            out: Vec<Vec<usize>>,
        }
        fn visit(t: &mut T, v: usize) {
            t.index[v] = Some(t.next);
            t.low[v] = t.next;
            t.next += 1;
            t.stack.push(v);
            t.on[v] = true;
            let succ: Vec<usize> = t.g.succ(v).collect();
            for w in succ {
                match t.index[w] {
                    None => {
                        visit(t, w);
                        t.low[v] = t.low[v].min(t.low[w]);
                    }
                    Some(iw) if t.on[w] => t.low[v] = t.low[v].min(iw),
                    _ => {}
                }
            }
            if Some(t.low[v]) == t.index[v] {
                let mut comp = Vec::new();
                while let Some(w) = t.stack.pop() {
                    t.on[w] = false;
                    comp.push(w);
                    if w == v {
                        break;
                    }
                }
                if comp.len() > 1 {
                    t.out.push(comp);
                }
            }
        }
        let n = self.files.len();
        let mut t = T {
            g: self,
            index: vec![None; n],
            low: vec![0; n],
            on: vec![false; n],
            stack: Vec::new(),
            next: 0,
            out: Vec::new(),
        };
        for v in 0..n {
            if t.index[v].is_none() {
                visit(&mut t, v);
            }
        }
        for c in &mut t.out {
            c.sort_by(|a, b| self.files[*a].cmp(&self.files[*b]));
        }
        t.out
            .sort_by(|a, b| self.files[a[0]].cmp(&self.files[b[0]]));
        t.out
    }

    /// The shortest cycle through `start` inside `comp`, as file indices ending at `start`.
    fn shortest_cycle(&self, start: usize, comp: &[usize]) -> Vec<usize> {
        let inside: HashSet<usize> = comp.iter().copied().collect();
        let mut prev: HashMap<usize, usize> = HashMap::new();
        let mut q = VecDeque::from([start]);
        while let Some(v) = q.pop_front() {
            for w in self.succ(v) {
                if !inside.contains(&w) {
                    continue;
                }
                if w == start {
                    let mut path = vec![start];
                    let mut x = v;
                    while x != start {
                        path.push(x);
                        x = prev[&x];
                    }
                    path.push(start);
                    path.reverse();
                    return path;
                }
                if let std::collections::hash_map::Entry::Vacant(e) = prev.entry(w) {
                    e.insert(v);
                    q.push_back(w);
                }
            }
        }
        vec![start]
    }

    /// `a.rs -> b.rs -> a.rs` for one cycle.
    fn show(&self, cycle: &[usize]) -> String {
        cycle
            .iter()
            .map(|&f| self.files[f].as_str())
            .collect::<Vec<_>>()
            .join(" -> ")
    }

    /// Every cycle component, with the shortest cycle through each of its files (deduplicated)
    /// and the line behind each edge of those cycles.
    fn describe(&self, comp: &[usize]) -> String {
        let mut seen = BTreeSet::new();
        let mut text = format!(
            "cycle among {} files: {}\n",
            comp.len(),
            comp.iter()
                .map(|&f| self.files[f].as_str())
                .collect::<Vec<_>>()
                .join(", ")
        );
        for &f in comp {
            let c = self.shortest_cycle(f, comp);
            // The same cycle from another start: rotate to its smallest file.
            let body = &c[..c.len() - 1];
            let min = (0..body.len())
                .min_by_key(|&k| &self.files[body[k]])
                .unwrap_or(0);
            let mut rot: Vec<usize> = body[min..].iter().chain(&body[..min]).copied().collect();
            rot.push(rot[0]);
            if seen.insert(rot.clone()) {
                text += &format!("  {}\n", self.show(&rot));
                for w in rot.windows(2) {
                    text += &format!("      because {}\n", self.edges[&w[0]][&w[1]]);
                }
            }
        }
        text
    }

    fn index(&self, file: &str) -> Option<usize> {
        self.files.iter().position(|f| f == file)
    }

    fn has_edge(&self, from: &str, to: &str) -> bool {
        match (self.index(from), self.index(to)) {
            (Some(a), Some(b)) => self.edges.get(&a).is_some_and(|m| m.contains_key(&b)),
            _ => false,
        }
    }
}

fn read_graph(root: &Path) -> Graph {
    Crate::read(root).graph()
}

// ---------------------------------------------------------------------------------------------
// The crate itself

#[test]
fn src_has_no_import_cycles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let g = read_graph(&root);
    assert!(
        g.files.len() > 50,
        "the reader found only {} files under src/",
        g.files.len()
    );
    assert!(
        g.unresolved.is_empty(),
        "paths into the crate the import-graph reader cannot resolve (fix the reader, or the path):\n{}",
        g.unresolved.join("\n")
    );
    let known: Vec<BTreeSet<&str>> = KNOWN_CYCLES
        .iter()
        .chain(LEFT_TO_ANOTHER_BRANCH)
        .map(|c| c.iter().copied().collect())
        .collect();
    let mut tolerated = String::new();
    let mut failing = String::new();
    for comp in g.cycles() {
        let files: BTreeSet<&str> = comp.iter().map(|&f| g.files[f].as_str()).collect();
        let text = g.describe(&comp);
        if known.iter().any(|k| files.is_subset(k)) {
            tolerated += &text;
        } else {
            failing += &text;
        }
    }
    if !tolerated.is_empty() {
        println!("known core cycles (KNOWN_CYCLES, being removed):\n{tolerated}");
    }
    assert!(
        failing.is_empty(),
        "import cycles between files of src/:\n{failing}"
    );
}

#[test]
fn known_cycles_lie_inside_the_core() {
    for entry in KNOWN_CYCLES {
        for file in *entry {
            assert!(
                CORE_WITH_KNOWN_CYCLES.iter().any(|m| file.starts_with(m)),
                "KNOWN_CYCLES may only name files of effects, integrate, collide, sim: {file}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The checker on synthetic trees

/// Writes `files` (path relative to the root, content) into a temporary source tree.
fn tree(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    for (path, text) in files {
        let p = dir.path().join(path);
        if let Some(parent) = p.parent() {
            fs::create_dir_all(parent).expect("create dir");
        }
        fs::write(&p, text).expect("write file");
    }
    dir
}

fn cycles_text(g: &Graph) -> Vec<String> {
    g.cycles()
        .iter()
        .map(|c| g.show(&g.shortest_cycle(c[0], c)))
        .collect()
}

#[test]
fn checker_finds_a_two_file_cycle() {
    let t = tree(&[
        ("lib.rs", "mod a;\nmod b;\n"),
        ("a.rs", "use crate::b::B;\npub struct A(B);\n"),
        ("b.rs", "pub struct B;\nfn f() -> crate::a::A { todo!() }\n"),
    ]);
    let g = read_graph(t.path());
    assert!(g.unresolved.is_empty(), "{:?}", g.unresolved);
    assert_eq!(cycles_text(&g), vec!["a.rs -> b.rs -> a.rs"]);
}

#[test]
fn checker_sees_through_re_exports() {
    // x.rs names `Thing` through m/mod.rs's re-export; the item lives in m/inner.rs, which names
    // x.rs back: a cycle x.rs <-> m/inner.rs that does not include m/mod.rs.
    let t = tree(&[
        ("lib.rs", "pub mod m;\npub mod x;\n"),
        ("m/mod.rs", "mod inner;\npub use inner::Thing;\n"),
        ("m/inner.rs", "use crate::x::X;\npub struct Thing(X);\n"),
        (
            "x.rs",
            "use crate::m::Thing;\npub struct X;\npub fn f(_: Thing) {}\n",
        ),
    ]);
    let g = read_graph(t.path());
    assert!(g.unresolved.is_empty(), "{:?}", g.unresolved);
    assert_eq!(cycles_text(&g), vec!["m/inner.rs -> x.rs -> m/inner.rs"]);
    assert!(!g.has_edge("x.rs", "m/mod.rs"));
}

#[test]
fn checker_treats_a_declaring_mod_rs_as_transparent() {
    // p.rs takes Q through mod.rs; mod.rs declares p and q and re-exports them. Without
    // transparency p.rs -> mod.rs -> p.rs would be a false cycle.
    let t = tree(&[
        ("lib.rs", "mod m;\n"),
        (
            "m/mod.rs",
            "mod p;\nmod q;\npub use p::P;\npub use self::q::Q;\n",
        ),
        ("m/p.rs", "use super::Q;\npub struct P(Q);\n"),
        ("m/q.rs", "pub struct Q;\n"),
    ]);
    let g = read_graph(t.path());
    assert!(g.unresolved.is_empty(), "{:?}", g.unresolved);
    assert!(g.cycles().is_empty(), "{:?}", cycles_text(&g));
    assert!(g.has_edge("m/p.rs", "m/q.rs"));
    assert!(!g.has_edge("m/p.rs", "m/mod.rs"));
    assert!(!g.has_edge("m/mod.rs", "m/p.rs"));
}

#[test]
fn checker_counts_a_re_export_only_where_its_file_uses_it() {
    // lib.rs re-exports Pose and defines Real, which pose.rs uses: no cycle. m/mod.rs re-exports
    // K and also uses it, while kid.rs uses m/mod.rs's M: a cycle.
    let t = tree(&[
        (
            "lib.rs",
            "mod pose;\nmod m;\npub use pose::Pose;\npub type Real = f64;\n",
        ),
        ("pose.rs", "pub struct Pose(crate::Real);\n"),
        (
            "m/mod.rs",
            "mod kid;\npub use kid::K;\npub struct M;\npub fn f(_: K) {}\n",
        ),
        ("m/kid.rs", "pub struct K(super::M);\n"),
    ]);
    let g = read_graph(t.path());
    assert!(g.unresolved.is_empty(), "{:?}", g.unresolved);
    assert!(!g.has_edge("lib.rs", "pose.rs"));
    assert_eq!(cycles_text(&g), vec!["m/kid.rs -> m/mod.rs -> m/kid.rs"]);
}

#[test]
fn checker_reads_grouped_aliased_and_inline_paths() {
    let t = tree(&[
        (
            "lib.rs",
            "pub mod a;\npub mod e;\npub mod user;\npub mod other;\npub type Real = f64;\n",
        ),
        ("a/mod.rs", "pub mod b;\npub mod d;\n"),
        (
            "a/b.rs",
            "pub struct C;\nimpl C { pub fn new() -> C { C } }\n",
        ),
        ("a/d.rs", "pub enum D { One }\n"),
        ("e.rs", "pub struct F;\npub struct G;\n"),
        (
            "user.rs",
            "use crate::{a::{b::{self as bee}, d::D}, e::F as Eff};\n\
             use std::collections::HashMap;\n\
             fn f() { let _ = bee::C::new(); let _ = D::One; let _: Option<Eff> = None;\n\
             let _ = HashMap::<u8, u8>::new(); let _: crate::Real = 1.0; }\n",
        ),
        ("other.rs", "pub fn g() -> crate::e::G { crate::e::G }\n"),
    ]);
    let g = read_graph(t.path());
    assert!(g.unresolved.is_empty(), "{:?}", g.unresolved);
    assert!(g.has_edge("user.rs", "a/b.rs"));
    assert!(g.has_edge("user.rs", "a/d.rs"));
    assert!(g.has_edge("user.rs", "e.rs"));
    assert!(g.has_edge("user.rs", "lib.rs"));
    assert!(g.has_edge("other.rs", "e.rs"));
    assert!(!g.has_edge("user.rs", "a/mod.rs"));
}

#[test]
fn checker_ignores_comments_and_strings_but_not_test_modules() {
    let t = tree(&[
        ("lib.rs", "mod a;\nmod b;\nmod c;\n"),
        (
            "a.rs",
            "// use crate::b::B;\n/* crate::b::B /* nested */ crate::b::B */\n\
             pub const S: &str = \"crate::b::B\";\npub const R: &str = r#\"crate::b::B\"#;\n\
             pub const CH: char = '\"'; pub fn l<'b>(x: &'b str) -> &'b str { x }\n\
             pub struct A;\n",
        ),
        ("b.rs", "use crate::a::A;\npub struct B(A);\n"),
        (
            "c.rs",
            "pub struct Cc;\n#[cfg(test)]\nmod tests {\n    use super::*;\n    use super::super::b::B;\n    \
             #[test] fn t() { let _ = Cc; let _: Option<B> = None; }\n}\n",
        ),
    ]);
    let g = read_graph(t.path());
    assert!(g.unresolved.is_empty(), "{:?}", g.unresolved);
    assert!(g.cycles().is_empty(), "{:?}", cycles_text(&g));
    assert!(!g.has_edge("a.rs", "b.rs"));
    assert!(
        g.has_edge("c.rs", "b.rs"),
        "an inline test module's imports belong to its file"
    );
}

#[test]
fn checker_reports_paths_it_cannot_resolve() {
    let t = tree(&[
        ("lib.rs", "mod a;\n"),
        (
            "a.rs",
            "use crate::nowhere::X;\npub fn f() { super::gone::g(); }\n",
        ),
    ]);
    let g = read_graph(t.path());
    assert_eq!(g.unresolved.len(), 2, "{:?}", g.unresolved);
}

#[test]
fn checker_follows_macros_globs_and_uniform_paths() {
    let t = tree(&[
        ("lib.rs", "mod m;\nmod n;\n"),
        // A macro defined in mod.rs and used in a child is an edge child -> mod.rs.
        (
            "m/mod.rs",
            "macro_rules! mk { () => { crate::n::N } }\nmod kid;\nuse kid::K;\npub struct M(K);\n",
        ),
        ("m/kid.rs", "pub struct K;\npub fn f() { let _ = mk!(); }\n"),
        // A glob import of another file's module names everything it exports.
        (
            "n.rs",
            "pub struct N;\nmod inner {\n    use crate::m::*;\n    fn f(_: M) {}\n}\n",
        ),
    ]);
    let g = read_graph(t.path());
    assert!(g.unresolved.is_empty(), "{:?}", g.unresolved);
    assert!(
        g.has_edge("m/mod.rs", "m/kid.rs"),
        "uniform path through a child module"
    );
    assert!(
        g.has_edge("m/kid.rs", "m/mod.rs"),
        "macro used below its definition"
    );
    assert!(g.has_edge("n.rs", "m/mod.rs"), "glob import");
    assert_eq!(cycles_text(&g), vec!["m/kid.rs -> m/mod.rs -> m/kid.rs"]);
}

//! The architecture rules of STYLE.md, checked on the source text so that they cannot erode
//! unnoticed:
//!
//! * data flows one way: the `use crate::X` graph between the top-level modules of `src/` has no
//!   cycle (a module may use itself, `error` and the leaf helpers freely);
//! * inside every module, the files (and sub-folders) use one another without a cycle: a
//!   module's `mod.rs` is its face (it declares, re-exports and may orchestrate its files) and
//!   is not a node, and test code (`#[cfg(test)]` items, `tests.rs`, `*_tests.rs`) is left out;
//! * no function outside tests (test modules and test files) is longer than
//!   [`MAX_FUNCTION_LINES`] lines, in `src/` and in the Python package's `python/src/` alike;
//! * the command line is a shell over the library: nothing outside `src/cli/` and `src/main.rs`
//!   names `crate::cli` or `pgt::cli`, and `python/src/` names no `pgt::cli`;
//! * the contract is inside the repository: every `§N` the code cites is a heading of
//!   `docs/design.md`, every `docs/….md` it names exists (with the heading it quotes), and every
//!   relative link of README.md and `docs/` resolves (to a file, and to a heading where it has
//!   a `#fragment`).
//!
//! Both scans read text, not the compiler's view: they are deliberately simple, and each has a
//! test below showing that it catches what it is meant to catch.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Longest function body (signature to closing brace) allowed outside tests.
const MAX_FUNCTION_LINES: usize = 120;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The top-level module a file under `src/` belongs to (`src/scene/file.rs` → `scene`,
/// `src/error.rs` → `error`); `None` for `lib.rs` and `main.rs`.
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?;
    let first = rel.components().next()?.as_os_str().to_str()?.to_string();
    let name = first.trim_end_matches(".rs").to_string();
    (name != "lib" && name != "main").then_some(name)
}

/// Removes `//` comments (line and doc comments) so that prose mentioning `crate::x` is not an
/// edge. String literals are left alone: a path inside a string is rare and would show up as a
/// spurious edge, the safe direction.
fn strip_comments(text: &str) -> String {
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The modules named as `crate::NAME` in `text`.
fn crate_paths(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let code = strip_comments(text);
    let mut rest = code.as_str();
    while let Some(i) = rest.find("crate::") {
        let after = &rest[i + "crate::".len()..];
        let name: String = after
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect();
        if !name.is_empty() {
            out.insert(name);
        }
        rest = after;
    }
    out
}

/// Module → the other top-level modules it uses.
fn module_graph(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let modules: BTreeSet<String> = files.iter().filter_map(|f| module_of(src, f)).collect();
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in &files {
        let Some(m) = module_of(src, f) else { continue };
        let text = std::fs::read_to_string(f).unwrap();
        let entry = graph.entry(m.clone()).or_default();
        for used in crate_paths(&text) {
            if used != m && modules.contains(&used) {
                entry.insert(used);
            }
        }
    }
    graph
}

/// One cycle of the graph, if there is one (depth-first search with colours).
fn find_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(node.to_string(), 1);
        stack.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            match state.get(next.as_str()).copied().unwrap_or(0) {
                1 => {
                    let start = stack.iter().position(|s| s == next).unwrap();
                    let mut cycle = stack[start..].to_vec();
                    cycle.push(next.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(next, graph, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(node.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for node in graph.keys() {
        if state.get(node.as_str()).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(node, graph, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

/// Functions longer than `max` lines in `text`, as (line of the signature, name, length).
/// `#[cfg(test)]` items (test modules) are skipped. A function is a line whose code starts with
/// `fn ` after optional `pub`/`pub(crate)`/`const`/`unsafe`/`async`, up to the line with the
/// closing brace at the signature's indentation.
fn long_functions(text: &str, max: usize) -> Vec<(usize, String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let trimmed = line.trim_start();
        let indent = line.len() - trimmed.len();
        if trimmed.starts_with("#[cfg(test)]") {
            // Skip the next item: up to the closing brace at this indentation.
            i = end_of_item(&lines, i + 1, indent).map_or(i + 2, |e| e + 1);
            continue;
        }
        if let Some(name) = fn_name(trimmed) {
            if let Some(end) = end_of_item(&lines, i, indent) {
                let len = end - i + 1;
                if len > max {
                    out.push((i + 1, name, len));
                }
            }
        }
        i += 1;
    }
    out
}

fn fn_name(code: &str) -> Option<String> {
    let mut rest = code;
    for prefix in [
        "pub(crate) ",
        "pub(super) ",
        "pub ",
        "const ",
        "unsafe ",
        "async ",
    ] {
        rest = rest.strip_prefix(prefix).unwrap_or(rest);
    }
    let rest = rest.strip_prefix("fn ")?;
    let name: String = rest
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect();
    (!name.is_empty()).then_some(name)
}

/// The line index of the `}` that closes the item whose first line is `start` and whose closing
/// brace sits at `indent`; the item's own line when it opens and closes its body on one line;
/// `None` for an item without a body (`fn f();`, `use …;`).
fn end_of_item(lines: &[&str], start: usize, indent: usize) -> Option<usize> {
    let mut body_started = false;
    for (j, l) in lines.iter().enumerate().skip(start) {
        let t = l.trim_start();
        if !body_started {
            if t.contains('{') {
                body_started = true;
                if t.matches('{').count() == t.matches('}').count() {
                    return Some(j);
                }
            } else if t.trim_end().ends_with(';') {
                return None;
            }
            continue;
        }
        if l.len() - t.len() == indent && t.starts_with('}') {
            return Some(j);
        }
    }
    None
}

/// Removes `#[cfg(test)]` items (test modules, test-only helpers) from `text`.
fn strip_test_items(text: &str) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        let trimmed = lines[i].trim_start();
        if trimmed.starts_with("#[cfg(test)]") {
            let indent = lines[i].len() - trimmed.len();
            // The item after the attribute: up to its closing brace, or its `;`.
            let next = i + 1;
            let end = if lines.get(next).is_some_and(|l| l.trim_end().ends_with(';')) {
                Some(next)
            } else {
                end_of_item(&lines, next, indent)
            };
            i = end.map_or(next + 1, |e| e + 1);
            continue;
        }
        out.push(lines[i]);
        i += 1;
    }
    out.join("\n")
}

/// Whether a file holds only tests (`tests.rs`, `*_tests.rs`).
fn is_test_file(file: &Path) -> bool {
    file.file_name()
        .and_then(|n| n.to_str())
        .is_some_and(|n| n == "tests.rs" || n.ends_with("_tests.rs"))
}

/// The module path of a file under `src/`: `src/optics/emission.rs` → `optics::emission`,
/// `src/optics/mod.rs` → `optics`; empty for `lib.rs` and `main.rs`.
fn file_module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).expect("a file under src/");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let last = parts.pop().unwrap_or_default();
    let stem = last.trim_end_matches(".rs");
    if !matches!(stem, "mod" | "lib" | "main") {
        parts.push(stem.to_string());
    }
    parts
}

/// The paths of a `use` tree or path expression starting at `text` (just after `crate::`,
/// `super::` or `self::`): `a::b` → [[a, b]], `{a::B, c::{d, e}}` → [[a, B], [c, d], [c, e]].
fn path_tree(text: &str) -> Vec<Vec<String>> {
    fn ident(s: &str) -> (&str, &str) {
        let n = s
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(s.len());
        (&s[..n], &s[n..])
    }
    fn tree(s: &str) -> (Vec<Vec<String>>, &str) {
        let s = s.trim_start();
        if let Some(mut rest) = s.strip_prefix('{') {
            let mut out = Vec::new();
            loop {
                rest = rest.trim_start();
                if let Some(r) = rest.strip_prefix('}') {
                    return (out, r);
                }
                if rest.is_empty() {
                    return (out, rest);
                }
                let (paths, r) = tree(rest);
                out.extend(paths);
                rest = r.trim_start();
                rest = rest.strip_prefix(',').unwrap_or(rest);
                if rest.len() == r.trim_start().len() && !rest.starts_with('}') {
                    // Neither a comma nor the closing brace: not a use tree.
                    return (out, rest);
                }
            }
        }
        let (name, rest) = ident(s);
        if name.is_empty() {
            return (vec![], rest);
        }
        // `name as alias`: the alias is no path.
        let rest = match rest.trim_start().strip_prefix("as ") {
            Some(r) => ident(r.trim_start()).1,
            None => rest,
        };
        match rest.strip_prefix("::") {
            Some(after) => {
                let (subs, r) = tree(after);
                let paths = if subs.is_empty() {
                    vec![vec![name.to_string()]]
                } else {
                    subs.into_iter()
                        .map(|mut p| {
                            p.insert(0, name.to_string());
                            p
                        })
                        .collect()
                };
                (paths, r)
            }
            None => (vec![vec![name.to_string()]], rest),
        }
    }
    tree(text).0
}

/// Every module path `text` names, made absolute for a file whose module path is `module`
/// (`crate::x::y`, `super::x`, `super::super::x`, `self::x`, braced groups included). A
/// `mod.rs` file's module is its folder's.
fn referenced_paths(text: &str, module: &[String]) -> Vec<Vec<String>> {
    let code = strip_comments(text);
    let mut out = Vec::new();
    let bytes = code.as_bytes();
    let mut i = 0;
    while i < code.len() {
        let boundary = i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
        let rest = &code[i..];
        if boundary {
            // A mod.rs file is its folder's module; `self` is that module, `super` its parent.
            let own: Vec<String> = module.to_vec();
            // `super` from module M is M's parent (for a mod.rs too: its module is the folder's).
            let parent = |n: usize| (own.len() >= n).then(|| own[..own.len() - n].to_vec());
            let (base, after) = if let Some(r) = rest.strip_prefix("crate::") {
                (Some(vec![]), r)
            } else if let Some(r) = rest.strip_prefix("self::") {
                (Some(own.clone()), r)
            } else if rest.starts_with("super::") {
                let mut r = rest;
                let mut n = 0;
                while let Some(next) = r.strip_prefix("super::") {
                    r = next;
                    n += 1;
                }
                (parent(n), r)
            } else {
                (None, rest)
            };
            if let Some(base) = base {
                for p in path_tree(after) {
                    let mut abs = base.clone();
                    abs.extend(p);
                    out.push(abs);
                }
                i += rest.len() - after.len();
                continue;
            }
        }
        i += rest.chars().next().map_or(1, char::len_utf8);
    }
    out
}

/// The nodes of the module whose folder is `dir`: its files (but `mod.rs` and test files) and
/// its sub-folders, by module name.
fn module_children(dir: &Path) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    for e in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() {
            out.insert(name);
        } else if let Some(stem) = name.strip_suffix(".rs") {
            if stem != "mod" && !is_test_file(&p) {
                out.insert(stem.to_string());
            }
        }
    }
    out
}

/// For every module folder under `src/` (by module path), the graph between its files and
/// sub-folders: an edge a → b where code in a (or under it) names b.
fn file_graphs(src: &Path) -> BTreeMap<String, BTreeMap<String, BTreeSet<String>>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let mut graphs: BTreeMap<String, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for f in files.iter().filter(|f| !is_test_file(f)) {
        let module = file_module_path(src, f);
        let text = strip_test_items(&std::fs::read_to_string(f).unwrap());
        for path in referenced_paths(&text, &module) {
            // Each module folder that holds this file, below the crate root.
            for depth in 1..module.len() {
                let level = &module[..depth];
                let dir = level.iter().fold(src.to_path_buf(), |d, s| d.join(s));
                if !dir.is_dir() || !path.starts_with(level) || path.len() <= depth {
                    continue;
                }
                let (from, to) = (&module[depth], &path[depth]);
                let children = module_children(&dir);
                if from != to && children.contains(from) && children.contains(to) {
                    graphs
                        .entry(level.join("::"))
                        .or_default()
                        .entry(from.clone())
                        .or_default()
                        .insert(to.clone());
                }
            }
        }
    }
    graphs
}

/// The strongly connected components of more than one node: every set of nodes that reach one
/// another, each a cycle or several.
fn cyclic_components(graph: &BTreeMap<String, BTreeSet<String>>) -> Vec<BTreeSet<String>> {
    let reach = |from: &String| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from.clone()];
        while let Some(n) = stack.pop() {
            for m in graph.get(&n).into_iter().flatten() {
                if seen.insert(m.clone()) {
                    stack.push(m.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&String, BTreeSet<String>> =
        graph.keys().map(|n| (n, reach(n))).collect();
    let mut out: Vec<BTreeSet<String>> = Vec::new();
    for (n, r) in &reached {
        if !r.contains(*n) || out.iter().any(|c| c.contains(*n)) {
            continue;
        }
        let component: BTreeSet<String> = r
            .iter()
            .filter(|m| reached.get(m).is_some_and(|back| back.contains(*n)))
            .cloned()
            .collect();
        out.push(component);
    }
    out
}

#[test]
fn files_inside_each_module_have_no_cycle() {
    let graphs = file_graphs(&src_dir());
    assert!(
        graphs.len() >= 6 && graphs.contains_key("optics") && graphs.contains_key("reference"),
        "the scan found too few module folders: {:?}",
        graphs.keys()
    );
    let cycles: Vec<String> = graphs
        .iter()
        .flat_map(|(m, g)| {
            cyclic_components(g).into_iter().map(move |c| {
                let names: Vec<&str> = c.iter().map(String::as_str).collect();
                format!("{m}: {{{}}} use one another", names.join(", "))
            })
        })
        .collect();
    assert!(
        cycles.is_empty(),
        "cycles between files inside a module:\n{}",
        cycles.join("\n")
    );
}

#[test]
fn the_file_scan_finds_a_cycle_between_files() {
    // A module `m` in a scratch tree whose files a and b use each other (b through a braced
    // `super` group, a through `crate::`), and c uses a: the scan must report a ↔ b.
    let root = std::env::temp_dir().join(format!("pgt-arch-{}", std::process::id()));
    let src = root.join("src");
    let m = src.join("m");
    std::fs::create_dir_all(&m).unwrap();
    std::fs::write(src.join("lib.rs"), "pub mod m;\n").unwrap();
    std::fs::write(
        m.join("mod.rs"),
        "pub mod a;\npub mod b;\npub mod c;\npub use a::A;\n",
    )
    .unwrap();
    std::fs::write(m.join("a.rs"), "use crate::m::b::B;\npub struct A(B);\n").unwrap();
    std::fs::write(
        m.join("b.rs"),
        "use super::{a::A as _, c};\n// super::c in a comment is no edge\npub struct B;\n",
    )
    .unwrap();
    std::fs::write(
        m.join("c.rs"),
        "#[cfg(test)]\nmod tests {\n    use super::super::b;\n}\n",
    )
    .unwrap();
    let graphs = file_graphs(&src);
    std::fs::remove_dir_all(&root).unwrap();
    let g = &graphs["m"];
    let names = |v: &[&str]| -> BTreeSet<String> { v.iter().map(|s| s.to_string()).collect() };
    assert_eq!(cyclic_components(g), vec![names(&["a", "b"])], "{g:?}");
    assert_eq!(g["b"], names(&["a", "c"]));
    assert!(!g.contains_key("c"), "test code is no edge: {g:?}");
}

#[test]
fn top_level_modules_have_no_cycle() {
    let graph = module_graph(&src_dir());
    assert!(
        graph.len() >= 8,
        "the scan found too few modules: {graph:?}"
    );
    if let Some(cycle) = find_cycle(&graph) {
        panic!(
            "cycle between top-level modules: {}\nwhole graph: {graph:#?}",
            cycle.join(" → ")
        );
    }
}

/// The Rust sources of the Python package.
fn python_src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("python")
        .join("src")
}

#[test]
fn no_function_is_longer_than_the_limit() {
    let mut files = Vec::new();
    rust_files(&src_dir(), &mut files);
    rust_files(&python_src_dir(), &mut files);
    assert!(
        files.iter().any(|f| f.ends_with("python/src/scene.rs")),
        "the scan did not reach python/src"
    );
    let mut long = Vec::new();
    for f in files.iter().filter(|f| !is_test_file(f)) {
        let text = std::fs::read_to_string(f).unwrap();
        for (line, name, len) in long_functions(&text, MAX_FUNCTION_LINES) {
            long.push(format!("{}:{line}: fn {name} is {len} lines", f.display()));
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines:\n{}",
        long.join("\n")
    );
}

/// Whether `text`'s code (comments left out) names the command line's module: `crate::cli`
/// or `pgt::cli`, as a path of its own (`pgt::client` is not it).
fn names_the_cli(text: &str) -> bool {
    let code = strip_comments(text);
    ["crate::cli", "pgt::cli"].iter().any(|needle| {
        code.match_indices(needle).any(|(i, _)| {
            let before = code[..i].chars().next_back();
            let after = code[i + needle.len()..].chars().next();
            !before.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_')
                && !after.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_')
        })
    })
}

/// The files under `src` (but `src/cli/` and `src/main.rs`) and `python_src` that name the
/// command line's module.
fn files_naming_the_cli(src: &Path, python_src: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    rust_files(python_src, &mut files);
    files
        .into_iter()
        .filter(|f| !(f.starts_with(src.join("cli")) || *f == src.join("main.rs")))
        .filter(|f| names_the_cli(&std::fs::read_to_string(f).unwrap()))
        .collect()
}

#[test]
fn only_the_binary_uses_the_command_line() {
    let found = files_naming_the_cli(&src_dir(), &python_src_dir());
    assert!(
        found.is_empty(),
        "files outside src/cli/ and src/main.rs that use the command line's module (move what they use into the library):\n{}",
        found
            .iter()
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>()
            .join("\n")
    );
    let lib = std::fs::read_to_string(src_dir().join("lib.rs")).unwrap();
    assert!(
        !strip_comments(&lib).contains("mod cli"),
        "src/lib.rs declares the cli module; it belongs to the binary (src/main.rs)"
    );
}

#[test]
fn the_cli_scan_finds_a_use_of_the_cli() {
    // A scratch tree: a library file and a Python file that use the CLI, one that only
    // mentions it in a comment or names a look-alike, and the CLI's own files.
    let root = std::env::temp_dir().join(format!("pgt-arch-cli-{}", std::process::id()));
    let (src, py) = (root.join("src"), root.join("python/src"));
    std::fs::create_dir_all(src.join("cli")).unwrap();
    std::fs::create_dir_all(&py).unwrap();
    std::fs::write(src.join("lib.rs"), "pub mod a;\n").unwrap();
    std::fs::write(src.join("a.rs"), "use crate::cli::render::f;\n").unwrap();
    std::fs::write(
        src.join("b.rs"),
        "// crate::cli in a comment\nuse crate::client::X;\n",
    )
    .unwrap();
    std::fs::write(src.join("main.rs"), "mod cli;\nuse crate::cli::run;\n").unwrap();
    std::fs::write(src.join("cli/mod.rs"), "use crate::cli::x;\n").unwrap();
    std::fs::write(py.join("p.rs"), "let m = pgt::cli::error_message(&e);\n").unwrap();
    let found = files_naming_the_cli(&src, &py);
    std::fs::remove_dir_all(&root).unwrap();
    let names: Vec<String> = found
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["a.rs".to_string(), "p.rs".to_string()]);
}

#[test]
fn the_cycle_scan_finds_a_cycle() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.entry("a".into()).or_default().insert("b".into());
    g.entry("b".into()).or_default().insert("c".into());
    g.entry("c".into()).or_default().insert("a".into());
    g.entry("d".into()).or_default().insert("a".into());
    let cycle = find_cycle(&g).expect("a → b → c → a");
    assert_eq!(cycle.first(), cycle.last());
    assert_eq!(cycle.len(), 4);
    g.get_mut("c").unwrap().clear();
    assert_eq!(find_cycle(&g), None);
}

#[test]
fn the_path_scan_ignores_comments_and_reads_uses() {
    let text = "use crate::scene::Scene; // crate::report\n/// see crate::metrics\nlet x = crate::optics::f();";
    let found = crate_paths(text);
    assert_eq!(
        found,
        ["optics", "scene"].iter().map(|s| s.to_string()).collect()
    );
}

#[test]
fn the_length_scan_measures_functions_and_skips_tests() {
    let mut text =
        String::from("pub fn short() {\n    1;\n}\n\nfn long(\n    a: u32,\n) -> u32 {\n");
    for _ in 0..130 {
        text.push_str("    let _ = a;\n");
    }
    text.push_str("    a\n}\n\n#[cfg(test)]\nmod tests {\n    fn long_test() {\n");
    for _ in 0..200 {
        text.push_str("        let _ = 1;\n");
    }
    text.push_str("    }\n}\n");
    let found = long_functions(&text, 120);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].1, "long");
    assert_eq!(found[0].2, 135);
    assert_eq!(found[0].0, 5);
}

/// The repository's root.
fn root_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The headings of a Markdown file, as written (without the `#`s).
fn headings(markdown: &str) -> Vec<String> {
    let mut in_code = false;
    let mut out = Vec::new();
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        } else if !in_code && line.starts_with('#') {
            out.push(line.trim_start_matches('#').trim().to_string());
        }
    }
    out
}

/// GitHub's anchor of a heading: lower case, spaces to hyphens, other punctuation dropped.
fn anchor(heading: &str) -> String {
    heading
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// Every `§N` citation of `text` that refers to docs/design.md, with its line: all of them
/// but those of outside documents (a paper's or a standard's sections, named just before).
fn design_citations(text: &str) -> Vec<(usize, u32)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        for (i, _) in line.match_indices('§') {
            let before = &line[..i];
            // The last 40 bytes, moved forward to a character boundary.
            let mut start = before.len().saturating_sub(40);
            while !before.is_char_boundary(start) {
                start += 1;
            }
            let window = &before[start..];
            if window.contains("paper") || window.contains("14772") || window.contains("thesis §")
            {
                continue;
            }
            let digits: String = line[i + '§'.len_utf8()..]
                .chars()
                .take_while(char::is_ascii_digit)
                .collect();
            if let Ok(section) = digits.parse() {
                out.push((n + 1, section));
            }
        }
    }
    out
}

/// `docs/NAME.md` paths named in `text`, each with the heading quoted right after it
/// (`docs/performance.md, "Exponentials"`), if any.
fn docs_mentions(text: &str) -> Vec<(usize, String, Option<String>)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(i) = rest.find("docs/") {
            let after = &rest[i..];
            let end = after
                .find(|c: char| !(c.is_ascii_alphanumeric() || "/-_.".contains(c)))
                .unwrap_or(after.len());
            let path = after[..end].trim_end_matches('.');
            if path.ends_with(".md") {
                let quoted = after[path.len()..]
                    .strip_prefix(", \"")
                    .and_then(|q| q.split('"').next())
                    .map(str::to_string);
                out.push((n + 1, path.to_string(), quoted));
            }
            rest = &after[end.max(1)..];
        }
    }
    out
}

#[test]
fn every_citation_in_the_code_resolves_in_the_docs() {
    let root = root_dir();
    let design = std::fs::read_to_string(root.join("docs/design.md")).expect("docs/design.md");
    let sections: BTreeSet<u32> = headings(&design)
        .iter()
        .filter_map(|h| h.split('.').next()?.parse().ok())
        .collect();
    let mut files = Vec::new();
    rust_files(&src_dir(), &mut files);
    let mut bad = Vec::new();
    let mut cited = 0;
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (line, section) in design_citations(&text) {
            cited += 1;
            if !sections.contains(&section) {
                bad.push(format!(
                    "{}:{line}: §{section} is no section of docs/design.md",
                    f.display()
                ));
            }
        }
        for (line, path, quoted) in docs_mentions(&text) {
            match std::fs::read_to_string(root.join(&path)) {
                Err(_) => bad.push(format!("{}:{line}: {path} does not exist", f.display())),
                Ok(doc) => {
                    if let Some(q) = quoted {
                        if !headings(&doc).iter().any(|h| h == &q) {
                            bad.push(format!(
                                "{}:{line}: {path} has no heading \"{q}\"",
                                f.display()
                            ));
                        }
                    }
                }
            }
        }
    }
    assert!(cited > 100, "the scan found only {cited} citations");
    assert!(
        bad.is_empty(),
        "citations that do not resolve:\n{}",
        bad.join("\n")
    );
}

/// The relative links of a Markdown file that do not resolve, as messages.
fn broken_links(file: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let dir = file.parent().unwrap();
    let mut bad = Vec::new();
    let mut in_code = false;
    for (n, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        for (i, _) in line.match_indices("](") {
            let target = &line[i + 2..];
            let Some(end) = target.find(')') else {
                continue;
            };
            let target = target[..end].trim();
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, fragment) = match target.split_once('#') {
                Some((p, f)) => (p, Some(f)),
                None => (target, None),
            };
            let linked = if path.is_empty() {
                file.to_path_buf()
            } else {
                dir.join(path)
            };
            let here = format!("{}:{}: ({target})", file.display(), n + 1);
            if !linked.exists() {
                bad.push(format!("{here}: no such file"));
                continue;
            }
            if let (Some(fragment), true) =
                (fragment, linked.extension().is_some_and(|e| e == "md"))
            {
                let doc = std::fs::read_to_string(&linked).unwrap();
                if !headings(&doc).iter().any(|h| anchor(h) == fragment) {
                    bad.push(format!("{here}: no heading with the anchor #{fragment}"));
                }
            }
        }
    }
    bad
}

#[test]
fn every_relative_link_of_the_docs_resolves() {
    let root = root_dir();
    let mut files = vec![root.join("README.md")];
    for dir in ["docs", "reports/examples", "contrib/slurm", "contrib/k8s"] {
        for e in std::fs::read_dir(root.join(dir)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|e| e == "md") {
                files.push(p);
            }
        }
    }
    assert!(files.len() >= 8, "{files:?}");
    let bad: Vec<String> = files.iter().flat_map(|f| broken_links(f)).collect();
    assert!(
        bad.is_empty(),
        "links that do not resolve:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_docs_scans_find_what_they_should() {
    // Citations: design sections, not a paper's or a standard's.
    let text = "/// docs/design.md §2, and §8\n/// (paper §3.1) ISO/IEC 14772-1 §5.1\n";
    assert_eq!(design_citations(text), vec![(1, 2), (1, 8)]);
    // A window of 40 bytes that would start inside a character moves to the next one.
    assert_eq!(
        design_citations("//! ··········· (docs/design.md §2)"),
        vec![(1, 2)]
    );
    assert_eq!(
        docs_mentions("see docs/performance.md, \"Exponentials\"; docs/cli.md."),
        vec![
            (1, "docs/performance.md".into(), Some("Exponentials".into())),
            (1, "docs/cli.md".into(), None)
        ]
    );
    assert_eq!(
        anchor("5. Comparison and reports"),
        "5-comparison-and-reports"
    );
    assert_eq!(anchor("`pgt render`"), "pgt-render");
    // A broken link and a broken fragment are found, a good one is not.
    let dir = std::env::temp_dir().join(format!("pgt-links-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("b.md"), "# Title here\n").unwrap();
    let a = dir.join("a.md");
    std::fs::write(
        &a,
        "[ok](b.md#title-here) [gone](c.md) [bad](b.md#nope)\n```\n[code](x.md)\n```\n",
    )
    .unwrap();
    let bad = broken_links(&a);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(bad.len(), 2, "{bad:?}");
    assert!(
        bad[0].contains("c.md") && bad[1].contains("#nope"),
        "{bad:?}"
    );
}

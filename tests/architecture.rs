//! The architecture rules of STYLE.md, checked on the source text so that they cannot erode
//! unnoticed:
//!
//! * data flows one way: the `use crate::X` graph between the top-level modules of `src/` has no
//!   cycle (a module may use itself, `error` and the leaf helpers freely);
//! * no function outside tests is longer than [`MAX_FUNCTION_LINES`] lines.
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

#[test]
fn no_function_is_longer_than_the_limit() {
    let mut files = Vec::new();
    rust_files(&src_dir(), &mut files);
    let mut long = Vec::new();
    for f in &files {
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

//! One definition of the CPU–GPU contract (docs/design.md §4, STYLE.md "one side generates the
//! other"): the constants, structs and bindings are generated from `src/approx/contract.rs` and
//! `src/approx/layout.rs`; no file under `shaders/` may declare them again or write their
//! numbers. No GPU needed.

use pgt::approx::contract::{self, BINDINGS};
use pgt::approx::wgsl::{self, WgslConst};
use std::path::{Path, PathBuf};

fn wgsl_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            wgsl_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "wgsl") {
            out.push(path);
        }
    }
}

/// The code of a WGSL text without `//` comments (comments may explain the numbers).
fn code(text: &str) -> String {
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Spellings of a contract number that must not appear as a token in a shader.
fn spellings(c: &WgslConst) -> Vec<String> {
    match *c {
        // 0 and 1 are everywhere (loop starts, flags); their names are checked instead.
        WgslConst::U32(_, v) if v < 2 => vec![],
        WgslConst::U32(_, v) => vec![
            format!("{v}"),
            format!("{v}u"),
            format!("{v}i"),
            format!("0x{v:x}"),
            format!("0x{v:x}u"),
        ],
        WgslConst::F32("T_FAR", _) => vec!["3e38".into(), "3.0e38".into(), "3.0e+38".into()],
        WgslConst::F32("PI", _) => vec!["3.14159".into()],
        WgslConst::F32(..) => vec![],
    }
}

/// Every place in `text` that repeats part of the contract.
fn repetitions(text: &str) -> Vec<String> {
    let code = code(text);
    let mut found = Vec::new();
    let tokens: Vec<String> = code
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '_'))
        .filter(|t| !t.is_empty())
        .map(|t| t.to_ascii_lowercase())
        .collect();
    for c in wgsl::constants() {
        if code.contains(&format!("const {}", c.name())) {
            found.push(format!("declares const {}", c.name()));
        }
        for s in spellings(&c) {
            if tokens
                .iter()
                .any(|t| *t == s || (s == "3.14159" && t.starts_with(&s)))
            {
                found.push(format!("writes {} as {s}", c.name()));
            }
        }
    }
    for name in [
        "Particle",
        "Ellipsoid",
        "BvhNode",
        "Light",
        "Frame",
        "Stats",
        "Splat",
    ] {
        if code.contains(&format!("struct {name} ")) || code.contains(&format!("struct {name}{{")) {
            found.push(format!("declares struct {name}"));
        }
    }
    for b in BINDINGS {
        if code.contains(&format!("> {}:", b.name)) {
            found.push(format!("declares binding {}", b.name));
        }
    }
    for attr in ["@binding(", "@group(", "@workgroup_size("] {
        for (i, _) in code.match_indices(attr) {
            if code[i + attr.len()..].starts_with(|c: char| c.is_ascii_digit()) {
                found.push(format!("writes a number in {attr}"));
            }
        }
    }
    found
}

#[test]
fn no_shader_repeats_what_rust_defines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
    let mut files = Vec::new();
    wgsl_files(&root, &mut files);
    assert!(files.len() >= 6, "shaders found: {files:?}");
    for f in files {
        let text = std::fs::read_to_string(&f).unwrap();
        let found = repetitions(&text);
        assert!(found.is_empty(), "{}: {found:?}", f.display());
    }
}

#[test]
fn the_check_finds_hand_copies() {
    // The hand-written prelude of before: every one of these must be caught.
    let old = "const MAX_HITS: u32 = 128u;\n\
               var<private> stack: array<u32, 64u>;\n\
               struct Frame {\n  width: u32,\n}\n\
               @group(0) @binding(5) var<storage, read_write> output: array<vec4<f32>>;\n\
               @compute @workgroup_size(8, 8, 1)\n\
               fn f() { let far = 3.0e38; let pi = 3.14159265358979; let skip = 0xffffffffu; if (n > 65535u) {} }\n";
    let found = repetitions(old);
    for expected in [
        "declares const MAX_HITS",
        "writes MAX_HITS as 128u",
        "writes STACK_SIZE as 64u",
        "declares struct Frame",
        "declares binding output",
        "writes a number in @binding(",
        "writes a number in @workgroup_size(",
        "writes T_FAR as 3.0e38",
        "writes PI as 3.14159",
        "writes NO_PARTICLE as 0xffffffffu",
        "writes LOOP_LIMIT as 65535u",
    ] {
        assert!(
            found.iter().any(|f| f == expected),
            "{expected} not in {found:?}"
        );
    }
    // Comments may name the numbers.
    assert!(repetitions("// MAX_HITS is 128\n").is_empty());
}

#[test]
fn the_generated_prelude_carries_the_rust_values() {
    let text = wgsl::wgsl_declarations();
    assert!(text.contains(&format!("const MAX_HITS: u32 = {}u;", contract::MAX_HITS)));
    assert!(text.contains(&format!(
        "@group(0) @binding({}) var<storage, read_write> stats: Stats;",
        contract::BINDING_STATS
    )));
    assert!(text.contains("    params: array<vec4<u32>, 2>,"), "{text}");
    assert!(text.contains("    hit_overflows: atomic<u32>,"), "{text}");
}

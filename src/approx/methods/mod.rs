//! The approximation methods pgt ships (docs/design.md §4): the [`ApproxMethod`] trait and the
//! registry [`METHODS`]. Each method is one Rust file here (its docs, parameters and scene
//! check) and one WGSL file in `shaders/` that defines `shade` on top of the prelude. Adding a
//! method is those two files and one line in the `registry!` list below; the CLI
//! (`pgt approx --method`, `--list-methods`), the sweep and the README's table read the
//! registry (a test checks the README against [`markdown_table`]).
//!
//! User shaders (`pgt approx --shader FILE.wgsl`, docs/user-shaders.md) are not registered:
//! they are [`super::Method::User`].

use super::param_spec::ParamSpec;
use crate::error::Result;
use crate::scene::{RenderMode, Scene};
use std::fmt::Write as _;

/// An approximation method: a WGSL `shade` function and what it needs.
pub trait ApproxMethod: Sync {
    /// The name on the command line and in sweeps (`--method NAME`).
    fn name(&self) -> &'static str;
    /// One line: what it computes.
    fn summary(&self) -> &'static str;
    /// The WGSL file's path in the repository, for messages (`shaders/NAME.wgsl`).
    fn wgsl_path(&self) -> &'static str;
    /// The WGSL source defining `fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32>`.
    fn wgsl(&self) -> &'static str;
    /// Its parameters, in slot order (the WGSL reads them as `method_param(PARAM_<NAME>)`).
    fn params(&self) -> &'static [ParamSpec] {
        &[]
    }
    /// Refuses scenes the method has no meaning for, with a message that says what to do.
    fn check_scene(&self, _scene: &Scene) -> Result<()> {
        Ok(())
    }
}

/// Declares the method modules and the registry from one list: one line per method.
macro_rules! registry {
    ($($module:ident :: $method:ident,)*) => {
        $(pub mod $module;)*

        /// Every built-in method, in the order `--list-methods` shows them.
        pub static METHODS: &[&dyn ApproxMethod] = &[$(&$module::$method,)*];
    };
}

registry! {
    emission::Emission,
    opaque::Opaque,
    thesis::Thesis,
    sorted_blend::SortedBlend,
}

/// The registered method called `name`.
pub fn find_method(name: &str) -> Option<&'static dyn ApproxMethod> {
    METHODS.iter().copied().find(|m| m.name() == name)
}

/// The registered names, in registry order.
pub fn names() -> Vec<&'static str> {
    METHODS.iter().map(|m| m.name()).collect()
}

/// The method a scene gets when none is named: `opaque` for opaque mode, `thesis` otherwise.
pub fn default_for(scene: &Scene) -> &'static dyn ApproxMethod {
    let name = match scene.render.mode {
        RenderMode::Opaque => "opaque",
        RenderMode::Volume => "thesis",
    };
    find_method(name).unwrap_or(METHODS[0])
}

/// A method's parameters as a Markdown table (the docstring table of its file is this).
pub fn param_table(params: &[ParamSpec]) -> String {
    let mut out = String::from("| parameter | default | range | meaning |\n|---|---|---|---|\n");
    for p in params {
        let _ = writeln!(
            out,
            "| `{}` | {} | {} | {} |",
            p.name,
            p.show(p.default),
            p.range(),
            p.doc
        );
    }
    out
}

/// The registry as a Markdown table: what `pgt approx --list-methods` prints and the README
/// shows.
pub fn markdown_table() -> String {
    let mut out = String::from("| method | parameters | what it computes |\n|---|---|---|\n");
    for m in METHODS {
        let params: Vec<String> = m
            .params()
            .iter()
            .map(|p| format!("`{}` ({})", p.name, p.show(p.default)))
            .collect();
        let params = if params.is_empty() {
            "—".to_string()
        } else {
            params.join(", ")
        };
        let _ = writeln!(out, "| `{}` | {params} | {} |", m.name(), m.summary());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_found() {
        let names = names();
        for (i, n) in names.iter().enumerate() {
            assert!(!names[i + 1..].contains(n), "{n} twice");
            assert_eq!(find_method(n).map(|m| m.name()), Some(*n));
        }
        assert!(find_method("no-such-method").is_none());
    }

    #[test]
    fn defaults_are_in_range() {
        for m in METHODS {
            for p in m.params() {
                assert!(
                    p.min <= p.default && p.default <= p.max,
                    "{}.{}",
                    m.name(),
                    p.name
                );
            }
            assert!(m.params().len() <= crate::approx::contract::PARAM_SLOTS);
        }
    }

    /// Each method file opens with its parameter table (Mitsuba style): it must be the one the
    /// registry generates, so the docs cannot drift from the code.
    #[test]
    fn each_method_file_documents_its_parameters() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/approx/methods");
        for m in METHODS {
            let path = dir.join(format!("{}.rs", m.name().replace('-', "_")));
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let doc: String = text
                .lines()
                .take_while(|l| l.starts_with("//!"))
                .map(|l| format!("{}\n", l.trim_start_matches("//!").trim_start()))
                .collect();
            let table = if m.params().is_empty() {
                "Parameters: none.\n".to_string()
            } else {
                param_table(m.params())
            };
            assert!(
                doc.contains(&table),
                "{} must document its parameters with this table:\n{table}",
                path.display()
            );
        }
    }

    /// The README's methods table is the registry's.
    #[test]
    fn the_readme_lists_the_registry() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("README.md: {e}"));
        let begin = "<!-- methods: generated by `pgt approx --list-methods` -->\n";
        let start = text.find(begin).expect("README.md has the methods marker") + begin.len();
        let end = start + text[start..].find("<!-- /methods -->").expect("end marker");
        assert_eq!(
            &text[start..end],
            markdown_table(),
            "README.md's methods table differs from the registry: paste `pgt approx --list-methods`"
        );
    }
}

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
use super::shader::WgslModule;
use crate::error::{PgtError, Result};
use crate::scene::{Model, RenderMode, Scene};
use std::fmt::Write as _;

/// What a method computes (docs/design.md §2), as each method declares it.
///
/// The rule, the same for every method: a scene outside what its method computes is refused
/// by name (exit 2), before any GPU work, with the flag that makes the choice explicit. A
/// method never computes something else silently, and never with only a warning: a warning
/// scrolls past in a script or a sweep, while the image it leaves behind is compared with the
/// scene's reference and scores as if the method were poor at the scene's model. Where the
/// substitution is what the user wants (what a rasteriser's emission-only blending gives on a
/// lit molecule), `--model emission` says so, and the image is then exactly what its name says.
#[derive(Debug, Clone, Copy)]
pub enum Computes {
    /// Opaque mode: solid spheres (the optical model plays no part, as in the reference).
    Opaque,
    /// Volume mode with these optical models.
    Volume(&'static [Model]),
}

impl Computes {
    /// Whether a scene of this mode and model is what the method computes.
    pub fn covers(self, mode: RenderMode, model: Model) -> bool {
        match self {
            Computes::Opaque => mode == RenderMode::Opaque,
            Computes::Volume(models) => mode == RenderMode::Volume && models.contains(&model),
        }
    }
}

/// What a method needs made on the CPU before its dispatch (the default: nothing).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Preparation {
    /// The Gaussian particles' shapes widened to this many standard deviations, both in the
    /// BVH and in the shapes the shader intersects (`gauss-ray`: its 3-σ ellipsoids).
    pub traced_sigmas: Option<f64>,
    /// The splat lists (`approx::splat_tiles`): each Gaussian projected to the image and
    /// binned into tiles, in `splats` and `tile_entries`.
    pub splat_tiles: bool,
}

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
    /// The render mode and optical models it computes (see [`Computes`] for the rule).
    fn computes(&self) -> Computes;
    /// Whether it draws particles of Gaussian density (docs/design.md §9): such a method is
    /// given only Gaussian scenes, the others only constant-density ones.
    fn draws_gaussians(&self) -> bool {
        false
    }
    /// The shared WGSL modules its file uses, included before it.
    fn modules(&self) -> &'static [WgslModule] {
        &[]
    }
    /// What it needs made on the CPU before the dispatch ([`Preparation`]).
    fn preparation(&self) -> Preparation {
        Preparation::default()
    }
    /// Refuses scenes the method does not compute ([`check_computes`], [`check_profile`]) or has
    /// no meaning for, with a message that says what to do.
    fn check_scene(&self, scene: &Scene) -> Result<()> {
        check_computes(self.name(), self.computes(), scene)?;
        if self.draws_gaussians() {
            check_gaussians_only(self.name(), scene)
        } else {
            check_profile(self.name(), false, scene)
        }
    }
}

/// The refusal of Gaussian particles by a method that draws constant density only (it would
/// draw each Gaussian as its solid 1-σ ellipsoid), naming the methods that draw them.
pub fn check_profile(name: &str, draws_gaussians: bool, scene: &Scene) -> Result<()> {
    if draws_gaussians || !scene.has_gaussians() {
        return Ok(());
    }
    let others: Vec<&str> = METHODS
        .iter()
        .filter(|m| m.draws_gaussians())
        .map(|m| m.name())
        .collect();
    let instead = if others.is_empty() {
        "no built-in method draws them yet".to_string()
    } else {
        format!("use a method that draws them: {}", others.join(", "))
    };
    Err(PgtError::Usage(format!(
        "the {name} method draws particles of constant density; this scene has Gaussian particles (density = \"gaussian\", docs/design.md §9): {instead}, or give them constant density (--density constant for a bare particle file; density = \"constant\" in a scene's [defaults] or include)"
    )))
}

/// The refusal of constant-density particles by a method that draws Gaussians only (the
/// splatting and Gaussian ray-tracing methods: a constant-density particle has no splat),
/// naming the methods that draw them.
pub fn check_gaussians_only(name: &str, scene: &Scene) -> Result<()> {
    let constant = scene
        .particles
        .iter()
        .filter(|p| p.profile == crate::scene::Profile::Constant)
        .count();
    if constant == 0 {
        return Ok(());
    }
    let others: Vec<&str> = METHODS
        .iter()
        .filter(|m| {
            !m.draws_gaussians() && m.computes().covers(scene.render.mode, scene.render.model)
        })
        .map(|m| m.name())
        .collect();
    Err(PgtError::Usage(format!(
        "the {name} method draws particles of Gaussian density only (docs/design.md §9); this scene has {constant} particles of constant density: give them Gaussian density (--density gaussian for a bare particle file; density = \"gaussian\" in a scene's [defaults] or include), or use a method that draws constant density{}",
        if others.is_empty() {
            String::new()
        } else {
            format!(" ({})", others.join(", "))
        }
    )))
}

/// The refusal of [`Computes`]: the method `name`, computing `computes`, on `scene`. The
/// message names the method, the scene's mode or model, and the flag or the methods that fit.
pub fn check_computes(name: &str, computes: Computes, scene: &Scene) -> Result<()> {
    let (mode, model) = (scene.render.mode, scene.render.model);
    if computes.covers(mode, model) {
        return Ok(());
    }
    let message = match (computes, mode) {
        (Computes::Volume(_), RenderMode::Opaque) => format!(
            "the {name} method renders gas (volume mode); this scene is in opaque mode: use --method opaque or --mode volume"
        ),
        (Computes::Opaque, _) => format!(
            "the {name} method draws solid spheres (opaque mode); this scene is in volume mode: use --mode opaque to draw it solid, or a volume method ({})",
            methods_for(|c| matches!(c, Computes::Volume(_))).join(", ")
        ),
        (Computes::Volume(models), RenderMode::Volume) => {
            let implemented: Vec<&str> = models.iter().map(|m| m.name()).collect();
            // The last is the fullest (the registry lists emission, lit, …).
            let nearest = implemented.last().copied().unwrap_or("emission");
            let others = methods_for(|c| c.covers(RenderMode::Volume, model));
            let instead = if others.is_empty() {
                format!(
                    "; no built-in method implements {} (a user shader can: --shader FILE.wgsl)",
                    model.name()
                )
            } else {
                format!(
                    ", or use a method that implements {}: {}",
                    model.name(),
                    others.join(", ")
                )
            };
            format!(
                "the {name} method implements the {} model{}, not {}, this scene's model: pass --model {nearest} to approximate it with the {nearest} model{instead}",
                implemented.join(" and "),
                if implemented.len() == 1 { "" } else { "s" },
                model.name(),
            )
        }
    };
    Err(PgtError::Usage(message))
}

/// The registered methods whose [`Computes`] satisfies `keep`, by name.
fn methods_for(keep: impl Fn(Computes) -> bool) -> Vec<&'static str> {
    METHODS
        .iter()
        .filter(|m| keep(m.computes()))
        .map(|m| m.name())
        .collect()
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
    ever::Ever,
    splat::Splat,
    splat_pixel_sort::SplatPixelSort,
    gauss_ray::GaussRay,
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

    /// Every method on every mode and model: what it declares runs, anything else is refused
    /// by name (the method, and the scene's mode or model).
    #[test]
    fn a_scene_outside_what_a_method_computes_is_refused_by_name() {
        let text = "[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";
        let mut refused = 0;
        for mode in [RenderMode::Opaque, RenderMode::Volume] {
            for &model in crate::optics::models::ALL {
                let options = crate::scene::SceneLoadOptions {
                    mode: Some(mode),
                    model: Some(model),
                    ..Default::default()
                };
                let scene =
                    Scene::from_toml_str(text, std::path::Path::new("s.toml"), &options).unwrap();
                // The methods that draw Gaussians get the same particle of Gaussian density.
                let mut gaussian = scene.clone();
                gaussian.particles[0].profile = crate::scene::Profile::Gaussian;
                for m in METHODS {
                    let scene = if m.draws_gaussians() {
                        &gaussian
                    } else {
                        &scene
                    };
                    let r = m.check_scene(scene);
                    if m.computes().covers(mode, model) {
                        assert!(
                            r.is_ok(),
                            "{} on {mode:?} {}: {r:?}",
                            m.name(),
                            model.name()
                        );
                        continue;
                    }
                    refused += 1;
                    let e = r.expect_err("refused").to_string();
                    assert!(e.contains(&format!("the {} method", m.name())), "{e}");
                    let named = match (m.computes(), mode) {
                        (Computes::Volume(_), RenderMode::Volume) => model.name(),
                        (_, RenderMode::Opaque) => "opaque mode",
                        (_, RenderMode::Volume) => "volume mode",
                    };
                    assert!(e.contains(named), "{e}");
                }
            }
        }
        // The lit model is not the emission methods' (sorted-blend with --model lit must not
        // give the emission image without a word).
        assert!(refused >= 2 * crate::optics::models::ALL.len());
        let lit = Computes::Volume(&[crate::optics::models::EMISSION]);
        assert!(!lit.covers(RenderMode::Volume, crate::optics::models::LIT));
        for name in ["emission", "sorted-blend"] {
            let m = find_method(name).unwrap();
            assert!(!m
                .computes()
                .covers(RenderMode::Volume, crate::optics::models::LIT));
        }
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

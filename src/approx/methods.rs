//! The approximation methods pgt ships (DESIGN.md §4), each a WGSL file in `shaders/` that
//! defines `shade` on top of the prelude, and their parameters.
//!
//! | method     | file                   | parameters            | scenes              |
//! |------------|------------------------|-----------------------|---------------------|
//! | `emission` | `shaders/emission.wgsl`| —                     | volume (any model: the emission model is used) |
//! | `opaque`   | `shaders/opaque.wgsl`  | — (scene's ambient)   | any (every particle drawn opaque) |
//! | `thesis`   | `shaders/thesis.wgsl`  | `samples`, `n_exact`  | volume, `emission` or `lit` model |
//! | user       | `--shader FILE.wgsl`   | all of the above are visible in `frame` | any |

use super::shader::{ShaderPart, ShaderProgram};
use crate::error::{PgtError, Result};
use crate::scene::{OpticalModel, RenderMode, Scene};
use std::borrow::Cow;
use std::path::PathBuf;

pub const EMISSION_WGSL: &str = include_str!("../../shaders/emission.wgsl");
pub const OPAQUE_WGSL: &str = include_str!("../../shaders/opaque.wgsl");
pub const THESIS_WGSL: &str = include_str!("../../shaders/thesis.wgsl");

/// Which approximation runs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Method {
    /// Per-particle compositing with the emission model's closed form (exact without overlaps).
    Emission,
    /// First hit, Lambert + Blinn–Phong, hard shadows (the reference's opaque mode in f32).
    Opaque,
    /// The thesis's scheme, DESIGN.md §4.
    Thesis,
    /// A user's WGSL file defining `shade` (docs/user-shaders.md).
    User(PathBuf),
}

impl Method {
    /// The method a scene gets when none is named: `opaque` for opaque mode, `thesis` otherwise.
    pub fn default_for(scene: &Scene) -> Method {
        match scene.render.mode {
            RenderMode::Opaque => Method::Opaque,
            RenderMode::Volume => Method::Thesis,
        }
    }

    /// A short name for summaries.
    pub fn name(&self) -> String {
        match self {
            Method::Emission => "emission".into(),
            Method::Opaque => "opaque".into(),
            Method::Thesis => "thesis".into(),
            Method::User(p) => format!("user shader {}", p.display()),
        }
    }

    /// Refuses combinations that have no meaning, with a message that says what to do.
    pub fn check_scene(&self, scene: &Scene) -> Result<()> {
        match self {
            Method::Thesis if scene.render.mode == RenderMode::Opaque => Err(PgtError::Usage(
                "the thesis method renders gas (volume mode); this scene is in opaque mode: use --method opaque or --mode volume".into(),
            )),
            Method::Thesis if scene.render.model == OpticalModel::SingleScatter => Err(PgtError::Usage(
                "the thesis method implements the emission and lit models; this scene uses single-scatter: use --model lit or a user shader".into(),
            )),
            Method::Emission if scene.render.mode == RenderMode::Opaque => Err(PgtError::Usage(
                "the emission method renders gas (volume mode); this scene is in opaque mode: use --method opaque or --mode volume".into(),
            )),
            _ => Ok(()),
        }
    }

    /// The complete program: prelude, the method's file, the entry point.
    pub fn program(&self) -> Result<ShaderProgram> {
        let builtin = |name: &str, text: &'static str| ShaderPart {
            name: format!("shaders/{name}.wgsl"),
            text: Cow::Borrowed(text),
        };
        let part = match self {
            Method::Emission => builtin("emission", EMISSION_WGSL),
            Method::Opaque => builtin("opaque", OPAQUE_WGSL),
            Method::Thesis => builtin("thesis", THESIS_WGSL),
            Method::User(path) => super::user_shader::load(path)?,
        };
        Ok(ShaderProgram::with_method(part))
    }
}

/// `n_exact` meaning "every particle on the ray" (`--n-exact all`).
pub const N_EXACT_ALL: u32 = u32::MAX;

/// Everything a GPU approximation run needs besides the scene: the library interface that
/// `pgt approx` and `pgt sweep` share.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ApproxParams {
    /// `None`: [`Method::default_for`] the scene.
    pub method: Option<Method>,
    /// `thesis`: midpoint-rule samples per particle chord (≥ 1). Default 100 (thesis ch. 6).
    pub samples: u32,
    /// `thesis`: particles from the eye that use the lit model; [`N_EXACT_ALL`] for all.
    pub n_exact: u32,
    /// Case-insensitive substring of the adapter name (`--adapter`).
    pub adapter: Option<String>,
}

impl Default for ApproxParams {
    fn default() -> Self {
        ApproxParams {
            method: None,
            samples: 100,
            n_exact: N_EXACT_ALL,
            adapter: None,
        }
    }
}

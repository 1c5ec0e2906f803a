//! What every format delivers and what an `[[include]]` asks of it (docs/design.md §1, §6): the
//! [`ParticleRecord`] before defaults and validation, and the [`IncludeSpec`] with its selections.
//! They live here, not in `scene`, so that `formats` depends on nothing above it: the scene
//! reads particle files, particle files know nothing of scenes.

use glam::DVec3;
use serde::Deserialize;

/// A particle as a file format delivers it, before defaults and validation.
#[derive(Debug, Clone, PartialEq)]
pub struct ParticleRecord {
    /// Centre, in the file's units (Å for PDB/mmCIF/XYZ).
    pub center: DVec3,
    /// Radius, same units, `radius_scale` applied.
    pub radius: f64,
    /// Linear RGB, if the file gives the particle a colour of its own.
    pub color: Option<DVec3>,
    /// Θmax, if the format carries one (e.g. VRML transparency).
    pub opacity: Option<f64>,
    /// Extinction σ in 1/(the file's length unit), if the format carries one (the `sigma` column
    /// of CSV, as `pgt export` writes it): where given it is the particle's σ exactly, ahead of
    /// `opacity` and of the scene's defaults (docs/design.md §1). +∞ is a perfectly absorbing
    /// ball (Θmax = 1).
    pub sigma: Option<f64>,
    /// Where in its file the particle was defined (line, or byte offset for binary formats).
    pub location: crate::error::Location,
    /// An ellipsoid's semi-axes and orientation, where the file gives them (`radius` is then
    /// its longest semi-axis); `None`: a sphere.
    pub ellipsoid: Option<EllipsoidRecord>,
}

/// An ellipsoid as a file gives it (docs/design.md §9), checked by
/// [`check_records`](super::check_records) and resolved (the quaternion normalised) when the
/// scene is built (`scene::load`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EllipsoidRecord {
    /// Semi-axes along the body's x, y, z, in the file's length unit.
    pub semi_axes: DVec3,
    /// The orientation (w, x, y, z), body to world, not necessarily of unit length.
    pub rotation: [f64; 4],
}

impl EllipsoidRecord {
    /// What is wrong with it, naming the field (`axes`: the three semi-axes' names, `rotation`:
    /// the quaternion's), or `None`: every semi-axis finite and > 0 (not subnormal), the
    /// quaternion finite and not zero.
    pub fn problem(&self, axes: [&str; 3], rotation: &str) -> Option<String> {
        for (name, v) in axes.iter().zip(self.semi_axes.to_array()) {
            // A subnormal semi-axis has no finite reciprocal: the map to the unit sphere needs it.
            if !(v.is_finite() && v >= f64::MIN_POSITIVE) {
                return Some(format!(
                    "{name} (a semi-axis) must be finite and > 0 (and not below {:e}), got {v}",
                    f64::MIN_POSITIVE
                ));
            }
        }
        let q = self.rotation;
        if !q.iter().all(|v| v.is_finite()) || q.iter().all(|&v| v == 0.0) {
            return Some(format!(
                "{rotation} must be a finite, non-zero quaternion (w, x, y, z), got {q:?}"
            ));
        }
        None
    }
}

/// How particles read from a file are coloured (PDB/mmCIF; `uniform` applies to every format).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ColorBy {
    /// Jmol's CPK colour of the element.
    #[default]
    Element,
    /// One colour per chain, in order of first appearance.
    Chain,
    /// No colour of its own: the scene's `[defaults] color`.
    Uniform,
}

/// Which colour a 3D Gaussian splatting PLY gives its particles (docs/design.md §9).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShColor {
    /// The degree-0 term: 0.5 + C0·f_dc, clamped at 0.
    #[default]
    Dc,
    /// Every degree the file has, for the direction from the scene camera to the centre.
    View,
}

/// The SH coefficients of a file's particles where `sh = "view"` asks for the view-dependent
/// colour (docs/design.md §9, "3D Gaussian splatting PLY"): kept beside the records so that the
/// scene evaluates them for the eye of each frame ([`ShCoefficients::color`]), not once for
/// one eye when the file is read.
#[derive(Debug, Clone, PartialEq)]
pub struct ShCoefficients {
    /// Coefficients per particle and channel: 4, 9 or 16 (degree 1 to 3; degree 0 has no
    /// view-dependent part and keeps no table).
    pub per_particle: usize,
    /// RGB of each coefficient, particle after particle, in the order of the records: the DC
    /// term first, then degree 1 and up in the order of [`crate::formats::ply::view_color`].
    pub values: Vec<DVec3>,
}

impl ShCoefficients {
    /// Particle `i`'s colour seen from `eye`: the reference rasteriser's `computeColorFromSH`
    /// for the direction from the eye to `center`, clamped at 0 (the PLY reader's colour for
    /// the same eye, bit for bit).
    pub fn color(&self, i: usize, center: DVec3, eye: DVec3) -> DVec3 {
        let k = self.per_particle;
        let c = &self.values[i * k..(i + 1) * k];
        crate::formats::ply::view_color(c[0], &c[1..], center - eye).max(DVec3::ZERO)
    }

    /// The number of particles the table holds.
    pub fn len(&self) -> usize {
        self.values.len() / self.per_particle.max(1)
    }

    /// Whether the table holds no particle.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The order of the `f_rest_*` coefficients of a 3D Gaussian splatting PLY.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShOrder {
    /// The reference implementation's: every red coefficient, then green, then blue.
    #[default]
    ChannelMajor,
    /// RGB of coefficient 1, then of coefficient 2, …: EVER's training code.
    CoefficientMajor,
}

fn one() -> f64 {
    1.0
}

/// `[[include]]`: particles from a file (docs/design.md §1, §6). The path is relative to the scene
/// file. Format-specific selections are ignored by formats they do not apply to.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IncludeSpec {
    /// The particle file (already joined to the scene file's folder once validated); for a
    /// `trajectory`, its topology. Empty only where `sequence` names the files instead.
    #[serde(default)]
    pub path: std::path::PathBuf,
    /// How the particles are coloured.
    #[serde(default)]
    pub color_by: ColorBy,
    /// Factor on every radius (> 0).
    #[serde(default = "one")]
    pub radius_scale: f64,
    /// PDB/mmCIF: keep only these chains.
    pub chains: Option<Vec<String>>,
    /// PDB/mmCIF: which model (1-based); the first by default.
    pub model: Option<usize>,
    /// PDB/mmCIF: drop waters.
    #[serde(default)]
    pub skip_water: bool,
    /// PDB/mmCIF: drop hydrogens.
    #[serde(default)]
    pub skip_hydrogen: bool,
    /// Which frame (0-based) the include shows in every scene frame, for sources with frames
    /// other than PDB/mmCIF (MMPLD, XYZ, a trajectory, a sequence); the first by default.
    pub frame: Option<usize>,
    /// A DCD or XTC trajectory whose frames move the atoms of `path` (its topology: PDB, mmCIF,
    /// GRO or PSF), docs/design.md §10.
    pub trajectory: Option<std::path::PathBuf>,
    /// Numbered particle files, one frame each, instead of `path`: `"traj/frame_%04d.csv"` or
    /// `"traj/frame_*.csv"` ([`super::frames::SequencePattern`]).
    pub sequence: Option<std::path::PathBuf>,
    /// Which frames of the source the scene plays, `"A..B"` (0-based, B excluded) or `"A.."`.
    pub frames: Option<super::frames::FrameRange>,
    /// Source frames between two scene frames (≥ 1; 1 by default).
    pub frame_step: Option<usize>,
    /// 3DGS PLY: standard deviations per semi-axis (> 0); [`super::ply::DEFAULT_EXTENT`] by
    /// default. Not with `density = "gaussian"`, whose semi-axes are the standard deviations.
    pub extent: Option<f64>,
    /// The density profile of the file's particles (docs/design.md §9); `[defaults]`' by
    /// default.
    #[serde(default)]
    pub density: Option<crate::formats::Profile>,
    /// 3DGS PLY: the DC colour (default) or the view-dependent one.
    pub sh: Option<ShColor>,
    /// 3DGS PLY: the order of `f_rest_*` (channel-major by default).
    pub sh_order: Option<ShOrder>,
    /// 3DGS PLY with `sh = "view"`: the eye the reader evaluates the records' colours for;
    /// `None`: the DC colour, the coefficients kept in [`super::LoadedParticles::sh`] for the
    /// scene to evaluate per frame. Never read from the file.
    #[serde(skip)]
    pub view_from: Option<glam::DVec3>,
    /// Forces a file format whatever the extension: the name of a particle format of
    /// [`super::FORMATS`] (`"pdb"`, `"mmcif"`, `"vrml"`, `"mmpld"`, `"xyz"`, `"csv"`, `"gro"`,
    /// `"ply"`).
    #[serde(default, deserialize_with = "super::deserialize_format")]
    pub format: Option<&'static super::Format>,
}

impl IncludeSpec {
    /// The include of a bare particle file, with every option at its default.
    pub fn bare(path: &std::path::Path) -> IncludeSpec {
        IncludeSpec {
            path: path.to_path_buf(),
            color_by: ColorBy::default(),
            radius_scale: 1.0,
            chains: None,
            model: None,
            skip_water: false,
            skip_hydrogen: false,
            frame: None,
            trajectory: None,
            sequence: None,
            frames: None,
            frame_step: None,
            extent: None,
            density: None,
            sh: None,
            sh_order: None,
            view_from: None,
            format: None,
        }
    }
}

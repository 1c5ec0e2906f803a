//! Where a scene's settings were chosen (docs/design.md §6, "Bad input"): the scene file's table
//! and line, a command-line flag, or the default. The loader accepts every combination of
//! settings; a renderer that cannot draw one (Gaussian particles in the opaque mode, with the lit
//! model, …) refuses it through [`Scene::gaussians_refused`] or
//! [`Scene::mixed_density_refused`], which name the file and the lines that chose each part, as
//! a loading error names the line of a bad value.

use super::{Profile, RenderMode, RenderSettings, Scene};
use crate::error::{Location, PgtError};

/// Where one setting was chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Origin {
    /// Nowhere: the default (or a value a program set directly).
    #[default]
    Default,
    /// A key of the scene file: the table that holds it (`"render"`, `"defaults"`,
    /// `"particles"`, `"include"`), the key, and the table's line (`None` for settings a program
    /// gave as text, whose lines the user never saw).
    Key {
        table: &'static str,
        key: &'static str,
        line: Option<usize>,
    },
    /// A command-line flag (`"--mode"`; the Python keyword of the same name).
    Flag(&'static str),
}

impl Origin {
    /// The line of the scene file that chose the setting, if one did.
    pub fn line(self) -> Option<usize> {
        match self {
            Origin::Key { line, .. } => line,
            _ => None,
        }
    }
}

/// What gave a run of particles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParticleSource {
    /// `[[particles]]` tables (or particles a program gave as such).
    Inline,
    /// An `[[include]]`.
    Include,
    /// A bare particle file, the scene's only source.
    File,
}

/// A run of a scene's particles that one source gave one density.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParticleOrigin {
    pub source: ParticleSource,
    /// The line of the table that gave them; `None`: the file as a whole, or a program.
    pub line: Option<usize>,
    pub profile: Profile,
    /// Where their `density` was chosen: their own table's key, `[defaults]`, or the default.
    pub density: Origin,
}

/// Where a scene's render mode, optical model and particle densities were chosen.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Provenance {
    pub mode: Origin,
    pub model: Origin,
    /// The scene's particle sources in order (consecutive `[[particles]]` tables whose density
    /// comes from the same place are one run).
    pub particles: Vec<ParticleOrigin>,
}

impl Provenance {
    /// Adds a run, joined to the last one where both are `[[particles]]` tables with the same
    /// density from the same place (a table's own `density` key is a place of its own).
    pub fn push_particles(&mut self, run: ParticleOrigin) {
        let joins = self.particles.last().is_some_and(|last| {
            last.source == ParticleSource::Inline
                && run.source == ParticleSource::Inline
                && last.profile == run.profile
                && last.density == run.density
        });
        if !joins {
            self.particles.push(run);
        }
    }

    /// The same provenance without lines: for settings a program gave as text.
    pub fn without_lines(mut self) -> Provenance {
        fn strip(o: &mut Origin) {
            if let Origin::Key { line, .. } = o {
                *line = None;
            }
        }
        strip(&mut self.mode);
        strip(&mut self.model);
        for p in &mut self.particles {
            p.line = None;
            strip(&mut p.density);
        }
        self
    }
}

/// A setting that a renderer refuses with Gaussian particles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Setting {
    /// `[render] mode`.
    Mode,
    /// `[render] model`.
    Model,
    /// An option of the render itself, named as its flag (`"--integrator riemann"`).
    Flag(&'static str),
}

impl Scene {
    /// The refusal of this scene's Gaussian particles with `setting`, for the reason `why`: at
    /// the line of the key that chose the setting where one did, else at the table of the first
    /// Gaussian particles (else the file), naming both:
    /// `scene.toml:3: [render] at line 3 sets mode = "opaque": WHY; the Gaussians: the [[include]] at line 9 (density = "gaussian" there)`.
    pub fn gaussians_refused(&self, setting: Setting, why: &str) -> PgtError {
        let gaussians = self
            .provenance
            .particles
            .iter()
            .find(|p| p.profile == Profile::Gaussian);
        let chosen_line = match setting {
            Setting::Mode => self.provenance.mode.line(),
            Setting::Model => self.provenance.model.line(),
            Setting::Flag(_) => None,
        };
        let line = chosen_line.or(gaussians.and_then(|g| g.line));
        let chosen = describe_setting(setting, &self.provenance, &self.render);
        let gaussians =
            gaussians.map_or_else(|| "the scene's particles".to_string(), describe_particles);
        self.error_at(line, format!("{chosen}: {why}; the Gaussians: {gaussians}"))
    }

    /// The refusal of a scene whose particles mix constant and Gaussian density, for the reason
    /// `why`: at the table of the first particles whose density differs from the first
    /// particles', naming both and where each density was chosen.
    pub fn mixed_density_refused(&self, why: &str) -> PgtError {
        let runs = &self.provenance.particles;
        let (first, other) = match runs.first() {
            Some(first) => (
                Some(first),
                runs.iter().find(|r| r.profile != first.profile),
            ),
            None => (None, None),
        };
        let (Some(first), Some(other)) = (first, other) else {
            return self.error_at(
                None,
                format!("this scene mixes particles of constant and Gaussian density; {why}"),
            );
        };
        self.error_at(
            other.line,
            format!(
                "this scene mixes particles of constant and Gaussian density: {} has {} density ({}), but {} has {} density ({}); {why}",
                describe_particles_source(other),
                profile_word(other.profile),
                describe_density(other),
                describe_particles_source(first),
                profile_word(first.profile),
                describe_density(first),
            ),
        )
    }

    /// An error at `line` of the scene's file (the file as a whole without one).
    fn error_at(&self, line: Option<usize>, message: String) -> PgtError {
        PgtError::Input {
            path: self.source.clone(),
            location: line.map_or(Location::File, Location::Line),
            message,
        }
    }
}

/// "Gaussian" or "constant".
fn profile_word(p: Profile) -> &'static str {
    match p {
        Profile::Constant => "constant",
        Profile::Gaussian => "Gaussian",
    }
}

/// The name of a render mode in scene files and on the command line.
fn mode_name(mode: RenderMode) -> &'static str {
    match mode {
        RenderMode::Opaque => "opaque",
        RenderMode::Volume => "volume",
    }
}

/// `[render] at line 3 sets mode = "opaque"`, `--mode opaque`, `the lit model (the default)`.
fn describe_setting(setting: Setting, provenance: &Provenance, render: &RenderSettings) -> String {
    let defaults = RenderSettings::default();
    let (origin, key, value, is_default, what) = match setting {
        Setting::Flag(flag) => return flag.to_string(),
        Setting::Mode => (
            provenance.mode,
            "mode",
            mode_name(render.mode),
            render.mode == defaults.mode,
            "mode",
        ),
        Setting::Model => (
            provenance.model,
            "model",
            render.model.name(),
            render.model == defaults.model,
            "model",
        ),
    };
    match origin {
        Origin::Key { table, line, .. } => {
            format!("{} sets {key} = \"{value}\"", describe_table(table, line))
        }
        Origin::Flag(flag) => format!("{flag} {value}"),
        Origin::Default if is_default => {
            format!("the {value} {what} (the default: no {key} is set)")
        }
        Origin::Default => format!("the {value} {what}"),
    }
}

/// `[render] at line 3`, `[render]`.
fn describe_table(table: &str, line: Option<usize>) -> String {
    let table = match table {
        "particles" | "include" => format!("[[{table}]]"),
        t => format!("[{t}]"),
    };
    match line {
        Some(line) => format!("{table} at line {line}"),
        None => table,
    }
}

/// `the [[include]] at line 9 (density = "gaussian" there)`.
fn describe_particles(p: &ParticleOrigin) -> String {
    format!("{} ({})", describe_particles_source(p), describe_density(p))
}

/// `the [[include]] at line 9`, `the [[particles]] table at line 4`, `the particle file`.
fn describe_particles_source(p: &ParticleOrigin) -> String {
    let at = p.line.map(|l| format!(" at line {l}")).unwrap_or_default();
    match p.source {
        ParticleSource::Inline if p.line.is_none() => "the given particles".to_string(),
        ParticleSource::Inline => format!("the [[particles]] table{at}"),
        ParticleSource::Include => format!("the [[include]]{at}"),
        ParticleSource::File => "the particle file".to_string(),
    }
}

/// Where a run's density was chosen: `density = "gaussian" there`, `[defaults] at line 2 sets
/// density = "gaussian"`, `the default`.
fn describe_density(p: &ParticleOrigin) -> String {
    let value = p.profile.name();
    match p.density {
        Origin::Key {
            table: "defaults",
            line,
            ..
        } => format!(
            "{} sets density = \"{value}\"",
            describe_table("defaults", line)
        ),
        Origin::Key { .. } => format!("density = \"{value}\" there"),
        Origin::Flag(flag) => format!("{flag} {value}"),
        Origin::Default => "the default".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SceneLoadOptions;
    use std::path::Path;

    fn load(text: &str, options: &SceneLoadOptions) -> Scene {
        Scene::from_toml_str(text, Path::new("g.toml"), options).unwrap()
    }

    const GAUSSIAN_INCLUDE_FREE: &str = "[render]\nmode = \"opaque\"\nmodel = \"emission\"\n\n[defaults]\ndensity = \"gaussian\"\nopacity = 0.5\n\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";

    #[test]
    fn a_mode_key_is_named_at_its_table_with_the_gaussians() {
        let s = load(GAUSSIAN_INCLUDE_FREE, &SceneLoadOptions::default());
        let e = s.gaussians_refused(Setting::Mode, "no surface").to_string();
        assert_eq!(
            e,
            "g.toml:1: [render] at line 1 sets mode = \"opaque\": no surface; the Gaussians: the [[particles]] table at line 9 ([defaults] at line 5 sets density = \"gaussian\")"
        );
    }

    #[test]
    fn a_flag_is_named_as_given_and_the_line_is_the_gaussians() {
        let options = SceneLoadOptions {
            mode: Some(RenderMode::Opaque),
            ..SceneLoadOptions::default()
        };
        let text = "[render]\nmodel = \"emission\"\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\ndensity = \"gaussian\"\n";
        let s = load(text, &options);
        let e = s.gaussians_refused(Setting::Mode, "no surface").to_string();
        assert_eq!(
            e,
            "g.toml:3: --mode opaque: no surface; the Gaussians: the [[particles]] table at line 3 (density = \"gaussian\" there)"
        );
        let e = s
            .gaussians_refused(Setting::Flag("--integrator riemann"), "adaptive only")
            .to_string();
        assert!(
            e.starts_with("g.toml:3: --integrator riemann: adaptive only;"),
            "{e}"
        );
    }

    #[test]
    fn a_default_model_says_it_is_the_default() {
        let text = "[defaults]\ndensity = \"gaussian\"\n[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n";
        let s = load(text, &SceneLoadOptions::default());
        let e = s.gaussians_refused(Setting::Model, "why").to_string();
        assert!(
            e.starts_with("g.toml:3: the lit model (the default: no model is set): why;"),
            "{e}"
        );
        // A value a program set without a key is not called the default.
        let mut s = s;
        s.render.model = crate::optics::models::SINGLE_SCATTER;
        let e = s.gaussians_refused(Setting::Model, "why").to_string();
        assert!(
            e.starts_with("g.toml:3: the single-scatter model: why;"),
            "{e}"
        );
    }

    #[test]
    fn mixed_densities_name_both_tables() {
        let text = "[[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\n[[particles]]\ncenter = [3.0, 0.0, 0.0]\nradius = 1.0\n\n[[particles]]\ncenter = [6.0, 0.0, 0.0]\nradius = 1.0\ndensity = \"gaussian\"\n";
        let s = load(text, &SceneLoadOptions::default());
        // The two constant tables are one run.
        assert_eq!(s.provenance.particles.len(), 2);
        let e = s.mixed_density_refused("one kind").to_string();
        assert_eq!(
            e,
            "g.toml:8: this scene mixes particles of constant and Gaussian density: the [[particles]] table at line 8 has Gaussian density (density = \"gaussian\" there), but the [[particles]] table at line 1 has constant density (the default); one kind"
        );
    }

    #[test]
    fn a_scene_a_program_built_names_the_file_only() {
        let s = Scene {
            provenance: Provenance::default(),
            ..load(GAUSSIAN_INCLUDE_FREE, &SceneLoadOptions::default())
        };
        let e = s.gaussians_refused(Setting::Mode, "no surface").to_string();
        assert!(
            e.starts_with(
                "g.toml: the opaque mode: no surface; the Gaussians: the scene's particles"
            ),
            "{e}"
        );
        let e = s.mixed_density_refused("one kind").to_string();
        assert!(e.starts_with("g.toml: this scene mixes"), "{e}");
    }

    #[test]
    fn without_lines_keeps_the_keys() {
        let s = load(GAUSSIAN_INCLUDE_FREE, &SceneLoadOptions::default());
        let p = s.provenance.clone().without_lines();
        assert_eq!(
            p.mode,
            Origin::Key {
                table: "render",
                key: "mode",
                line: None
            }
        );
        assert!(p.particles.iter().all(|r| r.line.is_none()));
        let s = Scene { provenance: p, ..s };
        let e = s.gaussians_refused(Setting::Mode, "no surface").to_string();
        assert!(
            e.starts_with("g.toml: [render] sets mode = \"opaque\": no surface"),
            "{e}"
        );
    }
}

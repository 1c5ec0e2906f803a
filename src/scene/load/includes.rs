//! Step 4: the `[[include]]`s. Each include's keys that say where its files are are checked and
//! joined to the scene file's folder, its files read (docs/design.md §1, §6, §10), and its
//! records made particles. A file that cannot be read is named at the line of the key that
//! named it (`path`, `trajectory` or `sequence`), with the folder a relative path is taken from.

use super::super::file::SceneFile;
use super::super::provenance::{Origin, ParticleOrigin, ParticleSource, Provenance};
use super::defaults::ResolvedDefaults;
use super::particles::record_particle;
use super::IncludeGroup;
use crate::error::{line_of, At, PgtError, Result, SourceText};
use crate::formats::IncludeSpec;
use crate::optics::particle::Particle;
use std::path::Path;
use toml::Spanned;

/// Reads every include of `file` in order, appending its particles to `particles` (after the
/// inline ones); the groups that say where each include's particles sit, and the readers'
/// warnings.
pub(super) fn read_all(
    source: &SourceText,
    file: &SceneFile,
    defaults: &ResolvedDefaults,
    lambda: f64,
    particles: &mut Vec<Particle>,
    provenance: &mut Provenance,
) -> Result<(Vec<IncludeGroup>, Vec<String>)> {
    let base = source.path.parent().unwrap_or(Path::new("."));
    let mut includes = Vec::with_capacity(file.include.len());
    let mut warnings = Vec::new();
    for (index, inc) in file.include.iter().enumerate() {
        let spec_at = source.at(inc.span());
        let mut spec = resolve(&spec_at, base, inc.get_ref().clone())?;
        // The readers see the density the particles get (a splatting file's semi-axes are its
        // standard deviations for Gaussians).
        spec.density = Some(spec.density.unwrap_or(defaults.density));
        // With `sh = "view"` the records come with the DC colour and their coefficients, which
        // the scene evaluates for the eye of each frame once the camera is known
        // (`super::color_for_eye`).
        let mut loaded = crate::formats::load_particles(&spec)
            .map_err(|e| read_error(e, source, index, inc, &spec, base))?;
        warnings.extend(loaded.warnings);
        let start = particles.len();
        for rec in &loaded.records {
            particles.push(record_particle(
                &spec.path,
                rec,
                defaults,
                lambda,
                spec.density,
            )?);
        }
        let line = source.line(inc);
        provenance.push_particles(ParticleOrigin {
            source: ParticleSource::Include,
            line: Some(line),
            profile: spec.density.unwrap_or_default(),
            density: match inc.get_ref().density {
                Some(_) => Origin::Key {
                    table: "include",
                    key: "density",
                    line: Some(line),
                },
                None => defaults.density_origin,
            },
        });
        includes.push(IncludeGroup {
            spec,
            location: spec_at.location.clone(),
            range: start..particles.len(),
            sh: loaded.sh.take().map(std::sync::Arc::new),
        });
    }
    Ok((includes, warnings))
}

/// An `[[include]]`'s keys that say where its files are, checked and joined to the scene file's
/// folder `base` (docs/design.md §10: `path`, `trajectory`, `sequence`, `frame`, `frames`,
/// `frame_step`).
fn resolve(at: &At, base: &Path, mut spec: IncludeSpec) -> Result<IncludeSpec> {
    at.in_range(
        "include.radius_scale",
        spec.radius_scale,
        f64::MIN_POSITIVE,
        f64::MAX,
        "> 0",
    )?;
    if let Some(k) = spec.extent {
        at.in_range("include.extent", k, f64::MIN_POSITIVE, f64::MAX, "> 0")?;
    }
    let has_path = !spec.path.as_os_str().is_empty();
    match (has_path, spec.sequence.is_some(), spec.trajectory.is_some()) {
        (false, false, _) => {
            return Err(at.err(
                "include: set `path` (a particle file, or a trajectory's topology) or `sequence` (numbered files)",
            ))
        }
        (true, true, _) => {
            return Err(at.err("include: set `path` or `sequence`, not both"))
        }
        (false, true, true) => {
            return Err(at.err(
                "include.trajectory needs `path` (its topology: PDB, mmCIF, GRO or PSF), not `sequence`",
            ))
        }
        _ => {}
    }
    if spec.frame.is_some() && spec.frames.is_some() {
        return Err(at.err(
            "include: set `frame` (one frame in every scene frame) or `frames` (the frames to play), not both",
        ));
    }
    if spec.model.is_some() && spec.frames.is_some() {
        return Err(at.err(
            "include: set `model` (one model in every scene frame) or `frames` (the models to play), not both",
        ));
    }
    if spec.frame_step == Some(0) {
        return Err(at.err("include.frame_step must be ≥ 1, got 0"));
    }
    if has_path {
        spec.path = base.join(&spec.path);
    }
    spec.trajectory = spec.trajectory.map(|t| base.join(t));
    spec.sequence = spec.sequence.map(|q| base.join(q));
    Ok(spec)
}

/// An error of reading the include `inc` (the `index`-th), `spec` its resolved keys. A file that
/// cannot be read is named at its key's line (a typo in the path is the usual cause); errors
/// inside a file that was read name that file's line; errors of a frame source (a trajectory,
/// a sequence, a `frames` range) also name the include's line, since the keys that chose the
/// frames are there.
fn read_error(
    e: PgtError,
    source: &SourceText,
    index: usize,
    inc: &Spanned<IncludeSpec>,
    spec: &IncludeSpec,
    base: &Path,
) -> PgtError {
    match e {
        PgtError::Io { path, source: io } => {
            let written = inc.get_ref();
            let (key, written) = match (&spec.trajectory, &written.trajectory, &written.sequence) {
                (Some(t), Some(w), _) if *t == path => ("trajectory", w.as_path()),
                (_, _, Some(w)) => ("sequence", w.as_path()),
                _ => ("path", written.path.as_path()),
            };
            let line = key_line(source.text, index, key).unwrap_or_else(|| source.line(inc));
            let at = At {
                path: source.path,
                location: crate::error::Location::Line(line),
            };
            unreadable(&at, key, base, written, &path, &io)
        }
        e if crate::formats::frames::uses_frames(spec) => e.context(format!(
            "{}:{}: [[include]]",
            source.path.display(),
            line_of(source.text, inc.span().start)
        )),
        e => e,
    }
}

/// The line of `key` in the `index`-th `[[include]]` of the scene text, if it is there. Read
/// only for an error: the scene types keep the include's line, not each key's.
fn key_line(text: &str, index: usize, key: &str) -> Option<usize> {
    #[derive(serde::Deserialize)]
    struct Includes {
        #[serde(default)]
        include: Vec<std::collections::BTreeMap<String, Spanned<toml::Value>>>,
    }
    let includes: Includes = toml::from_str(text).ok()?;
    let value = includes.include.get(index)?.get(key)?;
    Some(line_of(text, value.span().start))
}

/// An include file that cannot be read: named at `at` (the line of `key`), with the file, the
/// cause, and, for a relative path, the folder it was taken relative to (the scene file's
/// `base`, not the working directory: the usual surprise).
fn unreadable(
    at: &At,
    key: &str,
    base: &Path,
    written: &Path,
    path: &Path,
    source: &std::io::Error,
) -> PgtError {
    let relative = if written.is_absolute() {
        String::new()
    } else {
        let folder = if base.as_os_str().is_empty() {
            "the current folder, where the scene file is".to_string()
        } else {
            format!("{}, the scene file's folder", base.display())
        };
        format!(
            " (the path `{}` is taken relative to {folder})",
            written.display()
        )
    };
    at.err(format!(
        "include.{key}: cannot read {}: {source}{relative}",
        path.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Scene, SceneLoadOptions};

    fn load_at(path: &Path, text: &str) -> Result<Scene> {
        Scene::from_toml_str(text, path, &SceneLoadOptions::default())
    }

    fn err_text(text: &str) -> String {
        load_at(Path::new("s.toml"), text).unwrap_err().to_string()
    }

    #[test]
    fn conflicting_keys_name_the_include_line() {
        for (keys, words) in [
            ("color_by = \"uniform\"", "include: set `path`"),
            (
                "path = \"a.csv\"\nsequence = \"f_%d.csv\"",
                "set `path` or `sequence`, not both",
            ),
            (
                "sequence = \"f_%d.csv\"\ntrajectory = \"t.dcd\"",
                "include.trajectory needs `path`",
            ),
            (
                "path = \"a.xyz\"\nframe = 1\nframes = \"0..\"",
                "set `frame`",
            ),
            (
                "path = \"a.pdb\"\nmodel = 1\nframes = \"0..\"",
                "set `model`",
            ),
            (
                "path = \"a.xyz\"\nframe_step = 0",
                "include.frame_step must be ≥ 1",
            ),
            (
                "path = \"a.xyz\"\nradius_scale = 0.0",
                "include.radius_scale must be > 0",
            ),
            (
                "path = \"a.ply\"\nextent = -1.0",
                "include.extent must be > 0",
            ),
        ] {
            let e = err_text(&format!("\n[[include]]\n{keys}\n"));
            assert!(
                e.starts_with("s.toml:2: ") && e.contains(words),
                "{keys}: {e}"
            );
        }
    }

    #[test]
    fn paths_are_joined_to_the_scene_files_folder() {
        let at = At::whole(Path::new("s.toml"));
        let spec: IncludeSpec =
            toml::from_str("path = \"top.gro\"\ntrajectory = \"t.xtc\"\n").unwrap();
        let spec = resolve(&at, Path::new("scenes"), spec).unwrap();
        assert_eq!(spec.path, Path::new("scenes/top.gro"));
        assert_eq!(spec.trajectory.as_deref(), Some(Path::new("scenes/t.xtc")));
    }

    #[test]
    fn an_unreadable_file_is_named_at_its_keys_line() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("s.toml");
        let gro = dir.path().join("top.gro");
        let atom = format!(
            "{:>5}{:<5}{:>5}{:>5}{:8.3}{:8.3}{:8.3}",
            1, "SOL", "OW", 1, 0.126, 1.624, 1.679
        );
        std::fs::write(
            &gro,
            format!("t\n    1\n{atom}\n   1.00000   1.00000   1.00000\n"),
        )
        .unwrap();
        // The topology is there, the trajectory is not: the `trajectory` key is named.
        let text = "[render]\nmodel = \"emission\"\n\n[[include]]\npath = \"top.gro\"\ntrajectory = \"missing.xtc\"\n";
        let e = load_at(&scene, text).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "{}:6: include.trajectory: cannot read ",
                scene.display()
            )),
            "{e}"
        );
        assert!(e.contains("missing.xtc"), "{e}");
        assert!(
            e.contains("(the path `missing.xtc` is taken relative to"),
            "{e}"
        );
        assert!(!e.contains("top.gro"), "{e}");
        // A missing particle file names the `path` key.
        let text = "[[include]]\nradius_scale = 1.0\npath = \"gone.gro\"\n";
        let e = load_at(&scene, text).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "{}:3: include.path: cannot read ",
                scene.display()
            )) && e.contains("`gone.gro` is taken relative to"),
            "{e}"
        );
        // An inline include table has its keys on its one line.
        let text = "include = [{ path = \"top.gro\", trajectory = \"missing.xtc\" }]\n";
        let e = load_at(&scene, text).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!("{}:1: include.trajectory", scene.display())),
            "{e}"
        );
    }

    #[test]
    fn the_key_line_is_found_in_the_right_include() {
        let text = "[[include]]\npath = \"a\"\n\n[[include]]\n\npath = \"b\"\ntrajectory = \"c\"\n";
        assert_eq!(key_line(text, 0, "path"), Some(2));
        assert_eq!(key_line(text, 1, "path"), Some(6));
        assert_eq!(key_line(text, 1, "trajectory"), Some(7));
        assert_eq!(key_line(text, 0, "trajectory"), None);
        assert_eq!(key_line(text, 2, "path"), None);
    }
}

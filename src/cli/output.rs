//! The one check of every output a command will write, made before any work starts (a
//! bad output path found after an hour of rendering wastes the hour). Every command lists its
//! outputs (`-o`, `--json`, `--report`, …) and calls [`check_outputs`] first.
//!
//! For each output: its extension names a format the command writes; it is not a folder where
//! a file is wanted (or a file where a folder is wanted); and the folder it goes into exists or
//! can be made: the nearest folder that exists on its path is a folder pgt can write into
//! (checked by creating and removing a temporary file there). Missing folders are not made
//! here: the writers make them when they write ([`pgt::image_io::write_atomically`],
//! [`pgt::image_io::write_folder_atomically`]), so a command that fails leaves nothing.

use std::path::{Path, PathBuf};

/// What an output argument names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputKind {
    /// An image file: `.exr` or `.png`.
    Image,
    /// A part of a cluster render: `.exr` only.
    Part,
    /// A file whose format follows its extension, one of these (lower case, without the dot).
    File(&'static [&'static str]),
    /// A text file of a fixed format (JSON) whatever its name; `-` is standard output.
    Text,
    /// A folder (a report).
    Folder,
}

/// One output of a command: the argument that names it (for messages), the path, its kind.
#[derive(Debug, Clone, Copy)]
pub struct Output<'a> {
    /// The argument as the user types it: `--output`, `--json`, `--report`.
    pub arg: &'static str,
    pub path: &'a Path,
    pub kind: OutputKind,
}

impl<'a> Output<'a> {
    pub fn new(arg: &'static str, path: &'a Path, kind: OutputKind) -> Self {
        Output { arg, path, kind }
    }
}

/// Checks every output (see the module docs); the first problem is an error naming the
/// argument and the path (exit 2, before any work).
pub fn check_outputs(outputs: &[Output]) -> anyhow::Result<()> {
    for o in outputs {
        check_output(o)
            .map_err(|problem| anyhow::anyhow!("{} {}: {problem}", o.arg, o.path.display()))?;
    }
    Ok(())
}

fn check_output(o: &Output) -> Result<(), String> {
    if o.kind == OutputKind::Text && o.path.as_os_str() == "-" {
        return Ok(());
    }
    if o.path.as_os_str().is_empty() {
        return Err("the path is empty".into());
    }
    check_extension(o)?;
    let folder = match o.kind {
        OutputKind::Folder => {
            if o.path.exists() && !o.path.is_dir() {
                return Err("exists and is not a folder".into());
            }
            o.path
        }
        _ => {
            if o.path.is_dir() {
                return Err("is a folder; name the file to write".into());
            }
            match o.path.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            }
        }
    };
    check_folder(folder)
}

fn check_extension(o: &Output) -> Result<(), String> {
    let allowed: &[&str] = match o.kind {
        OutputKind::Image => &["exr", "png"],
        OutputKind::Part => &["exr"],
        OutputKind::File(list) => list,
        OutputKind::Text | OutputKind::Folder => return Ok(()),
    };
    let ext = o
        .path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref().is_some_and(|e| allowed.contains(&e)) {
        return Ok(());
    }
    let list: Vec<String> = allowed.iter().map(|e| format!(".{e}")).collect();
    Err(match o.kind {
        OutputKind::Part => "a part (--part) is written as an EXR; name it .exr and merge the parts with `pgt merge` into any format".into(),
        _ => format!(
            "the format follows the extension, which must be {}",
            list.join(" or ")
        ),
    })
}

/// `folder` exists and is writable, or can be made: its nearest existing ancestor is a folder
/// that takes a new file.
fn check_folder(folder: &Path) -> Result<(), String> {
    let mut existing: PathBuf = folder.to_path_buf();
    while !existing.exists() {
        match existing.parent() {
            Some(p) if !p.as_os_str().is_empty() => existing = p.to_path_buf(),
            _ => {
                existing = PathBuf::from(".");
                break;
            }
        }
    }
    if !existing.is_dir() {
        return Err(format!(
            "cannot make the folder {}: {} is a file, not a folder",
            folder.display(),
            existing.display()
        ));
    }
    tempfile::Builder::new()
        .prefix(".pgt-probe-")
        .tempfile_in(&existing)
        .map(drop)
        .map_err(|e| format!("cannot write into the folder {}: {e}", existing.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn problem(path: &Path, kind: OutputKind) -> String {
        check_outputs(&[Output::new("--output", path, kind)])
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn extensions_are_checked_per_kind() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        for (name, kind) in [
            ("a.exr", OutputKind::Image),
            ("a.PNG", OutputKind::Image),
            ("a.exr", OutputKind::Part),
            ("a.ply", OutputKind::File(&["csv", "ply"])),
            ("a.anything", OutputKind::Text),
            ("report", OutputKind::Folder),
        ] {
            check_outputs(&[Output::new("--output", &d.join(name), kind)]).unwrap();
        }
        let e = problem(&d.join("a.jpg"), OutputKind::Image);
        assert!(e.starts_with("--output "), "{e}");
        assert!(e.contains("a.jpg") && e.contains(".exr or .png"), "{e}");
        assert!(problem(&d.join("a.png"), OutputKind::Part).contains("EXR"));
        assert!(problem(&d.join("a.txt"), OutputKind::File(&["csv"])).contains(".csv"));
        check_outputs(&[Output::new("--json", Path::new("-"), OutputKind::Text)]).unwrap();
    }

    #[test]
    fn missing_folders_are_fine_and_not_made() {
        let dir = tempfile::tempdir().unwrap();
        let deep = dir.path().join("a/b/c");
        check_outputs(&[
            Output::new("--output", &deep.join("x.exr"), OutputKind::Image),
            Output::new("--report", &deep.join("report"), OutputKind::Folder),
        ])
        .unwrap();
        assert!(
            !dir.path().join("a").exists(),
            "nothing is made by the check"
        );
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            0,
            "no probe left"
        );
    }

    #[test]
    fn a_file_in_the_way_and_a_folder_as_file_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("notes.txt");
        std::fs::write(&file, "x").unwrap();
        let e = problem(&file.join("sub/x.exr"), OutputKind::Image);
        assert!(e.contains("is a file, not a folder"), "{e}");
        let e = problem(&file, OutputKind::Folder);
        assert!(e.contains("not a folder"), "{e}");
        let folder = dir.path().join("out.exr");
        std::fs::create_dir(&folder).unwrap();
        let e = problem(&folder, OutputKind::Image);
        assert!(e.contains("is a folder"), "{e}");
    }
}

//! Folders written atomically (docs/design.md §7): a report is written into a temporary folder beside its
//! destination and moved into place at the end, so an interrupted or failed run never leaves a
//! half-written report folder that looks complete.

use crate::error::{PgtError, Result};
use std::path::{Path, PathBuf};

/// Fills a temporary folder with `fill` (given its path) and then makes `dir` hold its files.
///
/// Where `dir` does not exist, the temporary folder is renamed to it (one atomic step). Where it
/// exists, each file is moved into it by a rename, with the signal cleanup held off
/// (`crate::signals::hold_off`: microseconds) and `index.html` last, so that the page, which
/// links the rest, appears only once they are there; other files already in `dir` are kept, as
/// before. On an error of `fill`, or on SIGINT/SIGTERM, the temporary folder is removed.
pub fn write_folder_atomically<T>(dir: &Path, fill: impl FnOnce(&Path) -> Result<T>) -> Result<T> {
    if dir.exists() && !dir.is_dir() {
        return Err(PgtError::in_file(dir, "exists and is not a folder"));
    }
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(parent).map_err(|e| PgtError::io(parent, e))?;
    let (tmp, guard) = crate::signals::track(
        || {
            tempfile::Builder::new()
                .prefix(".pgt-partial-")
                .tempdir_in(parent)
        },
        |t| t.path().to_path_buf(),
    )
    .map_err(|e| PgtError::io(parent, e))?;
    let value = fill(tmp.path())?;
    if dir.exists() {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(tmp.path())
            .and_then(|rd| rd.map(|e| e.map(|e| e.path())).collect())
            .map_err(|e| PgtError::io(tmp.path(), e))?;
        // index.html last; the rest in a fixed order.
        entries.sort_by_key(|p| (p.file_name() == Some("index.html".as_ref()), p.clone()));
        crate::signals::hold_off(|| {
            for from in &entries {
                let to = dir.join(from.file_name().unwrap_or_default());
                if to.is_dir() {
                    std::fs::remove_dir_all(&to).map_err(|e| PgtError::io(&to, e))?;
                }
                std::fs::rename(from, &to).map_err(|e| PgtError::io(&to, e))?;
            }
            Ok::<_, PgtError>(())
        })?;
        // The emptied temporary folder goes with `tmp`'s drop; `guard` forgets it after.
        drop(tmp);
        drop(guard);
    } else {
        let tmp_path = tmp.keep();
        guard
            .finish(|| std::fs::rename(&tmp_path, dir))
            .map_err(|e| {
                let _ = std::fs::remove_dir_all(&tmp_path);
                PgtError::io(dir, e)
            })?;
    }
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_new_folder_appears_whole() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("report");
        write_folder_atomically(&dir, |tmp| {
            assert!(
                !dir.exists(),
                "nothing at the destination while it is written"
            );
            std::fs::write(tmp.join("index.html"), "page").unwrap();
            std::fs::write(tmp.join("a.png"), "a").unwrap();
            Ok(())
        })
        .unwrap();
        assert_eq!(names(&dir), ["a.png", "index.html"]);
        assert_eq!(names(root.path()), ["report"], "no temporary folder left");
    }

    #[test]
    fn an_existing_folder_keeps_other_files_and_gets_new_ones() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("report");
        std::fs::create_dir(&dir).unwrap();
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        std::fs::write(dir.join("index.html"), "old").unwrap();
        write_folder_atomically(&dir, |tmp| {
            std::fs::write(tmp.join("index.html"), "new").unwrap();
            Ok(())
        })
        .unwrap();
        assert_eq!(names(&dir), ["index.html", "notes.txt"]);
        assert_eq!(
            std::fs::read_to_string(dir.join("index.html")).unwrap(),
            "new"
        );
        assert_eq!(names(root.path()), ["report"]);
    }

    #[test]
    fn a_failed_fill_leaves_nothing() {
        let root = tempfile::tempdir().unwrap();
        let dir = root.path().join("report");
        let r: Result<()> = write_folder_atomically(&dir, |tmp| {
            std::fs::write(tmp.join("index.html"), "half").unwrap();
            Err(PgtError::Usage("failed".into()))
        });
        assert!(r.is_err());
        assert!(names(root.path()).is_empty(), "{:?}", names(root.path()));
    }
}

//! Interrupted runs leave nothing behind (docs/design.md §7): on SIGINT (Ctrl-C) or SIGTERM, pgt removes
//! every temporary file and folder it is writing, prints one line and exits 130 (SIGINT) or 143
//! (SIGTERM), the shell's 128 + signal number.
//!
//! Whatever writes a temporary thing registers it with [`track`] (which creates and registers it
//! in one step, so no signal falls between the two) and makes it final with
//! [`TempGuard::finish`] (the rename, during which the cleanup waits: an interrupt then leaves
//! either the old output or the complete new one, never half of one). The binary calls
//! [`install`] once; without it (the library used by itself) nothing changes but the bookkeeping.

use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// Temporary paths to remove on a signal, with the id of the guard that registered each.
static REGISTRY: Mutex<Vec<(u64, PathBuf)>> = Mutex::new(Vec::new());
static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
/// Outputs made final by [`TempGuard::finish`] in this process (the frames of `--frames` that an
/// interrupt leaves in place).
static FINISHED: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

fn registry() -> MutexGuard<'static, Vec<(u64, PathBuf)>> {
    // A panic elsewhere while holding the lock must not stop the cleanup.
    REGISTRY.lock().unwrap_or_else(|e| e.into_inner())
}

/// A registered temporary file or folder; dropping it forgets the path (the owner removes it).
#[derive(Debug)]
pub struct TempGuard {
    id: u64,
}

impl TempGuard {
    /// Runs `finish` (the rename that turns the temporary thing into the output) while signal
    /// cleanup is held off, then forgets the path if it succeeded.
    pub fn finish<T, E>(self, finish: impl FnOnce() -> Result<T, E>) -> Result<T, E> {
        let mut list = registry();
        let result = finish();
        if result.is_ok() {
            list.retain(|(id, _)| *id != self.id);
            FINISHED.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        drop(list);
        result
    }
}

impl Drop for TempGuard {
    fn drop(&mut self) {
        registry().retain(|(id, _)| *id != self.id);
    }
}

/// Creates a temporary thing with `create` and registers the path `path_of` gives, both while
/// signal cleanup is held off.
pub fn track<T, E>(
    create: impl FnOnce() -> Result<T, E>,
    path_of: impl FnOnce(&T) -> PathBuf,
) -> Result<(T, TempGuard), E> {
    let mut list = registry();
    let made = create()?;
    let id = NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    list.push((id, path_of(&made)));
    Ok((made, TempGuard { id }))
}

/// Runs `f` with signal cleanup held off (for a few quick renames that must not be cut in two).
/// `f` must not call [`track`] or drop a [`TempGuard`] (the lock is not reentrant).
pub fn hold_off<T>(f: impl FnOnce() -> T) -> T {
    let _list = registry();
    f()
}

/// The exit code for a signal: 128 + its number (130 for SIGINT, 143 for SIGTERM).
pub fn exit_code(signal: i32) -> u8 {
    (128 + signal).clamp(0, 255) as u8
}

/// Installs the SIGINT and SIGTERM handling: a thread that, on the first such signal, removes
/// the registered temporary paths, prints one line on stderr and exits with [`exit_code`].
pub fn install() -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new()
        .name("pgt-signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                let name = if signal == SIGINT {
                    "SIGINT"
                } else {
                    "SIGTERM"
                };
                // Holding the lock to the end: no new temporary file appears, no rename starts.
                let list = registry();
                let removed = list.iter().filter(|(_, p)| remove(p)).count();
                let finished = FINISHED.load(std::sync::atomic::Ordering::Relaxed);
                eprintln!("error: {}", interrupted_line(name, removed, finished));
                std::process::exit(exit_code(signal).into());
            }
        })?;
    Ok(())
}

/// What an interrupt did: the temporary files removed, and the outputs this run finished
/// before it, which stay (the frames of `--frames`).
fn interrupted_line(signal: &str, removed: usize, finished: u64) -> String {
    if finished == 0 {
        format!("interrupted by {signal}; {removed} temporary file(s) removed, no output written")
    } else {
        format!(
            "interrupted by {signal}; {removed} temporary file(s) removed; the {finished} output file(s) finished before it are kept"
        )
    }
}

/// Removes a file or a folder with its contents; whether something was there.
fn remove(path: &Path) -> bool {
    match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => std::fs::remove_dir_all(path).is_ok(),
        Ok(_) => std::fs::remove_file(path).is_ok(),
        Err(_) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracked_paths_are_forgotten_when_finished_or_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let a = dir.path().join("a");
        let b = dir.path().join("b");
        let count = |p: &Path| registry().iter().filter(|(_, q)| q == p).count();
        let (_, ga) = track(|| Ok::<_, ()>(()), |_| a.clone()).unwrap();
        let (_, gb) = track(|| Ok::<_, ()>(()), |_| b.clone()).unwrap();
        assert_eq!((count(&a), count(&b)), (1, 1));
        // A failed finish keeps the path registered until the guard goes.
        let failed: Result<(), ()> = ga.finish(|| Err(()));
        assert!(failed.is_err());
        assert_eq!(count(&a), 0, "the guard was consumed and dropped");
        gb.finish(|| Ok::<_, ()>(())).unwrap();
        assert_eq!(count(&b), 0);
        assert_eq!((exit_code(2), exit_code(15)), (130, 143));
    }

    #[test]
    fn the_interrupt_line_says_what_was_kept() {
        let none = interrupted_line("SIGINT", 1, 0);
        assert!(
            none.ends_with("1 temporary file(s) removed, no output written"),
            "{none}"
        );
        let kept = interrupted_line("SIGTERM", 2, 7);
        assert!(
            kept.contains("SIGTERM")
                && kept.contains("the 7 output file(s) finished before it are kept"),
            "{kept}"
        );
        assert!(!kept.contains("no output written"), "{kept}");
    }

    #[test]
    fn remove_takes_files_and_folders() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("f");
        let d = dir.path().join("d");
        std::fs::write(&f, b"x").unwrap();
        std::fs::create_dir(&d).unwrap();
        std::fs::write(d.join("inner"), b"y").unwrap();
        assert!(remove(&f) && remove(&d));
        assert!(!f.exists() && !d.exists());
        assert!(!remove(&f), "nothing there any more");
    }
}

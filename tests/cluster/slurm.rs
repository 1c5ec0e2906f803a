//! A cluster render through a real Slurm (issue 12): `contrib/slurm/ci-local-slurm.sh` starts a
//! single-node Slurm on localhost (munged, slurmctld, slurmd), submits the array job of parts and
//! the dependent merge job with `contrib/slurm/submit.sh`, and stops the daemons; this test
//! checks that the merged image equals a direct render in every bit and that no daemon is left.
//!
//! Under `CI=true` a Slurm that cannot start fails the test (`.ci/run` installs the packages);
//! elsewhere the test says why it skipped.

use crate::support::skip;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

fn channels(path: &Path) -> BTreeMap<String, Vec<u32>> {
    let img = exr::prelude::read_all_flat_layers_from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    img.layer_data
        .iter()
        .flat_map(|l| l.channel_data.list.iter())
        .map(|c| {
            let bits = c.sample_data.values_as_f32().map(f32::to_bits).collect();
            (c.name.to_string(), bits)
        })
        .collect()
}

/// Whether a process is still there in any state but a zombie (an exited daemon nobody has
/// waited for still answers `kill -0`).
fn alive(pid: u32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        // The state follows the command name, which is in parentheses and may contain spaces.
        Ok(stat) => stat
            .rsplit_once(')')
            .and_then(|(_, rest)| rest.split_whitespace().next())
            .is_some_and(|state| state != "Z"),
        Err(_) => false,
    }
}

/// Runs `contrib/slurm/ci-local-slurm.sh WORK disjoint_lit.toml 4 --size 40x30` with `PGT=pgt`,
/// checks that no daemon it started survived, and returns its exit code and stderr, or `None`
/// (after saying why) where Slurm cannot start outside CI.
fn local_slurm(work: &Path, pgt: &Path) -> Option<(Option<i32>, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("bash")
        .arg(root.join("contrib/slurm/ci-local-slurm.sh"))
        .arg(work)
        .arg(root.join("examples").join("disjoint_lit.toml"))
        .arg("4")
        .args(SIZE)
        .env("PGT", pgt)
        .stdin(std::process::Stdio::null())
        .output()
        .expect("bash runs");
    let log = String::from_utf8_lossy(&out.stderr).into_owned();
    // Whatever happened, the daemons the script started must be gone.
    let pids = std::fs::read_to_string(work.join("daemon-pids")).unwrap_or_default();
    for pid in pids
        .split_whitespace()
        .filter_map(|p| p.parse::<u32>().ok())
    {
        assert!(!alive(pid), "daemon {pid} is still running\n{log}");
    }
    if out.status.code() == Some(77) {
        let reason = log.lines().last().unwrap_or("(no reason given)");
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true: Slurm must start here: {reason}\n{log}"
        );
        skip::skipped(reason);
        return None;
    }
    Some((out.status.code(), log))
}

const SIZE: [&str; 2] = ["--size", "40x30"];

/// One test, so that the two Slurm runs do not overlap.
#[test]
fn an_array_job_and_a_dependent_merge_through_slurm_equal_a_direct_render() {
    let pgt = Path::new(env!("CARGO_BIN_EXE_pgt"));
    let work = tempfile::tempdir().unwrap();
    let Some((code, log)) = local_slurm(work.path(), pgt) else {
        return;
    };
    assert_eq!(code, Some(0), "{log}");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/disjoint_lit.toml");
    let direct = work.path().join("direct.exr");
    let st = Command::new(pgt)
        .arg("render")
        .arg(&scene)
        .args(SIZE)
        .arg("-o")
        .arg(&direct)
        .status()
        .unwrap();
    assert!(st.success());
    let (a, b) = (channels(&direct), channels(&work.path().join("merged.exr")));
    assert!(a.contains_key("err.R"), "the lit scene has an err layer");
    assert_eq!(
        a, b,
        "the merge through Slurm differs from the direct render\n{log}"
    );
    // All four array tasks ran as Slurm jobs.
    assert!(log.contains("4 JobState=COMPLETED"), "{log}");

    // A part that fails: the merge job must be cancelled (--kill-on-invalid-dep=yes), not left
    // pending, and nothing merged.
    let failing = tempfile::tempdir().unwrap();
    let wrapper = failing.path().join("pgt-fails-part-2");
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/sh\n[ \"$SLURM_ARRAY_TASK_ID\" = 2 ] && {{ echo 'part 2 fails' >&2; exit 3; }}\nexec '{}' \"$@\"\n",
            pgt.display()
        ),
    )
    .unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&wrapper, std::fs::Permissions::from_mode(0o755)).unwrap();
    let Some((code, log)) = local_slurm(failing.path(), &wrapper) else {
        return;
    };
    assert_eq!(code, Some(1), "{log}");
    assert!(log.contains("JobState=CANCELLED"), "{log}");
    assert!(log.contains("1 JobState=FAILED"), "{log}");
    assert!(!failing.path().join("merged.exr").exists());
}

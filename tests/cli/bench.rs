//! End-to-end test of `pgt bench` (docs/design.md §7): one small workload through the binary, the
//! table it prints read back.

use std::process::Command;

/// `pgt bench` on the single-scatter workload with point lights (inside the gas and above it),
/// on the generated protein-sized set (`--data` names no folder), 8×8, with `--accuracy`: three
/// rows (adaptive, Riemann-100, emission), shadow rays where the model traces them and none for
/// emission, and the adaptive image within tol 1e-4 of the tol 1e-9 truth.
#[test]
fn bench_prints_the_single_scatter_workload_with_its_baselines() {
    let dir = tempfile::tempdir().expect("temp dir");
    let out = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(["bench", "--size", "8", "--workloads", "1uun-scatter"])
        .args(["--accuracy", "--threads", "1", "--data"])
        .arg(dir.path().join("no-data"))
        .output()
        .expect("the pgt binary runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stderr.contains("generated protein-sized set"), "{stderr}");
    // workload (two words), renderer (one to three words), then the numeric columns.
    let rows: Vec<(String, Vec<String>)> = stdout
        .lines()
        .filter_map(|l| l.strip_prefix("protein scatter"))
        .map(|rest| {
            let words: Vec<&str> = rest.split_whitespace().collect();
            let first_number = words
                .iter()
                .position(|w| *w == "8")
                .expect("the size column");
            (
                words[..first_number].join(" "),
                words[first_number..]
                    .iter()
                    .map(|w| w.to_string())
                    .collect(),
            )
        })
        .collect();
    let renderers: Vec<&str> = rows.iter().map(|(r, _)| r.as_str()).collect();
    assert_eq!(
        renderers,
        ["adaptive tol 1e-4", "riemann-100", "emission"],
        "{stdout}"
    );
    // Columns after the renderer: size, spheres, time, setup, shadow/px, Mrays/s, /riemann,
    // /emission, max err, vs truth.
    let number = |row: usize, col: usize| -> f64 {
        rows[row].1[col]
            .parse()
            .unwrap_or_else(|_| panic!("row {row} column {col}: {stdout}"))
    };
    assert_eq!(number(0, 1), 2758.0, "{stdout}");
    assert!(number(0, 4) > 0.0 && number(1, 4) > 0.0, "{stdout}");
    assert_eq!(number(2, 4), 0.0, "{stdout}");
    let adaptive_vs_truth = number(0, 9);
    assert!(
        (0.0..=1e-4).contains(&adaptive_vs_truth),
        "adaptive off the truth by {adaptive_vs_truth}: {stdout}"
    );
}

/// `--repeat 2` says on stderr that each renderer runs twice in turn and still prints one row
/// per renderer; `--repeat 0` is refused with exit code 2 and no table. (Which of the runs the
/// table keeps is not visible from outside: the images are the same, only the times differ.)
#[test]
fn bench_repeat_prints_one_row_per_renderer_and_refuses_zero() {
    let dir = tempfile::tempdir().expect("temp dir");
    let bench = |repeat: &str| {
        Command::new(env!("CARGO_BIN_EXE_pgt"))
            .args([
                "bench",
                "--size",
                "4",
                "--workloads",
                "1uun",
                "--threads",
                "1",
            ])
            .args(["--repeat", repeat, "--data"])
            .arg(dir.path().join("no-data"))
            .output()
            .expect("the pgt binary runs")
    };
    let out = bench("2");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stderr.contains("each renderer 2 times in turn"), "{stderr}");
    let renderers: Vec<String> = stdout
        .lines()
        .filter(|l| l.starts_with("protein-like"))
        .map(|l| {
            let words: Vec<&str> = l.split_whitespace().collect();
            let size = words.iter().position(|w| *w == "4").expect("size column");
            words[1..size].join(" ")
        })
        .collect();
    assert_eq!(
        renderers,
        ["adaptive tol 1e-4", "riemann-100", "emission"],
        "{stdout}"
    );

    let out = bench("0");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--repeat"), "{stderr}");
    assert!(
        out.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
}

//! The first hour of a new user (issue 31) and two items of issue 30, end to end through the
//! `pgt` binary: outputs checked before any work, a closed stdout, methods that refuse a model
//! they do not implement, `pgt export`'s CSV read back without a warning, `--format`, the
//! include folder in messages, help and usage texts, `--part` (and the deprecated `--tile`),
//! and files that are the same bytes for any thread count and on every run.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn pgt(args: &[&str]) -> Output {
    pgt_env(args, &[])
}

fn pgt_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_pgt"));
    cmd.args(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("pgt runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples")
        .join(name)
}

fn ok(o: &Output) {
    assert_eq!(o.status.code(), Some(0), "{}", stderr(o));
}

/// Whether this is CI (`CI=true`), where a missing adapter is a failure, not a skip.
fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true")
}

/// A file in the way of a folder: `DIR/notes.txt` exists as a file, so no output can go under it
/// (the check does not depend on permissions, which root ignores).
fn file_in_the_way(dir: &Path) -> PathBuf {
    let f = dir.join("notes.txt");
    std::fs::write(&f, "a file, not a folder").unwrap();
    f
}

/// Expects exit 2 within a few seconds, a message naming `arg` and the bad path, and none of
/// `work` (what the command prints once it has done its work) on stderr.
fn fails_fast(args: &[&str], arg: &str, path: &Path, work: &str) {
    let start = Instant::now();
    let o = pgt(args);
    let took = start.elapsed();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
    assert!(
        err.contains(&format!("{arg} {}", path.display())),
        "{args:?}: the message must name {arg} and the path: {err}"
    );
    assert!(!err.contains(work), "{args:?}: work was done: {err}");
    assert!(!err.contains("panicked"), "{err}");
    // The work these commands were given takes minutes; refusing takes a blink.
    assert!(took < Duration::from_secs(20), "{args:?} took {took:?}");
}

/// A scene whose reference at its own size would take minutes (4096², lit gas).
fn big_scene(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(example("disjoint_lit.toml")).unwrap();
    let text = text.replacen("[camera]\n", "[camera]\nwidth = 4096\nheight = 4096\n", 1);
    let path = dir.join("big.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn every_output_is_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let blocked = file_in_the_way(d);
    let under = |name: &str| blocked.join("sub").join(name);
    let scene = example("disjoint_lit.toml");
    let big = big_scene(d);
    let size = "8192x8192";

    let out = under("x.exr");
    fails_fast(
        &["render", s(&scene), "--size", size, "-o", s(&out)],
        "--output",
        &out,
        "rendered",
    );
    let jpg = d.join("x.jpg");
    fails_fast(
        &["render", s(&scene), "--size", size, "-o", s(&jpg)],
        "--output",
        &jpg,
        "rendered",
    );
    let png = d.join("part.png");
    fails_fast(
        &[
            "render",
            s(&scene),
            "--size",
            size,
            "--part",
            "0/2",
            "-o",
            s(&png),
        ],
        "--output",
        &png,
        "rendered",
    );
    // No adapter is needed to refuse an output: the check comes first.
    fails_fast(
        &["approx", s(&scene), "--size", size, "-o", s(&out)],
        "--output",
        &out,
        "approximated",
    );
    let json = under("summary.json");
    fails_fast(
        &["compare", s(&big), s(&big), "--json", s(&json)],
        "--json",
        &json,
        "rendered the reference",
    );
    let report = under("report");
    fails_fast(
        &["compare", s(&big), s(&big), "--report", s(&report)],
        "--report",
        &report,
        "rendered the reference",
    );
    fails_fast(
        &["compare", s(&big), s(&big), "--report", s(&blocked)],
        "--report",
        &blocked,
        "rendered the reference",
    );
    let experiment = d.join("experiment.toml");
    std::fs::write(
        &experiment,
        format!(
            "scene = {:?}\nsize = [4096, 4096]\n[[approximations]]\nmethod = \"riemann\"\nsamples = [10]\n",
            s(&scene)
        ),
    )
    .unwrap();
    fails_fast(
        &["sweep", s(&experiment), "--report", s(&report)],
        "--report",
        &report,
        "reference:",
    );
    // The output is checked before the parts are even read.
    fails_fast(
        &["merge", "no-such-part.exr", "-o", s(&out)],
        "--output",
        &out,
        "merged",
    );
    let tif = d.join("x.tif");
    fails_fast(
        &["merge", "no-such-part.exr", "-o", s(&tif)],
        "--output",
        &tif,
        "merged",
    );
    let csv = under("particles.csv");
    fails_fast(
        &["export", s(&scene), "-o", s(&csv)],
        "--output",
        &csv,
        "exported",
    );
    let txt = d.join("particles.txt");
    fails_fast(
        &["export", s(&scene), "-o", s(&txt)],
        "--output",
        &txt,
        "exported",
    );
    fails_fast(
        &["gen", "random", "--count", "100000000", "-o", s(&csv)],
        "--output",
        &csv,
        "wrote",
    );
    fails_fast(
        &["gen", "random", "--count", "100000000", "-o", s(&txt)],
        "--output",
        &txt,
        "wrote",
    );
    // Nothing was written anywhere.
    let mut left: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["big.toml", "experiment.toml", "notes.txt"]);
}

#[test]
fn missing_folders_of_an_output_are_made() {
    let dir = tempfile::tempdir().unwrap();
    let scene = example("shadows.toml");
    let png = dir.path().join("a/b/c/shadows.png");
    ok(&pgt(&[
        "render",
        s(&scene),
        "--size",
        "16x12",
        "-o",
        s(&png),
    ]));
    assert!(png.is_file());
    let csv = dir.path().join("d/e/particles.csv");
    ok(&pgt(&["export", s(&scene), "-o", s(&csv)]));
    assert!(csv.is_file());
}

/// Runs `pgt` with its stdout a pipe whose reading end is closed at once, as `| true` does.
fn with_closed_stdout(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_pgt"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("pgt runs");
    drop(child.stdout.take());
    child.wait_with_output().expect("pgt ends")
}

#[test]
fn a_closed_stdout_ends_the_command_quietly() {
    let scene = example("disjoint_lit.toml");
    let csv = tempfile::tempdir().unwrap();
    let particles = csv.path().join("p.csv");
    ok(&pgt(&["export", s(&scene), "-o", s(&particles)]));
    for args in [
        vec!["info", s(&scene), "--json"],
        vec!["info", s(&particles)],
        vec!["camera", s(&scene), "--json"],
        vec!["camera", s(&scene)],
        vec!["approx", "--list-methods"],
    ] {
        let o = with_closed_stdout(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(!err.contains("Broken pipe"), "{args:?}: {err}");
    }
}

#[test]
fn a_method_refuses_a_model_it_does_not_implement() {
    let dir = tempfile::tempdir().unwrap();
    let lit = example("disjoint_lit.toml");
    let out = dir.path().join("x.exr");
    for method in ["sorted-blend", "emission"] {
        let o = pgt(&["approx", s(&lit), "--method", method, "-o", s(&out)]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&format!(
                "the {method} method implements the emission model"
            )) && err.contains("not lit")
                && err.contains("--model emission"),
            "{err}"
        );
        assert!(!out.exists());
    }
    // The thesis method implements both; no built-in method implements single-scatter.
    let o = pgt(&[
        "approx",
        s(&lit),
        "--model",
        "single-scatter",
        "-o",
        s(&out),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("not single-scatter") && err.contains("--shader"),
        "{err}"
    );
    // The opaque method draws opaque scenes only.
    let o = pgt(&["approx", s(&lit), "--method", "opaque", "-o", s(&out)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--mode opaque"), "{err}");
    // With `--model emission` the choice is explicit and the check passes: what follows is the
    // adapter, here pointed at no driver at all.
    let o = pgt_env(
        &[
            "approx",
            s(&lit),
            "--method",
            "sorted-blend",
            "--model",
            "emission",
            "-o",
            s(&out),
        ],
        &[
            ("VK_ICD_FILENAMES", "/nonexistent/icd.json"),
            ("VK_DRIVER_FILES", "/nonexistent/icd.json"),
        ],
    );
    let err = stderr(&o);
    assert!(err.contains(pgt::approx::NO_ADAPTER), "{err}");
}

/// An approximation of a small scene with stderr as pgt leaves it, or `None` without an adapter
/// (a failure under CI).
fn approx_stderr(dir: &Path, env_remove: &[&str]) -> Option<String> {
    let out = dir.join("a.png");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_pgt"));
    cmd.args([
        "approx",
        s(&example("disjoint_lit.toml")),
        "--size",
        "24x16",
        "--samples",
        "4",
        "--n-exact",
        "1",
        "-o",
        s(&out),
    ]);
    for k in env_remove {
        cmd.env_remove(k);
    }
    let o = cmd.output().expect("pgt runs");
    let err = stderr(&o);
    if err.contains(pgt::approx::NO_ADAPTER) {
        assert!(!in_ci(), "CI=true and no GPU adapter: {err}");
        crate::support::skipped("no GPU adapter (CI is not set)");
        return None;
    }
    assert_eq!(o.status.code(), Some(0), "{err}");
    Some(err)
}

#[test]
fn gpu_commands_print_only_pgts_own_words() {
    let dir = tempfile::tempdir().unwrap();
    let unset = [
        "XDG_RUNTIME_DIR",
        "NODEVICE_SELECT",
        "MESA_VK_DEVICE_SELECT",
        "DRI_PRIME",
    ];
    let Some(err) = approx_stderr(dir.path(), &unset) else {
        return;
    };
    assert!(!err.contains("XDG_RUNTIME_DIR"), "{err}");
    // The summary, and progress lines where the machine is slow enough to need them.
    for line in err.lines() {
        assert!(
            line.starts_with("approximated ") || line.starts_with("approx: "),
            "not pgt's words: {line}"
        );
    }
    let summary = err
        .lines()
        .find(|l| l.starts_with("approximated "))
        .unwrap_or_else(|| panic!("{err}"));
    // The rate and the GPU time with three significant digits, never a row of zeros.
    let number_before = |unit: &str| -> f64 {
        let head = &summary[..summary.find(unit).unwrap_or_else(|| panic!("{summary}"))];
        let word = head.trim_end().rsplit(' ').next().unwrap();
        word.parse()
            .unwrap_or_else(|_| panic!("'{word}' in {summary}"))
    };
    let rate = summary.rsplit(", ").next().unwrap();
    assert!(rate.ends_with("pixels/s"), "{summary}");
    let value: f64 = rate.split(' ').next().unwrap().parse().unwrap();
    assert!(value > 0.0, "{summary}");
    assert!(number_before(" s GPU") > 0.0, "{summary}");
}

#[test]
fn the_export_reads_back_without_warnings_and_with_its_sigma() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(
        &scene,
        "[render]\nlambda = 0.5\n[defaults]\nopacity = 0.3\n\
         [[particles]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.25\nopacity = 1.0\n\
         [[particles]]\ncenter = [3.0, 0.0, 0.0]\nradius = 0.7\nkappa = 0.9\n\
         [[particles]]\ncenter = [0.0, 3.0, 0.0]\nradius = 0.001\nopacity = 0.0\n\
         [[particles]]\ncenter = [0.0, 0.0, 3.0]\nradius = 2.0\n",
    )
    .unwrap();
    let csv = dir.path().join("p.csv");
    ok(&pgt(&["export", s(&scene), "-o", s(&csv)]));
    let options = pgt::SceneLoadOptions::default();
    let original = pgt::Scene::load(&scene, &options).unwrap();
    let again = pgt::Scene::load(&csv, &options).unwrap();
    assert!(again.warnings.is_empty(), "{:?}", again.warnings);
    assert_eq!(again.particles.len(), original.particles.len());
    for (a, b) in again.particles.iter().zip(&original.particles) {
        assert_eq!(a.sigma.to_bits(), b.sigma.to_bits(), "σ bit for bit");
    }
    // `pgt info` says the same: no warning.
    let o = pgt(&["info", s(&csv), "--json"]);
    ok(&o);
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["warnings"], serde_json::json!([]));
    // An opacity edited without its σ is refused, naming the line.
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<String> = lines[2].split(',').map(String::from).collect();
    cells[7] = "0.25".into();
    lines[2] = cells.join(",");
    let edited = dir.path().join("edited.csv");
    std::fs::write(&edited, lines.join("\n") + "\n").unwrap();
    let o = pgt(&["info", s(&edited)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("{}:3", edited.display())) && err.contains("disagree"),
        "{err}"
    );
}

#[test]
fn format_names_the_format_of_a_bare_file() {
    let dir = tempfile::tempdir().unwrap();
    let txt = dir.path().join("particles.txt");
    std::fs::write(&txt, "x,y,z,radius\n0,0,0,1\n2,0,0,0.5\n").unwrap();
    let o = pgt(&["info", s(&txt)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--format NAME") && err.contains("csv"),
        "{err}"
    );
    let o = pgt(&["info", s(&txt), "--format", "csv", "--json"]);
    ok(&o);
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["particles"], 2);
    assert_eq!(info["format"], "csv");
    let png = dir.path().join("p.png");
    ok(&pgt(&[
        "render",
        s(&txt),
        "--format",
        "csv",
        "--size",
        "8x8",
        "-o",
        s(&png),
    ]));
    assert!(png.is_file());
    ok(&pgt(&["camera", s(&txt), "--format", "csv", "--json"]));
    let csv = dir.path().join("p.csv");
    ok(&pgt(&["export", s(&txt), "--format", "csv", "-o", s(&csv)]));
    // A scene names its includes' formats itself.
    let o = pgt(&["camera", s(&example("shadows.toml")), "--format", "csv"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("[[include]]"), "{err}");
    let o = pgt(&["info", s(&txt), "--format", "jpeg"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("pdb"), "{}", stderr(&o));
}

#[test]
fn an_unreadable_include_says_which_folder_its_path_is_relative_to() {
    let dir = tempfile::tempdir().unwrap();
    let scenes = dir.path().join("scenes");
    std::fs::create_dir(&scenes).unwrap();
    let scene = scenes.join("s.toml");
    std::fs::write(&scene, "[[include]]\npath = \"data/missing.pdb\"\n").unwrap();
    let o = pgt(&["info", s(&scene)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    // Named at the line of the `path` key that names the file.
    assert!(
        err.contains(&format!("{}:2: include.path: cannot read", scene.display())),
        "{err}"
    );
    assert!(
        err.contains("`data/missing.pdb` is taken relative to")
            && err.contains(&format!("{}, the scene file's folder", scenes.display())),
        "{err}"
    );
}

#[test]
fn help_and_usage_say_what_is_optional() {
    let o = pgt(&["render", "scene.toml", "--size", "8x8"]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let usage = err
        .lines()
        .find(|l| l.starts_with("Usage:"))
        .unwrap_or_else(|| panic!("{err}"));
    assert!(!usage.contains("--size"), "{usage}");
    assert!(usage.contains("[OPTIONS]"), "{usage}");
    for command in ["render", "approx"] {
        let o = pgt(&[command, "--help"]);
        ok(&o);
        let help = String::from_utf8_lossy(&o.stdout).into_owned();
        let mode = help
            .lines()
            .skip_while(|l| !l.trim_start().starts_with("--mode"))
            .nth(1)
            .unwrap_or_default();
        assert!(
            mode.contains("Render mode"),
            "{command}: --mode has no help: {help}"
        );
        assert!(help.contains("--format <NAME>"), "{help}");
    }
}

#[test]
fn part_names_a_part_and_tile_still_works_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let scene = example("disjoint_lit.toml");
    let a = dir.path().join("a.exr");
    let b = dir.path().join("b.exr");
    let common = ["--size", "20x12"];
    let o = pgt(&[
        &["render", s(&scene), "--part", "1/3", "-o", s(&a)][..],
        &common,
    ]
    .concat());
    ok(&o);
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));
    let o = pgt(&[
        &["render", s(&scene), "--tile", "1/3", "-o", s(&b)][..],
        &common,
    ]
    .concat());
    ok(&o);
    let warnings: Vec<String> = stderr(&o)
        .lines()
        .filter(|l| l.contains("--tile"))
        .map(String::from)
        .collect();
    assert_eq!(warnings.len(), 1, "{}", stderr(&o));
    assert!(
        warnings[0].starts_with("warning: --tile is deprecated") && warnings[0].contains("--part")
    );
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let o = pgt(&[
        "render",
        s(&scene),
        "--part",
        "0/2",
        "--tile",
        "0/2",
        "-o",
        s(&a),
    ]);
    assert_eq!(o.status.code(), Some(2));
    // `--tile` is not advertised.
    let help = String::from_utf8_lossy(&pgt(&["render", "--help"]).stdout).into_owned();
    assert!(
        help.contains("--part <I/N>") && !help.contains("--tile"),
        "{help}"
    );
}

/// The same render is the same file, byte for byte, for any thread count and on every run:
/// EXR (with its err layer), PNG, the parts of a cluster render (with their header) and their
/// merge.
#[test]
fn the_same_render_is_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = example("disjoint_lit.toml");
    let size = ["--size", "48x32"];
    let render = |name: &str, threads: Option<&str>, extra: &[&str]| -> Vec<u8> {
        let out = d.join(name);
        let mut args = vec!["render", s(&scene), "-o", s(&out)];
        args.extend_from_slice(&size);
        args.extend_from_slice(extra);
        if let Some(t) = threads {
            args.extend_from_slice(&["--threads", t]);
        }
        ok(&pgt(&args));
        std::fs::read(&out).unwrap()
    };
    for ext in ["exr", "png"] {
        let one = render(&format!("t1.{ext}"), Some("1"), &[]);
        let two = render(&format!("t2.{ext}"), Some("2"), &[]);
        let again = render(&format!("again.{ext}"), None, &[]);
        assert!(one.len() > 100, "{ext}");
        assert!(one == two, "{ext}: threads 1 and 2 differ");
        assert!(one == again, "{ext}: two runs differ");
    }
    for i in 0..2 {
        let part = ["--part", if i == 0 { "0/2" } else { "1/2" }];
        let one = render(&format!("p{i}_t1.exr"), Some("1"), &part);
        let two = render(&format!("p{i}_t2.exr"), Some("2"), &part);
        let again = render(&format!("p{i}.exr"), None, &part);
        assert!(one == two, "part {i}: threads 1 and 2 differ");
        assert!(one == again, "part {i}: two runs differ");
    }
    let merge = |name: &str| {
        let out = d.join(name);
        ok(&pgt(&[
            "merge",
            s(&d.join("p1.exr")),
            s(&d.join("p0_t2.exr")),
            "-o",
            s(&out),
        ]));
        std::fs::read(&out).unwrap()
    };
    let merged = merge("m1.exr");
    assert!(merged == merge("m2.exr"), "two merges differ");
    assert!(
        merged == std::fs::read(d.join("t1.exr")).unwrap(),
        "the merge is the whole render"
    );
}

//! Skips that show: one line per skipped test in a plain `cargo test`.

/// Says that a test skips, on a line of its own in a plain `cargo test` (without
/// `--nocapture`): written straight to the process's standard error, which the test harness
/// does not capture (it captures only the `print!` family). Under `CI=true` a test must fail
/// instead of calling this.
pub fn skipped(reason: &str) {
    use std::io::Write as _;
    let test = std::thread::current()
        .name()
        .unwrap_or("a test")
        .to_string();
    let _ = std::io::stderr().write_all(format!("SKIPPED {test}: {reason}\n").as_bytes());
}

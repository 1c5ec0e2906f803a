//! `pgt compare REF_SEQUENCE APPROX_SEQUENCE` (docs/design.md §10): both arguments folders or
//! printf patterns of frames. The comparison, the gate, the verdict and the report are the
//! library's ([`pgt::report::sequence_compare`]); this file prints them.

use super::Outcome;
use pgt::metrics::gate::Gate;
use pgt::report::sequence_compare::{compare_sequence_files, SequenceArgs};
use std::path::Path;

/// Runs the comparison and prints the verdict and the JSON summary (`--json`, `-` for stdout).
pub fn run(args: &SequenceArgs, gate: &Gate, json: Option<&Path>) -> anyhow::Result<Outcome> {
    let outcome = compare_sequence_files(args, gate)?;
    if let Some(page) = &outcome.report_page {
        eprintln!("report: {}", page.display());
    }
    let verdict = &outcome.verdict;
    match json {
        Some(path) if path.as_os_str() == "-" => {
            super::print_stdout(&outcome.summary_json()?)?;
            eprintln!("{verdict}");
        }
        Some(path) => {
            pgt::report::text::write_text(path, &outcome.summary_json()?)?;
            super::print_stdout(&format!("{verdict}\n"))?;
        }
        None => super::print_stdout(&format!("{verdict}\n"))?,
    }
    Ok(match outcome.passed {
        Some(false) => Outcome::GateFailed,
        _ => Outcome::Success,
    })
}

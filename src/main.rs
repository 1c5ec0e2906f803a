//! The `pgt` binary: parse, run, map the outcome to an exit code (docs/design.md §7: 0 success,
//! 1 gate failed, 2 error).

mod cli;

use cli::Outcome;
use std::process::ExitCode;

fn main() -> ExitCode {
    // Before any thread starts: it sets an environment variable.
    pgt::approx::context::quiet_device_select_probe();
    let cli = match cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    // SIGINT/SIGTERM: remove temporary files, exit 130/143 (pgt::signals).
    if let Err(e) = pgt::signals::install() {
        eprintln!(
            "warning: cannot handle SIGINT/SIGTERM ({e}); an interrupt may leave temporary files"
        );
    }
    match cli::run(cli) {
        Ok(Outcome::Success) => ExitCode::SUCCESS,
        Ok(Outcome::GateFailed) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {}", pgt::error::error_message(&e));
            ExitCode::from(2)
        }
    }
}

//! The exact CPU reference (docs/design.md §2, §3): closed forms and limits, the honesty of its error
//! estimate, huge σ, and an independent Monte Carlo estimator.
//!
//! One module per topic; `support` is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod error;
mod exact;
mod limits;
mod mc;

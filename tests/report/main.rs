//! The HTML reports in a headless browser (docs/design.md §5 "Reports"): chromium, and
//! chromedriver for the interactive viewer.
//!
//! `support` (tests/support) is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod browser;

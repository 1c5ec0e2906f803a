//! The HTML reports in a headless browser (docs/design.md §5 "Reports"): chromium, and chromedriver
//! for the interactive viewer.
//!
//! One module per topic; `support` is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod browser;

//! The particle formats and the TOML inputs (docs/design.md §1, §6): PDB/mmCIF, MMPLD, VRML, XYZ/CSV
//! against the real files of `../shared/data`, `pgt info`/`gen`, and mutation smoke tests of every
//! parser.
//!
//! One module per topic; `support` is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod cli;
mod fuzz_smoke;
mod mmpld;
mod pdb;
mod text;
mod toml_fuzz_smoke;
mod vrml;

//! The inputs and outputs of particles (docs/design.md §1, §6, §9, §10): PDB/mmCIF, MMPLD, VRML,
//! XYZ/CSV against the real files of `../shared/data`, frames, ellipsoid input, `pgt export` read
//! back, `pgt info`/`gen`, and mutation smoke tests of every parser and of the TOML inputs.
//!
//! One module per topic; `support` (tests/support) is shared by every test binary.

#[path = "../support/mod.rs"]
mod support;

mod cli;
mod ellipsoid_input;
mod export_roundtrip;
mod frames;
mod fuzz_smoke;
mod mmpld;
mod pdb;
mod ply;
mod text;
mod toml_fuzz_smoke;
mod vrml;

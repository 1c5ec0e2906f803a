//! Optics: extinction from the particle description (docs/design.md §1, eq. 5.1), lights and what
//! arrives from them, the cutting of rays into intervals, the emission model's closed form, the
//! optical models of docs/design.md §2 (`model` says what one is, `models/` holds them, one file
//! each) and the places where shadow rays graze spheres (breakpoints of the quadrature).
//!
//! Depends on `geometry` only; `scene` builds on it.

pub mod cutter;
pub mod emission;
pub mod exponential;
pub mod extinction;
pub mod gaussian;
pub mod intervals;
pub mod kinks;
pub mod light;
pub mod model;
pub mod models;
pub mod particle;
pub mod source;
pub mod transmittance;

pub use light::{Falloff, Incident, Light, LightWeight};
pub use model::{LightNeed, Model, OpticalModel};
pub use particle::{Particle, Profile};

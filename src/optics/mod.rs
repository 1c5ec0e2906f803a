//! Optics: extinction from the particle description (DESIGN.md §1), the cutting of rays into
//! intervals, the emission model's closed form, the source terms Q of DESIGN.md §2 and the
//! places where shadow rays graze spheres (breakpoints of the quadrature).

pub mod emission;
pub mod extinction;
pub mod intervals;
pub mod kinks;
pub mod source;

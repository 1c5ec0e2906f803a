//! Optics: extinction from the particle description (DESIGN.md §1) and, with the volume
//! renderer, the interval cutting, closed forms and source terms of DESIGN.md §2.

pub mod extinction;

//! Rays, the stable ray–sphere intersection, the ellipsoid as a mapped sphere, the pinhole
//! camera and the BVH (docs/design.md §1, §3, §9).

pub mod bvh;
pub mod camera;
pub mod camera_path;
pub mod ellipsoid;
pub mod projection;
pub mod ray;
pub mod sphere;

pub use bvh::{Bvh, BvhNode, Hit, Leaf};
pub use camera::{check_rotation, Camera, Intrinsics, Lens};
pub use camera_path::{CameraPath, Interpolation, Keyframe};
pub use ellipsoid::{Ellipsoid, Shape};
pub use ray::Ray;
pub use sphere::{intersect_sphere, Chord};

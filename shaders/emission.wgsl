// Method `emission` (docs/design.md §2 emission model, §4): the particles a camera ray crosses,
// sorted by entry and composited back to front with the closed form
// L = L_behind·T + C·(1 − T) per particle. Exact where particles do not overlap.
fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    return emission_along(ray, 0.0, T_FAR, frame.background);
}

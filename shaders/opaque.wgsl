// Method `opaque` (docs/design.md §2 "Opaque mode", as src/reference/opaque.rs defines it): the first
// particle hit (sphere or ellipsoid), Lambertian C/π plus normalised Blinn–Phong ks·(s+8)/(8π)·max(0, n·h)^s·cos, hard
// shadows by one shadow ray per light through the BVH, plus ambient·C.

// Shadow rays start at the surface; other spheres block only beyond this distance, relative to
// the size of the coordinates (f32 round-off in the hit point is ~1e-7 of it).
const SHADOW_EPSILON: f32 = 1e-4;

fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    let hit = first_hit(ray, 0.0, T_FAR);
    if (!hit.hit) {
        return frame.background;
    }
    let p = particles[hit.index];
    // Snap the point onto the surface so the shadow ray starts exactly there.
    let surface = particle_surface(p, ray_at(ray, hit.t));
    let x = surface.position;
    let n = select(-surface.outward, surface.outward, hit.entering);
    var radiance = frame.ambient * p.color;
    // Seen from inside its particle, a wall's shadow ray towards the light crosses the particle.
    if (!hit.entering) {
        return radiance;
    }
    let scale = max(max(abs(x.x), abs(x.y)), abs(x.z)) + p.radius;
    for (var l = 0u; l < frame.light_count; l = l + 1u) {
        let inc = light_incident(lights[l], x);
        if (!inc.valid) {
            continue;
        }
        let cos_l = dot(n, inc.toward);
        if (cos_l <= 0.0) {
            continue;
        }
        if (any_hit(Ray(x, inc.toward), SHADOW_EPSILON * scale, inc.distance, hit.index)) {
            continue;
        }
        var brdf_cos = p.color / PI * cos_l;
        if (p.ks > 0.0) {
            let h = inc.toward - ray.direction;
            let hl = length(h);
            if (hl > 0.0) {
                let nh = dot(n, h / hl);
                if (nh > 0.0) {
                    brdf_cos = brdf_cos + vec3<f32>(p.ks * (p.shininess + 8.0) / (8.0 * PI) * pow(nh, p.shininess) * cos_l);
                }
            }
        }
        radiance = radiance + inc.irradiance * brdf_cos;
    }
    return radiance;
}

// Method `thesis` (DESIGN.md §4, thesis chapter 5): the particles a camera ray crosses, sorted by
// entry and composited back to front one particle at a time (overlaps ignored). The first
// `n_exact` particles from the eye use the lit model (DESIGN.md §2, thesis eq. 4.17) with
// `samples` midpoint-rule samples along their chord and one shadow ray per sample per light
// (`lit_source`: the emission model along the shadow ray, the light as background); the rest,
// and every particle of an emission-model scene, use the emission model's closed form.

// One particle of chord [t0, t1] lit by the midpoint rule:
// L = L_behind·e^{−σΔ} + Σ_k Q(x_k)·σ·e^{−σ(t_k − t0)}·Δt, t_k = t0 + (k + ½)Δt, Δt = Δ/samples
// (the σ factor of DESIGN.md §8). Θmax = 1 (σ = ∞) has no midpoint rule (every weight is ∞·0):
// the particle gets the integral's limit at its surface, `lit_opaque_surface`.
fn lit_particle(ray: Ray, index: u32, t_enter: f32, t1: f32, behind: vec3<f32>) -> vec3<f32> {
    let p = particles[index];
    let t0 = max(t_enter, 0.0);
    if (p.sigma < 0.0) {
        return lit_opaque_surface(ray, index, t0, t_enter > 0.0);
    }
    let length = t1 - t0;
    let n = max(frame.samples, 1u);
    let dt = length / f32(n);
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < n; k = k + 1u) {
        let t = t0 + (f32(k) + 0.5) * dt;
        let weight = p.sigma * exp(-p.sigma * (t - t0)) * dt;
        sum = sum + lit_source(ray_at(ray, t)) * weight;
    }
    return behind * exp(-p.sigma * length) + sum;
}

fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    var list: HitList;
    collect_hits(ray, 0.0, T_FAR, &list);
    var radiance = frame.background;
    var k = list.count;
    while (k > 0u) {
        k = k - 1u;
        // A camera inside a particle sees only the part of its chord in front of it.
        let t1 = list.t_exit[k];
        if (frame.lit == 1u && k < frame.n_exact) {
            radiance = lit_particle(ray, list.index[k], list.t_enter[k], t1, radiance);
        } else {
            let t0 = max(list.t_enter[k], 0.0);
            radiance = composite_emission(particles[list.index[k]], t1 - t0, radiance);
        }
    }
    return radiance;
}

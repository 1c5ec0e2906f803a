// Method `thesis` (docs/design.md §4, thesis chapter 5): the particles a camera ray crosses, sorted by
// entry and composited one particle at a time (overlaps ignored). The first `n_exact` particles
// from the eye use the lit model (docs/design.md §2, thesis eq. 4.17) with `samples` midpoint-rule
// samples along their chord and one shadow ray per sample per light (`lit_source`: the emission
// model along the shadow ray, the light as background); the rest, and every particle of an
// emission-model scene, use the emission model's closed form.
//
// Back-to-front compositing L = L_behind·T_i + S_i unrolls to L = Σ_i P_i·S_i + P·L_bg, with
// P_i = Π_{j<i} T_j the transmittance in front of particle i: the same sum, evaluated front to
// back, so that the lit samples can be spread over several passes (frame.pair_begin/pair_end,
// see src/approx/dispatch.rs) and each pass adds its share.

// Σ over samples j in [j_begin, j_end) of Q(x_j)·σ·e^{−σ(t_j − t0)}·Δt, t_j = t0 + (j + ½)Δt,
// Δt = (t1 − t0)/samples: the midpoint rule for ∫ Q·σ·T dt (the σ factor of docs/design.md §8).
fn lit_samples(ray: Ray, p: Particle, t0: f32, t1: f32, j_begin: u32, j_end: u32) -> vec3<f32> {
    let n = max(method_param(PARAM_SAMPLES), 1u);
    let dt = (t1 - t0) / f32(n);
    var sum = vec3<f32>(0.0);
    for (var j = j_begin; j < j_end; j = j + 1u) {
        count_iteration();
        let t = t0 + (f32(j) + 0.5) * dt;
        let weight = p.sigma * exp(-p.sigma * (t - t0)) * dt;
        sum = sum + lit_source(ray_at(ray, t)) * weight;
    }
    return sum;
}

fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    collect_hits(ray, 0.0, T_FAR, &camera_hits);
    let first_pass = frame.pair_begin == 0u;
    let samples = max(method_param(PARAM_SAMPLES), 1u);
    var n_lit = 0u;
    if (frame.lit == 1u) {
        n_lit = min(method_param(PARAM_N_EXACT), camera_hits.count);
    }
    var radiance = vec3<f32>(0.0);
    // P_i, the transmittance in front of the particle at hand.
    var front = 1.0;
    for (var k = 0u; k < camera_hits.count; k = k + 1u) {
        count_iteration();
        let index = camera_hits.index[k];
        let p = particles[index];
        let t_enter = camera_hits.t_enter[k];
        // A camera inside a particle sees only the part of its chord in front of it.
        let t0 = max(t_enter, 0.0);
        let t1 = camera_hits.t_exit[k];
        let transmittance = particle_transmittance(p.sigma, t1 - t0);
        if (k < n_lit) {
            if (p.sigma < 0.0) {
                // Θmax = 1 has no midpoint rule (every weight is ∞·0): the integral's limit.
                if (first_pass) {
                    radiance = radiance + front * lit_opaque_surface(ray, index, t0, t_enter > 0.0);
                }
            } else {
                // This particle's samples are the pairs [k·samples, (k+1)·samples).
                let base = k * samples;
                let lo = max(frame.pair_begin, base);
                let hi = min(frame.pair_end, base + samples);
                if (lo < hi) {
                    radiance = radiance + front * lit_samples(ray, p, t0, t1, lo - base, hi - base);
                }
                if (base + samples > frame.pair_end) {
                    pixel_more_work = true;
                }
            }
        } else if (first_pass) {
            radiance = radiance + front * p.color * (1.0 - transmittance);
        }
        front = front * transmittance;
        if (front <= 0.0) {
            break;
        }
    }
    if (first_pass) {
        radiance = radiance + front * frame.background;
    }
    return radiance;
}

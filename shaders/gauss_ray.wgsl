// Method `gauss-ray` (docs/design.md §4): 3D Gaussian ray tracing (3DGRT, Moenne-Loccoz et al.
// 2024). The BVH and the shapes are the Gaussians' 3-σ ellipsoids (GAUSSIAN_TRACE_SIGMAS; pgt
// widens them before the upload); every Gaussian whose 3-σ ellipsoid the ray crosses
// contributes α = min(0.99, o·exp(−½m*²)) at the depth t* of its maximum response along the
// ray (m* the Mahalanobis distance there), the hits blended front to back in order of t* and
// the ray stopped at the first hit that would take the transmittance below 1e-4 (that hit not
// added, as splat does). A ray keeps its MAX_HITS nearest hits by entry (an overflow is
// counted) and orders them by t*, as sorted-blend orders its hits by centre depth.

// Slots of camera_hits in order of t* (ties: lower particle index), and their t* and α.
var<private> ray_order: array<u32, MAX_HITS>;
var<private> ray_t_star: array<f32, MAX_HITS>;
var<private> ray_alpha: array<f32, MAX_HITS>;

fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    collect_hits(ray, 0.0, T_FAR, &camera_hits);
    let n = camera_hits.count;
    for (var k = 0u; k < n; k = k + 1u) {
        count_iteration();
        let index = camera_hits.index[k];
        let p = particles[index];
        let peak = gaussian_peak(ray, p, GAUSSIAN_TRACE_SIGMAS);
        ray_t_star[k] = peak.t_star;
        ray_alpha[k] = min(SPLAT_ALPHA_MAX, p.opacity * exp(-0.5 * peak.m * peak.m));
        // Insertion sort of the slots by t*.
        var slot = k;
        loop {
            if (slot == 0u) {
                break;
            }
            count_iteration();
            let prev = ray_order[slot - 1u];
            let prev_index = camera_hits.index[prev];
            if (ray_t_star[prev] < peak.t_star || (ray_t_star[prev] == peak.t_star && prev_index < index)) {
                break;
            }
            ray_order[slot] = prev;
            slot = slot - 1u;
        }
        ray_order[slot] = k;
    }
    var radiance = vec3<f32>(0.0);
    var transmittance = 1.0;
    for (var k = 0u; k < n; k = k + 1u) {
        count_iteration();
        let h = ray_order[k];
        let alpha = ray_alpha[h];
        let next = transmittance * (1.0 - alpha);
        if (next < SPLAT_T_MIN) {
            break;
        }
        radiance = radiance + particles[camera_hits.index[h]].color * (alpha * transmittance);
        transmittance = next;
    }
    return radiance + transmittance * frame.background;
}

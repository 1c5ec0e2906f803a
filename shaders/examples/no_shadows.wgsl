// Example user method for `pgt approx SCENE --shader shaders/examples/no_shadows.wgsl`
// (docs/user-shaders.md): no shadow rays at all. Each particle's source is the lit model with
// every *other* particle ignored: the light reaches the particle's centre through its own gas
// only (one radius, in closed form), Q = w·Σ_l [E_l·T_r + C·(1 − T_r)], T_r = e^{−σr}.
// Composited back to front with the emission model's closed form.
fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    collect_hits(ray, 0.0, T_FAR, &camera_hits);
    var radiance = frame.background;
    var k = camera_hits.count;
    while (k > 0u) {
        k = k - 1u;
        let p = particles[camera_hits.index[k]];
        var q = vec3<f32>(0.0);
        let t_own = particle_transmittance(p.sigma, p.radius);
        for (var l = 0u; l < frame.light_count; l = l + 1u) {
            let inc = light_incident(lights[l], p.center);
            if (inc.valid) {
                q = q + inc.irradiance * t_own + p.color * (1.0 - t_own);
            }
        }
        q = frame.light_weight * q;
        let length = camera_hits.t_exit[k] - max(camera_hits.t_enter[k], 0.0);
        let t = particle_transmittance(p.sigma, length);
        radiance = radiance * t + q * (1.0 - t);
    }
    return radiance;
}

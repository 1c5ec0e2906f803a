// Example user method for `pgt approx SCENE --shader shaders/examples/centre_shadow.wgsl`
// (docs/user-shaders.md): every particle is lit as a whole by the lit model's source evaluated
// at its centre only — one shadow ray per particle per light instead of one per sample — and
// composited back to front with the emission model's closed form using that colour:
// L = L_behind·T + Q(centre)·(1 − T). Cheap, and wrong where light varies across a particle.
fn shade(ray: Ray, pixel: vec2<u32>) -> vec3<f32> {
    collect_hits(ray, 0.0, T_FAR, &camera_hits);
    var radiance = frame.background;
    var k = camera_hits.count;
    while (k > 0u) {
        k = k - 1u;
        let p = particles[camera_hits.index[k]];
        let length = camera_hits.t_exit[k] - max(camera_hits.t_enter[k], 0.0);
        let t = particle_transmittance(p.sigma, length);
        let q = lit_source(p.center);
        radiance = radiance * t + q * (1.0 - t);
    }
    return radiance;
}

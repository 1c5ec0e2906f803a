// pgt entry point, appended after the method file: one invocation per pixel, one ray through
// the pixel centre (DESIGN.md §1), the method's `shade`, the result into `output`.
@compute @workgroup_size(8, 8, 1)
fn pgt_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= frame.width || gid.y >= frame.height) {
        return;
    }
    let pixel = gid.xy;
    let radiance = shade(camera_ray(pixel), pixel);
    output[gid.y * frame.width + gid.x] = vec4<f32>(radiance, 1.0);
    if (pixel_overflowed) {
        atomicAdd(&stats.hit_overflows, 1u);
    }
}

// pgt entry point, appended after the method file: one invocation per pixel of the band
// [row_begin, row_begin + row_count) of the image, one ray through the pixel centre
// (docs/design.md §1), the method's `shade`, the result into `output` (which holds the band only;
// pass 0 writes, later passes of a multi-pass method add), and the counters of `stats`.
@compute @workgroup_size(WORKGROUP_SIDE, WORKGROUP_SIDE, 1)
fn pgt_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= frame.width || gid.y >= frame.row_count) {
        return;
    }
    let pixel = vec2<u32>(gid.x, frame.row_begin + gid.y);
    let radiance = shade(camera_ray(pixel), pixel);
    let i = gid.y * frame.width + gid.x;
    if (frame.pair_begin == 0u) {
        output[i] = vec4<f32>(radiance, 1.0);
    } else {
        output[i] = output[i] + vec4<f32>(radiance, 0.0);
    }
    if (pixel_overflowed) {
        atomicAdd(&stats.hit_overflows, 1u);
    }
    if (loop_iterations >= LOOP_LIMIT_REPORT) {
        atomicAdd(&stats.loop_limited, 1u);
    }
    atomicMax(&stats.max_loop_iterations, loop_iterations);
    if (pixel_more_work) {
        atomicAdd(&stats.more_work, 1u);
    }
}

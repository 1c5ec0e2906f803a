// The nearest events along a ray, a batch at a time (docs/design.md §4 "ever", "gauss-ray",
// §12): one BVH traversal keeps the `capacity` nearest events beyond a cursor (t_after,
// key_after), in order of (t, key) — EVER's and 3DGRT's k nearest hits per trace, the GPU
// reference's batch. The program takes them in order and traverses again from the last one it
// took. Nearer children are visited first, so the batch fills early and prunes the boxes that
// start beyond its farthest event; which events the batch holds does not depend on the order.
//
// Shared by shaders/ever.wgsl, gauss_ray.wgsl (f32) and reference_emission.wgsl (f64). A
// program that includes this file declares
//     alias EventT = f32 or f64;       the type of t and of the ray
//     alias EventValue = …;            what an event carries besides (t, key)
//     const EVENT_CAPACITY: u32;       the most events a batch holds
//     const EVENT_T_FAR: EventT;       beyond every event
//     const EVENT_IN_BOX: bool;        whether every event of a particle lies on the ray's chord
//                                      of its BVH box (then boxes before the cursor or beyond
//                                      a full batch are pruned; else every box the ray meets
//                                      in front of the eye is visited)
// and defines the work at a leaf:
//     fn event_visit(ray: EventRay, i: u32, t_after: EventT, key_after: u32, capacity: u32)
// which puts particle i's events after (t_after, key_after) into the batch with event_insert.

// A ray as the traversal sees it: the origin of the particles' coordinates, the origin of the
// BVH boxes' coordinates (camera-relative; the same point), the unit direction and its
// component-wise inverse (zero components replaced by a tiny value of their sign).
struct EventRay {
    origin: vec3<EventT>,
    box_origin: vec3<EventT>,
    direction: vec3<EventT>,
    inv: vec3<EventT>,
}

// The batch: events sorted by (t, key), each with its value.
var<private> events_t: array<EventT, EVENT_CAPACITY>;
var<private> events_key: array<u32, EVENT_CAPACITY>;
var<private> events_value: array<EventValue, EVENT_CAPACITY>;
var<private> events_count: u32;

// event_before(t_a, key_a, t_b, key_b), whether event (t_a, key_a) comes before (t_b, key_b),
// and event_insert(t, key, value, capacity), which inserts an event into the batch of
// `capacity` (at most EVENT_CAPACITY) keeping the nearest, are generated after this file from
// the order and the sorted insert that the prelude's hit lists also use; so is
// event_box_span, the prelude's slab test in EventT (src/approx/wgsl_generic.rs).

// Slab test of a BVH node's box: where the ray enters it within [t_min, t_max] (t_min ≥ 0), or
// −1 where it does not.
fn event_box_entry(ray: EventRay, node: BvhNode, t_min: EventT, t_max: EventT) -> EventT {
    let span = event_box_span(ray.box_origin, ray.inv, node.min, node.max, t_min, t_max);
    return select(EventT(-1.0), span.x, span.x <= span.y);
}

// One traversal: the batch becomes the `capacity` nearest events after (t_after, key_after) of
// the scene's `particle_count` particles.
fn events_collect(ray: EventRay, t_after: EventT, key_after: u32, capacity: u32, particle_count: u32) {
    events_count = 0u;
    if (particle_count == 0u) {
        return;
    }
    let t_min = select(EventT(0.0), max(t_after, EventT(0.0)), EVENT_IN_BOX);
    traversal_stack[0] = 0u;
    var sp = 1u;
    while (sp > 0u) {
        count_iteration();
        sp = sp - 1u;
        let node = nodes[traversal_stack[sp]];
        // A full batch prunes boxes that start beyond its farthest event.
        var t_max = EVENT_T_FAR;
        if (EVENT_IN_BOX && events_count >= capacity) {
            t_max = events_t[capacity - 1u];
        }
        if (event_box_entry(ray, node, t_min, t_max) < EventT(0.0)) {
            continue;
        }
        if (node.count > 0u) {
            for (var k = 0u; k < node.count; k = k + 1u) {
                count_iteration();
                event_visit(ray, leaf_indices[node.first + k], t_after, key_after, capacity);
            }
        } else if (sp + 2u <= STACK_SIZE) {
            let t_a = event_box_entry(ray, nodes[node.first], t_min, t_max);
            let t_b = event_box_entry(ray, nodes[node.first + 1u], t_min, t_max);
            // The nearer child is pushed last, to be popped first; a child the ray misses is
            // not pushed.
            let a_first = t_b < EventT(0.0) || (t_a >= EventT(0.0) && t_a <= t_b);
            let near = select(node.first + 1u, node.first, a_first);
            let far = select(node.first, node.first + 1u, a_first);
            if (min(t_a, t_b) >= EventT(0.0)) {
                traversal_stack[sp] = far;
                sp = sp + 1u;
            }
            if (max(t_a, t_b) >= EventT(0.0)) {
                traversal_stack[sp] = near;
                sp = sp + 1u;
            }
        }
    }
}

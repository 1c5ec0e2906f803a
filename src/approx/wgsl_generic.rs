//! The WGSL functions that programs need for different types and storage, written once
//! (docs/design.md §4 "The program"). WGSL has no generics, so the sorted insert of the k
//! nearest hits, its order and the slab test of a BVH box are templates here, instantiated in
//! f32 over a hit list for the prelude's traversal (`shaders/common.wgsl`: `hit_before`,
//! `hit_list_sorted_insert`, `box_span`) and in the program's `EventT` over the batch of
//! `shaders/nearest_events.wgsl` (`event_before`, `event_insert`, `event_box_span`; f32 in
//! `ever` and `gauss-ray`, f64 in the GPU reference). A template's `$NAME`s are replaced by
//! [`instantiate`].

/// `fn $BEFORE(t_a, key_a, t_b, key_b) -> bool`: whether entry (t_a, key_a) comes before
/// (t_b, key_b), by t and then key (the total order of a sorted list).
const ORDER: &str = "
// Whether entry (t_a, key_a) comes before (t_b, key_b): by t, then by key.
fn $BEFORE(t_a: $T, key_a: u32, t_b: $T, key_b: u32) -> bool {
    return t_a < t_b || (t_a == t_b && key_a < key_b);
}
";

/// `fn $INSERT($LIST_PARAM t, key, value, capacity)`: inserts an entry into a list sorted by
/// `$BEFORE`, by insertion sort; a list holding `capacity` entries keeps its nearest ones
/// (running `$WHEN_FULL` first). `$COUNT`, `$TS`, `$KEYS` and `$VALUES` are the list's count
/// and arrays.
const SORTED_INSERT: &str = "
// Inserts (t, key, value) by insertion sort into a list of at most `capacity` entries sorted by
// $BEFORE; a full list keeps its nearest entries.
fn $INSERT($LIST_PARAMt: $T, key: u32, value: $VALUE, capacity: u32) {
    var slot = $COUNT;
    if (slot >= capacity) {$WHEN_FULL
        let last = capacity - 1u;
        if (!$BEFORE(t, key, $TS[last], $KEYS[last])) {
            return;
        }
        slot = last;
    } else {
        $COUNT = slot + 1u;
    }
    loop {
        count_iteration();
        if (slot == 0u || !$BEFORE(t, key, $TS[slot - 1u], $KEYS[slot - 1u])) {
            break;
        }
        $TS[slot] = $TS[slot - 1u];
        $KEYS[slot] = $KEYS[slot - 1u];
        $VALUES[slot] = $VALUES[slot - 1u];
        slot = slot - 1u;
    }
    $TS[slot] = t;
    $KEYS[slot] = key;
    $VALUES[slot] = value;
}
";

/// `fn $BOX_SPAN(origin, inv, box_min, box_max, t_min, t_max) -> vec2`: the slab test.
const BOX_SPAN: &str = "
// Slab test of a BVH box (f32 corners): where the ray (origin, component-wise inverse
// direction) enters and leaves it, clipped to [t_min, t_max]. It meets the box there where the
// entry is not beyond the exit.
fn $BOX_SPAN(origin: vec3<$T>, inv: vec3<$T>, box_min: vec3<f32>, box_max: vec3<f32>, t_min: $T, t_max: $T) -> vec2<$T> {
    let t0 = (vec3<$T>(box_min) - origin) * inv;
    let t1 = (vec3<$T>(box_max) - origin) * inv;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    return vec2<$T>(max(max(lo.x, lo.y), max(lo.z, t_min)), min(min(hi.x, hi.y), min(hi.z, t_max)));
}
";

/// `template` with each `$NAME` of `names` replaced by its text, longest names first (so that
/// `$T` does not eat `$TS`).
///
/// # Panics
/// Where a `$` is left: a template and its instantiation disagree, pgt's bug.
pub fn instantiate(template: &str, names: &[(&str, &str)]) -> String {
    let mut names = names.to_vec();
    names.sort_by_key(|(name, _)| std::cmp::Reverse(name.len()));
    let mut out = template.to_string();
    for (name, text) in names {
        out = out.replace(name, text);
    }
    assert!(!out.contains('$'), "a template name is left in:\n{out}");
    out
}

/// The prelude's instances (`shaders/common.wgsl`), in f32: `hit_before`,
/// `hit_list_sorted_insert` over a `HitList` (t = entry, key = particle index, value = exit;
/// a full list is flagged as overflowed, and so is the pixel) and `box_span`.
pub fn prelude_functions() -> String {
    let order = [("$BEFORE", "hit_before"), ("$T", "f32")];
    let insert = [
        ("$INSERT", "hit_list_sorted_insert"),
        ("$LIST_PARAM", "list: ptr<private, HitList>, "),
        ("$VALUE", "f32"),
        ("$COUNT", "(*list).count"),
        ("$TS", "(*list).t_enter"),
        ("$KEYS", "(*list).index"),
        ("$VALUES", "(*list).t_exit"),
        (
            "$WHEN_FULL",
            "\n        (*list).overflowed = true;\n        pixel_overflowed = true;",
        ),
    ];
    generated(&[
        instantiate(ORDER, &order),
        instantiate(SORTED_INSERT, &[&order[..], &insert[..]].concat()),
        instantiate(BOX_SPAN, &[("$BOX_SPAN", "box_span"), ("$T", "f32")]),
    ])
}

/// The instances of `shaders/nearest_events.wgsl`, in the program's `EventT`: `event_before`,
/// `event_insert` over the batch (`events_count`, `events_t`, `events_key`, `events_value`)
/// and `event_box_span`.
pub fn nearest_events_functions() -> String {
    let order = [("$BEFORE", "event_before"), ("$T", "EventT")];
    let insert = [
        ("$INSERT", "event_insert"),
        ("$LIST_PARAM", ""),
        ("$VALUE", "EventValue"),
        ("$COUNT", "events_count"),
        ("$TS", "events_t"),
        ("$KEYS", "events_key"),
        ("$VALUES", "events_value"),
        ("$WHEN_FULL", ""),
    ];
    generated(&[
        instantiate(ORDER, &order),
        instantiate(SORTED_INSERT, &[&order[..], &insert[..]].concat()),
        instantiate(
            BOX_SPAN,
            &[("$BOX_SPAN", "event_box_span"), ("$T", "EventT")],
        ),
    ])
}

fn generated(functions: &[String]) -> String {
    let mut out = String::from(
        "\n// Generated by pgt from the templates of src/approx/wgsl_generic.rs (docs there).\n",
    );
    for f in functions {
        out.push_str(f);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instances_leave_no_template_name() {
        for text in [prelude_functions(), nearest_events_functions()] {
            assert!(!text.contains('$'), "{text}");
        }
    }

    #[test]
    fn longer_names_are_replaced_before_their_prefixes() {
        assert_eq!(instantiate("$TS[$T]", &[("$T", "a"), ("$TS", "b")]), "b[a]");
    }

    #[test]
    fn the_event_insert_has_the_signature_nearest_events_documents() {
        let text = nearest_events_functions();
        assert!(text
            .contains("fn event_insert(t: EventT, key: u32, value: EventValue, capacity: u32) {"));
        assert!(text.contains(
            "fn event_before(t_a: EventT, key_a: u32, t_b: EventT, key_b: u32) -> bool {"
        ));
    }
}

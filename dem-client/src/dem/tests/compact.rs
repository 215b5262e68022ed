//! The compact contact passes of a large world: the same bits as through the bodies.

use super::*;

/// A world large enough for the compact contact passes (a copy of the spheres' motion for the
/// pair pass; the gather adding only the touching pairs where few touch) steps to the same bits
/// as the same world through the bodies, adding every pair: wet and dry (the batched law).
#[test]
fn a_large_world_steps_the_same_from_its_compact_arrays() {
    let n = 16;
    assert!(
        n * n * n >= crate::dem::world::COMPACT_FROM,
        "the bed is large enough"
    );
    for wet in [true, false] {
        let mut compact = bed(n, wet);
        let mut plain = bed(n, wet);
        plain.compact_from = usize::MAX;
        let mut few_touch = false;
        for _ in 0..20 {
            compact.advance(10);
            plain.advance(10);
            assert_eq!(compact.contact_count(), plain.contact_count(), "wet {wet}");
            let touching = compact.contact_count();
            few_touch |= touching > 0 && 2 * touching < compact.pair_count();
            for (a, b) in compact.bodies.iter().zip(&plain.bodies) {
                let (a, b, id) = ((a.x, a.v, a.w, a.f, a.t), (b.x, b.v, b.w, b.f, b.t), a.id);
                assert_eq!(a, b, "sphere {id}, wet {wet}");
            }
        }
        let (touching, pairs) = (compact.contact_count(), compact.pair_count());
        assert!(
            few_touch,
            "wet {wet}: the gather never skipped: {touching} contacts, {pairs} pairs"
        );
    }
}

//! The neighbour lists: contact histories carried through a rebuild.

use super::*;

/// Two spheres pressed together and sliding past each other with friction (their tangential
/// spring loaded); then a sphere is inserted (a neighbour-list build) after the two changed places
/// in the list: the spring's history follows them (found by their ids, its sign turned with their
/// order), and they go on as when they kept their places.
#[test]
fn a_contact_history_follows_its_spheres_through_a_rebuild_when_they_change_places() {
    let world = || {
        let mut bodies = vec![
            ball(0, [0.01, 0.01, 0.01], [0.0, 0.01, 0.0]),
            ball(1, [0.01 + 2.0 * R - 2e-6, 0.01, 0.01], [0.0, -0.01, 0.0]),
        ];
        bodies[0].f_ext = V3::new(2e-3, 0.0, 0.0);
        bodies[1].f_ext = V3::new(-2e-3, 0.0, 0.0);
        let l = law(
            NormalLaw::Hertz,
            TangentialLaw::History,
            Switches::LIGGGHTS,
            Linear::default(),
        );
        World::new(
            bodies,
            vec![],
            l,
            &[material(0.5, 0.5)],
            V3::zeros(),
            1e-6,
            0.5 * R,
        )
    };
    let (mut kept, mut swapped) = (world(), world());
    for w in [&mut kept, &mut swapped] {
        w.advance(300);
    }
    swapped.bodies.swap(0, 1);
    let far = ball(2, [0.05, 0.05, 0.05], [0.0; 3]);
    kept.insert(far);
    swapped.insert(far);
    kept.advance(300);
    swapped.advance(300);
    for (a, b) in [(0, 1), (1, 0)] {
        let (p, q) = (kept.bodies[a], swapped.bodies[b]);
        assert_eq!(p.id, q.id);
        assert_near(p.v, q.v, 1e-12, "velocity");
        assert_near(p.w, q.w, 1e-9, "spin");
        assert_near(p.f, q.f, 1e-12, "contact force");
    }
    assert!(
        kept.bodies[0].w.norm() > 1.0,
        "the spring turns them: {}",
        kept.bodies[0].w
    );
}

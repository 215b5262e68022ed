//! What the immersed moving boundary refuses (particles too large for an axis or the box index,
//! by id) and counts (covered cells beyond the room of their list).

use super::*;

#[test]
fn a_sphere_wider_than_a_periodic_axis_is_refused() {
    let setup = Setup::new([12, 5, 10], [Face::Periodic; 6], 0.7, Operator::Bgk);
    let mut lattice = coupled(&setup);
    let sphere = SolidParticle {
        position: [6.0, 2.5, 5.0],
        radius: 2.3,
        ..Default::default()
    };
    let err = lattice.step_coupled(&[sphere]).unwrap_err();
    assert!(
        err.contains("particle 0") && err.contains("periodic y axis of 5 cells"),
        "{err}"
    );
}

#[test]
fn a_particle_too_large_is_refused_by_id_in_any_chunk() {
    let setup = Setup::new([40, 36, 32], [Face::Periodic; 6], 0.7, Operator::Bgk);
    let mut lattice = coupled(&setup);
    let mut particles = many_particles(0.0);
    particles[2 * CHUNK + 7].radius = 17.0;
    let err = lattice.step_coupled(&particles).unwrap_err();
    let id = format!("particle {}:", 2 * CHUNK + 7);
    assert!(err.contains(&id) && err.contains("periodic z axis"), "{err}");
}

#[test]
fn a_particle_too_large_for_the_box_index_is_refused_by_id() {
    let setup = Setup::new([8; 3], [Face::Periodic; 6], 0.7, Operator::Bgk);
    let mut lattice = coupled(&setup);
    let mut particles = two_particles(0.0);
    particles[1].radius = 128.0;
    let err = lattice.step_coupled(&particles).unwrap_err();
    assert!(err.contains("particle 1"), "{err}");
}

/// Covered cells beyond the room of the list of covered cells are counted (the run stops on
/// them), none when the list has room.
#[test]
fn covered_cells_beyond_the_list_are_counted() {
    let setup = Setup::new([12; 3], [Face::Periodic; 6], 0.7, Operator::Bgk);
    for covered_cells in [CoveredCells::Redo, CoveredCells::Skip] {
        let unlisted = |cap: Option<u64>| {
            let options = ImbOptions {
                covered_cells,
                ..ImbOptions::default()
            };
            let mut lattice =
                GpuLattice::new(gpu(), setup.clone(), Health::default(), Some(options)).unwrap();
            if let Some(cells) = cap {
                lattice.cap_covered_cells(cells);
            }
            lattice.step_coupled(&two_particles(0.0)).unwrap();
            let left = lattice.cover_words_left();
            (
                lattice.lost_covers().unlisted,
                lattice.covered_cell_capacity(),
                left,
            )
        };
        assert_eq!(unlisted(None).0, 0);
        let (missing, room, left) = unlisted(Some(16));
        assert_eq!(room, 16);
        assert!(
            missing > 16,
            "{covered_cells:?}: {missing} covered cells beyond a list of 16"
        );
        // Skip: only listed cells are masked (and unmasked after the fluid kernels).
        assert_eq!(left, 0, "{covered_cells:?}: cover words left for the next step");
    }
}

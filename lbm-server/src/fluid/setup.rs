//! A scene's lattice for the kernels: its faces, operator and solid cells ([`setup_of`]), the
//! warning for a lattice near its stability limits, and the health check's limits.

use crate::lbm::geometry::{tau_minus, Face, Operator, Setup};
use crate::lbm::gpu::Health;
use crate::lbm::mrt::Rates;
use crate::terminal::Warning;
use scene::lattice::{mach_limit, CollisionOperator, LatticeFace, LatticeUnits};

/// The lattice of a scene, for the kernels.
pub fn setup_of(units: &LatticeUnits) -> Setup {
    let face = |f: &LatticeFace| match *f {
        LatticeFace::Periodic => Face::Periodic,
        LatticeFace::Wall => Face::Wall,
        LatticeFace::MovingWall(u) => Face::MovingWall(u),
        LatticeFace::VelocityInlet(u) => Face::VelocityInlet(u),
        LatticeFace::PressureOutlet(rho) => Face::PressureOutlet(rho),
    };
    let operator = match units.operator {
        CollisionOperator::Bgk => Operator::Bgk,
        CollisionOperator::Trt => Operator::Trt { magic: units.magic },
        CollisionOperator::Mrt => {
            let r = units.mrt;
            Operator::Mrt {
                rates: Rates {
                    nu: 1.0 / units.tau,
                    e: r.e,
                    epsilon: r.epsilon,
                    q: r.q,
                    pi: r.pi,
                    m: r.m,
                },
            }
        }
    };
    let mut setup = Setup::new(units.n, units.faces.map(|f| face(&f)), units.tau, operator);
    setup.solid = units.solid.clone();
    setup.force = units.force;
    setup.ramp_steps = units.ramp_steps;
    setup.storage = units.storage;
    setup.kernel = units.kernel.unwrap_or_default();
    setup
}

/// Below these taus TRT (magic 3/16, 1/4 or 0.01) blew up where BGK or MRT held
/// (validation/lbm/REPORT.md, "Stability near tau = 1/2", a sphere of 8 cells held in a stream of
/// 0.08): with a velocity inlet (at the inlet, from tau 0.5192; held at 0.538 in the sphere-drag
/// section), and with particles (at the sphere in a periodic box, from tau 0.5048; held at 0.5096).
const TRT_INLET_TAU: f64 = 0.53;
const TRT_PARTICLES_TAU: f64 = 0.51;
/// Below this tau BGK, and TRT with tau- at most [`BOUNDED_TAU_MINUS`] (`lattice.max_tau_minus`),
/// near the taus where they blew up in that table: both held the sphere to 0.5048 with inlet and
/// outlet and blew up at 0.5024; both blew up in the fluidized bed at 0.5034. BGK was refused
/// below it before that table was made.
const BGK_LIKE_TAU: f64 = 0.51;
const BOUNDED_TAU_MINUS: f64 = 1.0;

/// The warning for a lattice at a tau near where its operator was measured to blow up: TRT with
/// a velocity inlet below [`TRT_INLET_TAU`], with `particles` below [`TRT_PARTICLES_TAU`]; BGK,
/// or TRT with a bounded tau-, with an inlet or particles below [`BGK_LIKE_TAU`].
pub fn stability_warning(units: &LatticeUnits, particles: bool) -> Option<Warning> {
    let (name, measured, advice) = where_it_blew_up(units, particles)?;
    let tau = units.tau;
    let tau_minus = tau_minus(units.magic, tau);
    let short_name = match units.operator {
        CollisionOperator::Trt => format!("TRT (tau- = {tau_minus:.2})"),
        _ => "BGK".to_string(),
    };
    Some(Warning {
        brief: format!(
            "lattice tau = {tau:.4} with {short_name}: near the taus where it blew up; consider \
             lattice.operator = \"mrt\"{advice}"
        ),
        full: format!(
            "lattice tau = {tau:.4} with {name}. A sphere of 8 cells held in a stream \
             (validation/lbm/REPORT.md, \"Stability near tau = 1/2\") {measured}; consider \
             lattice.operator = \"mrt\"{advice}"
        ),
    })
}

/// Where the lattice's operator at its tau is near a measured blow-up (`particles` in it or
/// not): the operator's name, what was measured, and the advice beyond MRT; None where it is not.
fn where_it_blew_up(units: &LatticeUnits, particles: bool) -> Option<(String, &'static str, &'static str)> {
    let inlet = units
        .faces
        .iter()
        .any(|f| matches!(f, LatticeFace::VelocityInlet(_)));
    let tau = units.tau;
    let tau_minus = tau_minus(units.magic, tau);
    let found = match units.operator {
        CollisionOperator::Trt if tau_minus <= BOUNDED_TAU_MINUS + 1e-9 => (
            format!("TRT with tau- = {tau_minus:.2}"),
            if (inlet || particles) && tau < BGK_LIKE_TAU {
                "with tau- <= 1 held to tau 0.5048 and blew up at 0.5024, in a periodic box and \
                 between inlet and outlet alike, where MRT held; a fluidized bed of 216 grains \
                 between walls (validation/imb/FLUIDIZED_BED.md) blew up at tau 0.5034 with both \
                 TRT and BGK, where MRT ran"
            } else {
                return None;
            },
            "",
        ),
        CollisionOperator::Trt => (
            format!(
                "TRT: its antisymmetric modes relax with tau- = 1/2 + lattice.magic / (tau - 1/2) \
                 = {tau_minus:.1}, hardly at all"
            ),
            if inlet && tau < TRT_INLET_TAU {
                "blew up at the velocity inlet from tau 0.5192 (magic 3/16 and 1/4; held at \
                 0.538), where MRT held to tau 0.5024"
            } else if particles && tau < TRT_PARTICLES_TAU {
                "blew up at the sphere in a periodic box from tau 0.5048 (magic 3/16, 1/4 and \
                 0.01; held at 0.5096), where BGK and MRT held to tau 0.5024"
            } else {
                return None;
            },
            " or lattice.max_tau_minus = 1",
        ),
        CollisionOperator::Bgk if (inlet || particles) && tau < BGK_LIKE_TAU => (
            "BGK".to_string(),
            "held to tau 0.5024 in a periodic box and to 0.5048 between inlet and outlet, where \
             it blew up at 0.5024 and MRT held; a fluidized bed of 216 grains between walls \
             (validation/imb/FLUIDIZED_BED.md) blew up at tau 0.5034 with BGK, where MRT ran",
            "",
        ),
        _ => return None,
    };
    Some(found)
}

/// Health limits: twice the operator's Mach limit, and a density deviation of 50%.
pub fn health_of(units: &LatticeUnits) -> Health {
    Health {
        max_speed: 2.0 * mach_limit(units.operator) / 3f64.sqrt(),
        max_density_deviation: 0.5,
    }
}

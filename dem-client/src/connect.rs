//! `dem-client connect`: the DEM side of the lockstep loop.

use crate::standin::Particles;
use protocol::transport::LinkOptions;
use protocol::{DemLink, Hello, LinkError, ParticleReply, Physics, StepFlags, StepHeader, Units, Welcome};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

#[derive(clap::Args)]
pub struct ConnectArgs {
    /// Run name printed by lbm-server ("DEM service: NAME").
    #[arg(long)]
    service: String,
    /// Scene file holding the particles (default: the built-in default scene).
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Longest wait for a live but silent fluid server [s].
    #[arg(long, default_value_t = 10.0)]
    timeout: f64,
    /// Testing: announce this protocol version instead of ours.
    #[arg(long, hide = true)]
    protocol_version: Option<u32>,
    /// Testing: insert or remove one particle every step.
    #[arg(long, hide = true)]
    churn: bool,
    /// Testing: send the wrong step index at this step.
    #[arg(long, hide = true)]
    skip_step: Option<u64>,
    /// Testing: stop answering (stay alive, silent) at this step.
    #[arg(long, hide = true)]
    stall_at: Option<u64>,
}

/// Deliberate misbehaviour, for the tests of the failure rules.
#[derive(Clone, Copy, Default)]
struct Faults {
    churn: bool,
    skip_step: Option<u64>,
    stall_at: Option<u64>,
}

/// Physics this side applies while the DEM is a stand-in.
const PHYSICS: u64 = Physics::GRAVITY | Physics::BALLISTIC_STANDIN;

pub fn main(args: ConnectArgs) -> ExitCode {
    let scene = match crate::scene_or_default(args.scene.as_ref()) {
        Ok(s) => s,
        Err(e) => {
            protocol::say!("dem-client: error: {e}");
            return ExitCode::from(2);
        }
    };
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        protocol::say!(
            "dem-client: error: --timeout = {} s: must be a finite number > 0",
            args.timeout
        );
        return ExitCode::from(2);
    }
    let interrupted = Arc::new(AtomicBool::new(false));
    let flag = interrupted.clone();
    if let Err(e) = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst)) {
        protocol::say!("dem-client: warning: cannot install the Ctrl-C handler: {e}");
    }
    let mut particles = Particles::from_scene(&scene);
    let mut hello = Hello::new(
        Units::SI,
        PHYSICS,
        particles.states.len(),
        &format!("dem-client {} (stand-in: ballistic)", env!("CARGO_PKG_VERSION")),
    );
    if let Some(v) = args.protocol_version {
        hello.version = v;
    }
    let options = LinkOptions {
        run: args.service.clone(),
        timeout: Duration::from_secs_f64(args.timeout),
    };
    let (link, welcome) = match DemLink::connect(options, hello) {
        Ok(ok) => ok,
        Err(e) => {
            protocol::say!("dem-client: error: {e}");
            return ExitCode::from(1);
        }
    };
    let mut last = None;
    let faults = Faults {
        churn: args.churn,
        skip_step: args.skip_step,
        stall_at: args.stall_at,
    };
    match step_loop(&link, &welcome, &mut particles, &interrupted, faults, &mut last) {
        Ok(steps) => {
            protocol::say!("dem-client: finished after {steps} steps (stand-in physics: ballistic)");
            ExitCode::SUCCESS
        }
        Err(e) => {
            let last = last.map_or("none".to_string(), |s: u64| s.to_string());
            protocol::say!("dem-client: error: {e}; last completed step: {last}");
            ExitCode::from(1)
        }
    }
}

/// Runs the lockstep loop; returns the number of completed steps.
fn step_loop(
    link: &DemLink,
    welcome: &Welcome,
    particles: &mut Particles,
    interrupted: &AtomicBool,
    faults: Faults,
    last: &mut Option<u64>,
) -> Result<u64, LinkError> {
    let domain = (welcome.domain_min, welcome.domain_max);
    let mut replies: Vec<ParticleReply> = Vec::new();
    for step in 0..welcome.steps {
        if faults.churn && step > 0 {
            particles.churn(step);
        }
        while faults.stall_at == Some(step) {
            std::thread::sleep(Duration::from_secs(1));
        }
        let stop = interrupted.load(Ordering::SeqCst);
        let flags = if stop { StepFlags::STOP } else { 0 };
        let sent_step = if faults.skip_step == Some(step) {
            step + 1
        } else {
            step
        };
        let header = StepHeader::new(sent_step, step as f64 * welcome.dt, particles.states.len(), flags);
        link.send_states(header, |i| particles.states[i])?;
        let received = link.receive_forces(step)?;
        replies.clear();
        replies.extend_from_slice(received.particles());
        check_ids(particles, &replies)?;
        let done = received.header().has(StepFlags::FINAL | StepFlags::STOP) || stop;
        drop(received);
        *last = Some(step);
        if done {
            return Ok(step + 1);
        }
        particles.advance(&replies, welcome.gravity, welcome.dt, domain);
    }
    Ok(welcome.steps)
}

/// The fluid must answer every particle, in order.
fn check_ids(particles: &Particles, replies: &[ParticleReply]) -> Result<(), LinkError> {
    let wrong = particles
        .states
        .iter()
        .zip(replies)
        .position(|(s, r)| s.id != r.id);
    if replies.len() != particles.states.len() || wrong.is_some() {
        return Err(LinkError::Ipc(format!(
            "the fluid's reply does not match the states sent (count {} vs {}, first wrong index {:?})",
            replies.len(),
            particles.states.len(),
            wrong
        )));
    }
    Ok(())
}

//! The iceoryx2 transport of `bench-link`: the DEM end times rounds over shared memory, the
//! fluid end (the peer) answers them.

use super::peer_process::{peer_timeout, PeerProcess};
use super::{reply_for, state, time_rounds, touch_replies, PeerArgs, Plan, RoundTrip, READY};
use protocol::transport::{new_run_name, LinkOptions};
use protocol::{DemLink, FluidLink, Hello, Physics, StepFlags, StepHeader, Units, Welcome};
use std::io::Write;

/// The DEM end of the iceoryx2 link.
struct IceoryxBench {
    link: DemLink,
    n: usize,
}

impl RoundTrip for IceoryxBench {
    fn round(&mut self, step: u64) -> Result<(), String> {
        let header = StepHeader::new(step, 0.0, self.n, 0);
        self.link
            .send_states(header, |i| state(i, step))
            .map_err(|e| e.to_string())?;
        let received = self.link.receive_forces(step).map_err(|e| e.to_string())?;
        touch_replies(received.particles(), self.n)
    }
}

/// Times `rounds` rounds of `n` particles over iceoryx2 against a spawned peer.
pub(super) fn measure_iceoryx2(plan: &Plan, n: usize, rounds: usize) -> Result<Vec<f64>, String> {
    let run = new_run_name();
    let result = run_iceoryx2(plan, &run, n, rounds);
    protocol::cleanup::remove_run(&run);
    result
}

fn run_iceoryx2(plan: &Plan, run: &str, n: usize, rounds: usize) -> Result<Vec<f64>, String> {
    let steps = (plan.warmup + rounds) as u64;
    let mut peer = PeerProcess::spawn(
        &plan.exe,
        &[
            "--service".into(),
            run.into(),
            "--capacity".into(),
            n.to_string(),
            "--steps".into(),
            steps.to_string(),
            "--timeout".into(),
            plan.timeout.as_secs_f64().to_string(),
        ],
    )?;
    peer.wait_ready()?;
    let options = LinkOptions {
        run: run.to_string(),
        timeout: plan.timeout,
    };
    let hello = Hello::new(Units::SI, Physics::BALLISTIC_STANDIN, n, "lbm-server bench-link");
    let (link, _welcome) = DemLink::connect(options, hello).map_err(|e| format!("iceoryx2: {e}"))?;
    let mut bench = IceoryxBench { link, n };
    let times = time_rounds(&mut bench, plan.warmup, rounds).map_err(|e| format!("iceoryx2: {e}"))?;
    // The STOP step ends the peer; the link stays open until it has read it and exited.
    let stop = StepHeader::new(steps, 0.0, 0, StepFlags::STOP);
    bench
        .link
        .send_states(stop, |i| state(i, steps))
        .map_err(|e| format!("iceoryx2: {e}"))?;
    peer.finish(plan.timeout)?;
    Ok(times)
}

/// The fluid end of the iceoryx2 link: `--steps` steps, then the benchmark's STOP.
pub(super) fn serve_iceoryx2(run: &str, args: &PeerArgs) -> Result<(), String> {
    let timeout = peer_timeout(args.timeout)?;
    let options = LinkOptions {
        run: run.to_string(),
        timeout,
    };
    let mut link = FluidLink::create(options, args.capacity).map_err(|e| e.to_string())?;
    announce_ready()?;
    let bench_pid = std::os::unix::process::parent_id();
    link.accept(Some(bench_pid), timeout, &|| false, |_hello| {
        let mut welcome = Welcome::accepted("lbm-server bench-link-peer");
        welcome.steps = args.steps;
        welcome.dt = 1.0;
        welcome
    })
    .map_err(|e| e.to_string())?;
    for step in 0..args.steps {
        let received = link.receive_states(step).map_err(|e| e.to_string())?;
        let states = received.particles();
        let header = StepHeader::new(step, received.header().time, states.len(), 0);
        link.send_forces(header, |i| reply_for(&states[i]))
            .map_err(|e| e.to_string())?;
    }
    let last = link.receive_states(args.steps).map_err(|e| e.to_string())?;
    if !last.header().has(StepFlags::STOP) {
        return Err(format!("step {} came without the STOP flag", args.steps));
    }
    Ok(())
}

/// Tells the benchmark process that the services exist.
fn announce_ready() -> Result<(), String> {
    let mut out = std::io::stdout().lock();
    writeln!(out, "{READY}")
        .and_then(|()| out.flush())
        .map_err(|e| format!("stdout: {e}"))
}

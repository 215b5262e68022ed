//! One coupled run in progress ([`Session`]): opened (the link, particles.csv, the fluid),
//! connected to the DEM side (started or announced, then the handshake), stepped in lockstep
//! (`lockstep.rs`), finished (the DEM ended, summary.json written).

use super::checkpointing::resume_refusal;
use super::counters::Counters;
use super::prepare::Prepared;
use super::summary::{PeerInfo, Summary};
use super::welcome::{welcome_for, yielded};
use super::{Ending, EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_INTERRUPTED};
use crate::checkpoint::Checkpoints;
use crate::coupled::FluidSide;
use crate::launch::{self, DemStart};
use crate::output::ParticleOutput;
use crate::parallel::Communicator;
use crate::terminal;
use protocol::transport::LinkOptions;
use protocol::{FluidLink, Hello, LinkError, Physics};
use std::process::Child;
use std::rc::Rc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

/// One run in progress.
pub(super) struct Session {
    pub(super) p: Prepared,
    pub(super) link: FluidLink,
    child: Option<Child>,
    pub(super) particles: ParticleOutput,
    pub(super) fluid: FluidSide,
    pub(super) interrupted: Arc<AtomicBool>,
    pub(super) peer: Option<PeerInfo>,
    pub(super) hello: Option<Hello>,
    /// Whether a reply carried FINAL or STOP: the DEM ends on its own and is given the time to.
    pub(super) told_to_end: bool,
    /// The steps completed and where the wall time went.
    pub(super) counters: Counters,
    /// The run's checkpoints, and whether it writes them (the DEM declares it can: Hello's
    /// CHECKPOINT capability).
    pub(super) checkpoints: Checkpoints,
    pub(super) checkpointing: bool,
    /// The run's first step (a resumed run's checkpoint's; else 0).
    pub(super) first_step: u64,
    /// Why a resumed run refused its DEM (it cannot checkpoint), where it did.
    refused_resume: Option<String>,
}

impl Session {
    /// Runs the whole session and returns the process exit code.
    /// On several ranks (`comm`) this is rank 0's; the others follow its fluid side.
    pub(super) fn start(
        p: Prepared,
        run: &str,
        dem: DemStart,
        interrupted: Arc<AtomicBool>,
        comm: Rc<dyn Communicator>,
    ) -> u8 {
        let mut session = match Session::open(p, run, interrupted, comm) {
            Ok(session) => session,
            Err(e) => {
                protocol::say!("lbm-server: error: {e}");
                return EXIT_FAILURE;
            }
        };
        let result = session.connect(&dem).and_then(|()| session.step_loop());
        if let Some(why) = session.refused_resume.take() {
            return session.refuse_resume(&why);
        }
        session.finish(result)
    }

    /// The fluid (every rank's block of it), then the run's link (its services, before any DEM
    /// connects) and particles.csv; where these fail, the other ranks end with the run.
    fn open(
        p: Prepared,
        run: &str,
        interrupted: Arc<AtomicBool>,
        comm: Rc<dyn Communicator>,
    ) -> Result<Session, String> {
        let resumed = p.resumed.as_ref();
        let fluid = FluidSide::for_scene(&p.scene, p.steps, &p.out, resumed, (comm, p.blocks))?;
        Self::open_link(p, run, interrupted, fluid)
    }

    fn open_link(
        p: Prepared,
        run: &str,
        interrupted: Arc<AtomicBool>,
        fluid: FluidSide,
    ) -> Result<Session, String> {
        let options = LinkOptions {
            run: run.to_string(),
            timeout: Duration::from_secs_f64(p.scene.coupling.timeout),
        };
        let opened = FluidLink::create(options, p.scene.capacity() as usize)
            .map_err(|e| e.to_string())
            .and_then(|link| {
                let vtk = p.scene.dem.output.vtk;
                let particles = match &p.resumed {
                    Some(loaded) => ParticleOutput::resume(&p.out, vtk, &loaded.header.outputs),
                    None => ParticleOutput::create(&p.out, vtk).map_err(|e| e.to_string()),
                }
                .map_err(|e| format!("{}: {e}", p.out.display()))?;
                Ok((link, particles))
            });
        let (link, particles) = match opened {
            Ok(opened) => opened,
            Err(e) => {
                fluid.end_ranks(EXIT_FAILURE, 0.0);
                return Err(e);
            }
        };
        let checkpoints = p.checkpoints();
        let first_step = p.resumed.as_ref().map_or(0, |l| l.header.step);
        let mut counters = Counters::new();
        counters.last_completed = first_step.checked_sub(1);
        Ok(Session {
            p,
            link,
            child: None,
            particles,
            fluid,
            interrupted,
            peer: None,
            hello: None,
            told_to_end: false,
            counters,
            checkpoints,
            checkpointing: false,
            first_step,
            refused_resume: None,
        })
    }

    /// Starts or announces the DEM side and performs the handshake.
    fn connect(&mut self, dem: &DemStart) -> Result<(), String> {
        super::started();
        let spawned = self.start_dem(dem)?;
        let (scene, steps, first) = (&self.p.scene, self.p.steps, self.first_step);
        let physics = self.fluid.physics();
        let interrupted = self.interrupted.clone();
        let resumed = self.p.resumed.as_ref();
        let refused = std::cell::Cell::new(None);
        let hello = self
            .link
            .accept(
                spawned,
                self.p.connect_timeout,
                &|| interrupted.load(Ordering::SeqCst),
                |hello| match resume_refusal(resumed, hello) {
                    Some((refusal, why)) => {
                        refused.set(Some(why));
                        refusal
                    }
                    None => welcome_for(scene, steps, first, hello, physics & !yielded(hello)),
                },
            )
            .map_err(|e| {
                self.refused_resume = refused.take();
                e.to_string()
            })?;
        if yielded(&hello) != 0 {
            self.fluid.leave_lubrication();
        }
        self.checkpointing = self.dem_checkpoints(&hello);
        self.cut_back_outputs()?;
        self.peer = Some(PeerInfo {
            software: protocol::handshake::field_text(&hello.software),
            pid: hello.pid,
            protocol_version: hello.version,
            physics: Physics::names(hello.physics),
        });
        terminal::say(&self.header(&hello));
        self.fluid.say_warnings();
        self.hello = Some(hello);
        Ok(())
    }

    /// The run's first line: the scene, its particles, lattice, steps and simulated time and the
    /// device; with `--verbose` the lattice's scales, the DEM and the coupling's settings.
    fn header(&self, hello: &Hello) -> String {
        let (scene, steps) = (&self.p.scene, self.p.steps);
        let time = steps as f64 * scene.time.dt;
        if terminal::verbose() {
            return format!(
                "lbm-server: scene '{}', {steps} steps ({time:.4e} s), DEM: {} (pid {}); {}",
                scene.name,
                protocol::handshake::field_text(&hello.software),
                hello.pid,
                self.fluid.describe()
            );
        }
        format!(
            "lbm-server: scene '{}': {} particles, {}; {steps} steps = {} s; {}{}",
            scene.name,
            hello.initial_count,
            self.fluid.brief(),
            terminal::seconds(time),
            self.fluid.device(),
            self.fluid.exchange()
        )
    }

    /// Starts dem-client or the DEM's command (its pid) or prints the service name for an
    /// external DEM.
    fn start_dem(&mut self, dem: &DemStart) -> Result<Option<u32>, String> {
        let run = self.link.run().to_string();
        match dem {
            DemStart::Command(command) => {
                let child = command
                    .spawn(&run, &self.p.scene_copy, &self.checkpoint_env()?)
                    .map_err(|e| format!("cannot start the DEM `{}`: {e}", command.describe()))?;
                let pid = child.id();
                self.child = Some(child);
                Ok(Some(pid))
            }
            DemStart::Builtin => {
                let exe = launch::find_dem_client()
                    .ok_or("cannot find dem-client next to lbm-server or on PATH (build it: cargo build)")?;
                let (scene, timeout) = (&self.p.scene_copy, self.p.scene.coupling.timeout);
                let child = launch::spawn_dem_client(
                    &exe,
                    &run,
                    scene,
                    timeout,
                    terminal::verbose(),
                    &self.checkpoint_env()?,
                )
                .map_err(|e| format!("cannot start {}: {e}", exe.display()))?;
                let pid = child.id();
                self.child = Some(child);
                Ok(Some(pid))
            }
            DemStart::External => {
                println!("DEM service: {run}");
                println!(
                    "join with: dem-client connect --service {run} --scene {}",
                    self.p.scene_copy.display()
                );
                use std::io::Write;
                let _ = std::io::stdout().flush();
                Ok(None)
            }
        }
    }

    /// Whether the DEM process the run started has exited.
    pub(super) fn dem_exited(&mut self) -> bool {
        self.child
            .as_mut()
            .is_some_and(|c| matches!(c.try_wait(), Ok(Some(_))))
    }

    /// A failure of the fluid, with the last completed step.
    pub(super) fn describe_fluid(&self, e: String) -> String {
        format!(
            "{e}; last completed step: {}",
            self.counters.last_completed_text()
        )
    }

    /// A failure of the link, with its hint and the last completed step.
    pub(super) fn describe(&self, e: LinkError) -> String {
        let last = self.counters.last_completed_text();
        format!("{e}{}; last completed step: {last}", e.hint())
    }

    /// Ends the DEM process, writes summary.json; returns the exit code (1 where summary.json
    /// cannot be written).
    fn finish(mut self, result: Result<Ending, String>) -> u8 {
        if result.is_err() {
            self.keep_held_checkpoint();
        }
        let checkpointed = self.checkpoints.wait();
        let dem_status = self.end_dem(result.is_ok() || self.told_to_end);
        let (mut reason, mut code) = self.ending(&result, dem_status);
        if let Err(e) = checkpointed {
            protocol::say!("lbm-server: error: {e}");
            (reason, code) = (format!("error: {e}"), EXIT_FAILURE);
        }
        if let (Err(msg), true) = (&result, code == EXIT_FAILURE) {
            protocol::say!("lbm-server: error: {msg}");
        }
        if code != 0 {
            self.say_resumable();
        }
        let parallel = self.fluid.end_ranks(code, self.counters.wall());
        let summary = self.summary(reason, code, parallel);
        if let Err(e) = summary.write(&self.p.out.join("summary.json")) {
            // The run's record lost: whatever the run did, it did not end well.
            protocol::say!("lbm-server: error: summary.json: {e}");
            return EXIT_FAILURE;
        }
        self.say_ended(&summary, code);
        code
    }

    /// How the run ended, from its `result` and the exit status of a DEM it started: the
    /// summary's reason and the exit code.
    fn ending(&self, result: &Result<Ending, String>, dem_status: Option<i32>) -> (String, u8) {
        match result {
            // A DEM the run started that refused its input (exit 2: YADE or LIGGGHTS missing, a
            // deck or script that does not fit the scene) before or at step 0: the run's input
            // was bad, and it said why.
            _ if dem_status == Some(i32::from(EXIT_BAD_INPUT)) && self.counters.steps_completed() <= 1 => {
                let why = "the DEM refused its input (exit status 2; its message is above)";
                protocol::say!("lbm-server: error: {why}");
                (format!("error: {why}"), EXIT_BAD_INPUT)
            }
            Ok(Ending::Completed) => ("completed".to_string(), 0),
            Ok(Ending::Interrupted) => ("interrupted".to_string(), EXIT_INTERRUPTED),
            Ok(Ending::StoppedByPeer) => ("stopped by the DEM client".to_string(), EXIT_INTERRUPTED),
            Err(_) if self.interrupted.load(Ordering::SeqCst) => {
                ("interrupted".to_string(), EXIT_INTERRUPTED)
            }
            Err(e) => (format!("error: {e}"), EXIT_FAILURE),
        }
    }

    /// The run's last line, after `summary` was written with the exit `code`: how far an
    /// interrupted run came, or how fast a completed one ran; where its output is.
    fn say_ended(&self, summary: &Summary, code: u8) {
        if code == EXIT_INTERRUPTED {
            protocol::say!(
                "lbm-server: {} after {} of {} steps; output in {}",
                summary.exit_reason,
                summary.steps_completed,
                summary.steps_requested,
                self.p.out.display()
            );
        }
        if code == 0 {
            let split = if terminal::verbose() {
                format!("{}; ", summary.time_s.describe(summary.wall_time_s))
            } else {
                String::new()
            };
            protocol::say!(
                "lbm-server: {} steps in {:.2} s ({:.0} steps/s; {split}the fluid's step at {:.1} \
                 MLUPS); output in {}",
                summary.steps_completed,
                summary.wall_time_s,
                summary.steps_per_second,
                summary.fluid_mlups,
                self.p.out.display()
            );
        }
    }

    /// Ends the DEM side: a DEM `told` to end (its last reply said FINAL or STOP) ends on its own
    /// and is given the time to; a spawned one is then ended, an external one is left the time to
    /// read the last reply before our ports close. Returns a spawned DEM's exit status.
    pub(super) fn end_dem(&mut self, told: bool) -> Option<i32> {
        let grace = if told {
            Duration::from_secs(2)
        } else {
            Duration::ZERO
        };
        if let Some(child) = self.child.as_mut() {
            return launch::end_child(child, grace);
        }
        if told {
            self.link.linger(protocol::transport::LINGER);
        }
        None
    }
}

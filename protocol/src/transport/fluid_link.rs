//! The fluid side of a link: creates the run's services, accepts one DEM client, replies with forces.

use super::*;
use crate::handshake::{DecodeError, Hello, Message, Physics, Status, Welcome};
use crate::liveness::{process_state, ProcessState};
use crate::wire::{ParticleReply, ParticleState, StepHeader};
use core::time::Duration;
use std::time::Instant;

/// The fluid side of a link: creates the services, accepts one DEM client, replies with forces.
pub struct FluidLink {
    options: LinkOptions,
    hello: Inbox<u8, ()>,
    welcome: Outbox<u8, ()>,
    states: Inbox<ParticleState, StepHeader>,
    forces: Outbox<ParticleReply, StepHeader>,
    watch: Watch,
    capacity: usize,
    // Dropped last: the ports above belong to it.
    _node: Node<Ipc>,
}

impl FluidLink {
    /// Creates the run's services. Any DEM may connect once this returns.
    pub fn create(options: LinkOptions, capacity: usize) -> Result<Self, LinkError> {
        let node = create_node(&options.run)?;
        let run = options.run.as_str();
        let hello = inbox(&node, run, "hello", true)?;
        let welcome = outbox(&node, run, "welcome", true, crate::handshake::TEXT_LEN * 8)?;
        let states = inbox(&node, run, "states", true)?;
        let forces = outbox(&node, run, "forces", true, capacity)?;
        Ok(Self {
            options,
            hello,
            welcome,
            states,
            forces,
            watch: Watch {
                peer: Peer::Dem,
                pid: None,
                connected: false,
            },
            capacity,
            _node: node,
        })
    }

    pub fn run(&self) -> &str {
        &self.options.run
    }

    /// Pid of the connected DEM process.
    pub fn peer_pid(&self) -> Option<u32> {
        self.watch.pid
    }

    /// Waits for the DEM's `Hello`, checks it, and answers with `welcome(hello)` or a refusal.
    ///
    /// `spawned` is the pid of a DEM process this side started itself (its death is then noticed
    /// before the handshake too). `interrupt` aborts the wait (Ctrl-C).
    pub fn accept(
        &mut self,
        spawned: Option<u32>,
        connect_timeout: Duration,
        interrupt: &dyn Fn() -> bool,
        welcome: impl FnOnce(&Hello) -> Welcome,
    ) -> Result<Hello, LinkError> {
        let watch = Watch {
            peer: Peer::Dem,
            pid: spawned,
            connected: false,
        };
        let bytes = watch.wait(&self.hello, connect_timeout, interrupt, take_bytes)?;
        let software = format!("lbm-server {}", env!("CARGO_PKG_VERSION"));
        let hello = match Hello::from_bytes(&bytes) {
            Ok(hello) => hello,
            Err(DecodeError::Version(ours, theirs)) => {
                let why = format!(
                    "protocol version mismatch: lbm-server speaks version {ours}, the DEM client \
                     speaks version {theirs}"
                );
                return self.refuse(Welcome::refused(&software, Status::VersionMismatch, &why));
            }
            Err(e) => {
                return self.refuse(Welcome::refused(
                    &software,
                    Status::LayoutMismatch,
                    &e.to_string(),
                ));
            }
        };
        // A Welcome in the Hello's version (a version-1 DEM reads the first 344 bytes).
        let v = hello.version;
        if let Some((status, why)) = check_hello(&hello, self.capacity) {
            return self.refuse(Welcome::refused(&software, status, &why).for_version(v));
        }
        let mut answer = welcome(&hello).for_version(v);
        answer.capacity = self.capacity as u64;
        if answer.status != Status::Accepted as u32 {
            return self.refuse(answer);
        }
        if answer.physics & hello.physics & Physics::EXCLUSIVE != 0 {
            let twice = Physics::names(answer.physics & hello.physics & Physics::EXCLUSIVE);
            let why = format!("both sides apply {}", twice.join(", "));
            let refusal = Welcome::refused(&software, Status::PhysicsConflict, &why);
            return self.refuse(refusal.for_version(v));
        }
        self.send_welcome(&answer)?;
        self.watch = Watch {
            peer: Peer::Dem,
            pid: Some(hello.pid as u32),
            connected: true,
        };
        Ok(hello)
    }

    fn send_welcome(&self, welcome: &Welcome) -> Result<(), LinkError> {
        let bytes = welcome.to_bytes();
        self.welcome.send_with((), bytes.len(), |i| bytes[i])
    }

    fn refuse(&self, welcome: Welcome) -> Result<Hello, LinkError> {
        self.send_welcome(&welcome)?;
        self.linger(LINGER);
        Err(LinkError::Refused(welcome.reason_text()))
    }

    /// Keeps this side's ports (and so the shared memory of its last message) alive until the DEM
    /// has closed its own ports, died, or `max` has passed: a message must not vanish unread.
    pub fn linger(&self, max: Duration) {
        let start = Instant::now();
        while start.elapsed() < max {
            let open = self.hello.has_publisher() || self.states.has_publisher();
            let dead = self
                .watch
                .pid
                .is_some_and(|pid| process_state(pid) == ProcessState::Dead);
            if !open || dead {
                return;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    /// Waits for the states of step `step`.
    pub fn receive_states(&self, step: u64) -> Result<Received<ParticleState>, LinkError> {
        let (peer, capacity) = (self.watch.peer, self.capacity);
        let sample = self
            .watch
            .wait(&self.states, self.options.timeout, &|| false, |inbox| {
                take_step(inbox, peer, step, capacity)
            })?;
        Ok(Received { sample })
    }

    /// Sends the reply of a step, built in place by `fill(i)` for particle `i`.
    pub fn send_forces(
        &self,
        header: StepHeader,
        fill: impl FnMut(usize) -> ParticleReply,
    ) -> Result<(), LinkError> {
        self.forces.send_with(header, header.count as usize, fill)
    }
}

/// Version-independent checks of a `Hello`: the refusal status and reason, if any.
fn check_hello(hello: &Hello, capacity: usize) -> Option<(Status, String)> {
    if !hello.layout_matches() {
        return Some((
            Status::LayoutMismatch,
            format!(
                "message sizes state/reply/header {}/{}/{} bytes from the DEM, {}/{}/{} expected",
                hello.state_size,
                hello.reply_size,
                hello.header_size,
                core::mem::size_of::<ParticleState>(),
                core::mem::size_of::<ParticleReply>(),
                core::mem::size_of::<StepHeader>()
            ),
        ));
    }
    if !hello.units.is_valid() {
        return Some((Status::BadUnits, format!("invalid units {:?}", hello.units)));
    }
    if hello.initial_count as usize > capacity {
        let why = format!("{} particles exceed the capacity {capacity}", hello.initial_count);
        return Some((Status::CapacityExceeded, why));
    }
    None
}

//! The DEM side of a link: joins a run's services, sends states, receives forces.

use super::*;
use crate::handshake::{DecodeError, Hello, Message, Status, Welcome};
use crate::wire::{ParticleReply, ParticleState, StepHeader};
use std::time::Instant;

/// The DEM side of a link: sends states, receives forces.
pub struct DemLink {
    options: LinkOptions,
    states: Outbox<ParticleState, StepHeader>,
    forces: Inbox<ParticleReply, StepHeader>,
    watch: Watch,
    capacity: usize,
    _hello: Outbox<u8, ()>,
    _welcome: Inbox<u8, ()>,
    _node: Node<Ipc>,
}

impl DemLink {
    /// Opens the run's services, sends `hello`, and returns the link with the fluid's `Welcome`.
    pub fn connect(options: LinkOptions, hello: Hello) -> Result<(Self, Welcome), LinkError> {
        let node = create_node(&options.run)?;
        let run = options.run.as_str();
        let start = Instant::now();
        // The fluid side creates the services; retry briefly in case it is still doing so.
        let hello_box = loop {
            match outbox::<u8, ()>(&node, run, "hello", false, core::mem::size_of::<Hello>()) {
                Ok(b) if b.has_subscriber() => break b,
                Ok(_) | Err(_) if start.elapsed() < options.timeout => std::thread::sleep(POLL),
                Ok(_) => {
                    return Err(LinkError::Timeout {
                        peer: Peer::Fluid,
                        waited: start.elapsed(),
                        idle: None,
                    })
                }
                Err(e) => {
                    // No fluid side exists, so the only files of this run are our node's.
                    drop(node);
                    crate::cleanup::remove_run(run);
                    return Err(LinkError::Ipc(format!(
                        "no run named '{run}' found ({e}); is lbm-server running?"
                    )));
                }
            }
        };
        let welcome_box = inbox::<u8, ()>(&node, run, "welcome", false)?;
        let forces = inbox(&node, run, "forces", false)?;
        let capacity_guess = hello.initial_count as usize;
        let states = outbox(&node, run, "states", false, capacity_guess)?;
        let bytes = hello.to_bytes();
        hello_box.send_with((), bytes.len(), |i| bytes[i])?;
        let watch = Watch {
            peer: Peer::Fluid,
            pid: None,
            connected: true,
        };
        let reply = watch.wait(&welcome_box, options.timeout, &|| false, take_bytes)?;
        let welcome = decode_welcome(&reply)?;
        let capacity = welcome.capacity as usize;
        Ok((
            Self {
                options,
                states,
                forces,
                watch: Watch {
                    peer: Peer::Fluid,
                    pid: Some(welcome.pid as u32),
                    connected: true,
                },
                capacity,
                _hello: hello_box,
                _welcome: welcome_box,
                _node: node,
            },
            welcome,
        ))
    }

    pub fn run(&self) -> &str {
        &self.options.run
    }

    /// Sends the states of a step, built in place by `fill(i)` for particle `i`.
    pub fn send_states(
        &self,
        header: StepHeader,
        fill: impl FnMut(usize) -> ParticleState,
    ) -> Result<(), LinkError> {
        if header.count as usize > self.capacity {
            return Err(LinkError::BadCount {
                peer: Peer::Dem,
                count: header.count,
                len: header.count as usize,
                capacity: self.capacity,
            });
        }
        self.states.send_with(header, header.count as usize, fill)
    }

    /// Waits for the fluid's reply to step `step`.
    pub fn receive_forces(&self, step: u64) -> Result<Received<ParticleReply>, LinkError> {
        let (peer, capacity) = (self.watch.peer, self.capacity);
        let sample = self
            .watch
            .wait(&self.forces, self.options.timeout, &|| false, |inbox| {
                take_step(inbox, peer, step, capacity)
            })?;
        Ok(Received { sample })
    }
}

/// Reads the fluid's answer, turning a refusal or an unreadable answer into an error.
fn decode_welcome(bytes: &[u8]) -> Result<Welcome, LinkError> {
    match Welcome::from_bytes(bytes) {
        Ok(w) if w.status == Status::Accepted as u32 => Ok(w),
        Ok(w) => Err(LinkError::Refused(w.reason_text())),
        Err(DecodeError::Version(ours, theirs)) => Err(LinkError::Refused(format!(
            "protocol version mismatch: this DEM speaks version {ours}, the fluid server speaks \
             version {theirs}"
        ))),
        Err(e) => Err(LinkError::Refused(e.to_string())),
    }
}

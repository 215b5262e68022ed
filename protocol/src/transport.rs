//! The iceoryx2 transport: four publish-subscribe services, each paired with an event service of
//! the same name for blocking waits, under a per-run name that is also the shared-memory prefix.
//!
//! | service          | payload               | user header  | direction   |
//! |------------------|-----------------------|--------------|-------------|
//! | `RUN/hello`      | `[u8]` (a `Hello`)    | none         | DEM → fluid |
//! | `RUN/welcome`    | `[u8]` (a `Welcome`)  | none         | fluid → DEM |
//! | `RUN/states`     | `[ParticleState]`     | `StepHeader` | DEM → fluid |
//! | `RUN/forces`     | `[ParticleReply]`     | `StepHeader` | fluid → DEM |

use crate::liveness::{process_state, Activity, ProcessState};
use crate::wire::StepHeader;
use core::fmt::{self, Debug, Display};
use core::time::Duration;
use iceoryx2::port::listener::{Listener, ListenerWaitError};
use iceoryx2::port::notifier::Notifier;
use iceoryx2::port::publisher::Publisher;
use iceoryx2::port::subscriber::Subscriber;
use iceoryx2::prelude::*;
use iceoryx2::sample::Sample;
use std::time::Instant;

mod dem_link;
mod fluid_link;

pub use dem_link::DemLink;
pub use fluid_link::FluidLink;

type Ipc = ipc::Service;

/// How often a waiting side wakes up to look at its peer.
pub const POLL: Duration = Duration::from_millis(50);

/// Longest wait for the DEM to read the fluid's last message before the fluid's ports close.
pub const LINGER: Duration = Duration::from_secs(1);

/// How long a peer may stay suspended (SIGSTOP) before it counts as hung.
pub const STOPPED_GRACE: Duration = Duration::from_millis(400);

/// A peer that works (uses CPU) without answering is waited for up to this many times the
/// timeout; one that is silent and idle only for the timeout.
pub const BUSY_FACTOR: u32 = 60;

/// Which side of the link the other process is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Peer {
    Fluid,
    Dem,
}

impl Display for Peer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Peer::Fluid => write!(f, "fluid server (lbm-server)"),
            Peer::Dem => write!(f, "DEM client"),
        }
    }
}

/// Everything that ends a link. The messages name the peer; callers add the last completed step.
#[derive(Debug, Clone, PartialEq)]
pub enum LinkError {
    PeerLeft {
        peer: Peer,
    },
    PeerDied {
        peer: Peer,
        pid: u32,
    },
    PeerStopped {
        peer: Peer,
        pid: u32,
    },
    /// Silent beyond the timeout; `idle`: for how long it used no CPU, where its pid is known.
    Timeout {
        peer: Peer,
        waited: Duration,
        idle: Option<Duration>,
    },
    /// Working (using CPU) without answering for [`BUSY_FACTOR`] times the timeout.
    Busy {
        peer: Peer,
        pid: u32,
        waited: Duration,
    },
    StepMismatch {
        peer: Peer,
        expected: u64,
        got: u64,
    },
    BadCount {
        peer: Peer,
        count: u64,
        len: usize,
        capacity: usize,
    },
    Refused(String),
    Interrupted,
    Ipc(String),
}

impl Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkError::PeerDied { peer, pid } => write!(f, "the {peer} (pid {pid}) died"),
            LinkError::PeerStopped { peer, pid } => {
                write!(
                    f,
                    "the {peer} (pid {pid}) is suspended (stopped) and hangs the run"
                )
            }
            LinkError::PeerLeft { peer } => write!(f, "the {peer} left the run (its port closed)"),
            LinkError::Timeout {
                peer,
                waited,
                idle: None,
            } => write!(
                f,
                "the {peer} did not answer within {:.1} s (hung?)",
                waited.as_secs_f64()
            ),
            LinkError::Timeout {
                peer,
                waited,
                idle: Some(idle),
            } => write!(
                f,
                "the {peer} did not answer within {:.1} s and used no CPU for the last {:.1} s (hung?)",
                waited.as_secs_f64(),
                idle.as_secs_f64()
            ),
            LinkError::Busy { peer, pid, waited } => write!(
                f,
                "the {peer} (pid {pid}) worked for {:.1} s without answering ({BUSY_FACTOR} x the \
                 timeout; an endless loop?)",
                waited.as_secs_f64()
            ),
            LinkError::StepMismatch { peer, expected, got } => write!(
                f,
                "the {peer} sent step {got} where step {expected} was due (lockstep broken)"
            ),
            LinkError::BadCount {
                peer,
                count,
                len,
                capacity,
            } => write!(
                f,
                "the {peer} sent a step header counting {count} particles with {len} in the slice \
                 (capacity {capacity})"
            ),
            LinkError::Refused(why) => write!(f, "handshake refused: {why}"),
            LinkError::Interrupted => write!(f, "interrupted"),
            LinkError::Ipc(what) => write!(f, "shared-memory transport failed: {what}"),
        }
    }
}

impl std::error::Error for LinkError {}

impl LinkError {
    /// For a peer silent beyond the timeout, why a live one can take that long and what to raise
    /// (empty for every other error).
    pub fn hint(&self) -> &'static str {
        match self {
            LinkError::Timeout {
                peer: Peer::Fluid,
                idle: Some(_),
                ..
            } => {
                " (a fluid step on a GPU waits without using the CPU: if its steps take that long, \
                 raise coupling.timeout in the scene, or --timeout; a step that works on the CPU is \
                 waited for up to 60 x it)"
            }
            LinkError::Timeout {
                peer: Peer::Dem,
                idle: Some(_),
                ..
            } => {
                " (a DEM that works is waited for up to 60 x coupling.timeout; this one used no CPU: \
                 raise coupling.timeout in the scene only if its steps wait that long on something else)"
            }
            LinkError::Timeout { peer: Peer::Dem, .. } | LinkError::Busy { peer: Peer::Dem, .. } => {
                " (a DEM step with many spheres in contact can take that long on a few cores: raise \
                 coupling.timeout in the scene)"
            }
            LinkError::Timeout {
                peer: Peer::Fluid, ..
            }
            | LinkError::Busy {
                peer: Peer::Fluid, ..
            } => {
                " (a fluid step of a large lattice on a CPU Vulkan driver, or on a loaded machine, can \
                 take that long: raise coupling.timeout in the scene, or --timeout)"
            }
            _ => "",
        }
    }
}

fn ipc_err<E: Debug>(what: &str) -> impl FnOnce(E) -> LinkError + '_ {
    move |e| LinkError::Ipc(format!("{what}: {e:?}"))
}

/// Options shared by both sides.
#[derive(Debug, Clone)]
pub struct LinkOptions {
    /// The run's name: the service root and, followed by `_`, the shared-memory file prefix.
    pub run: String,
    /// Longest wait for a live peer that does not answer (a deadlock, an endless loop).
    pub timeout: Duration,
}

/// A fresh run name, unique on this host: `lbmdem_<pid>_<nanoseconds>`.
pub fn new_run_name() -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_nanos())
        .unwrap_or(0);
    format!(
        "{}{}_{:x}",
        crate::cleanup::RUN_PREFIX,
        std::process::id(),
        nanos & 0xffff_ffff_ffff
    )
}

/// iceoryx2's global configuration, without its "no config file" warning on stderr.
pub(crate) fn global_config() -> &'static Config {
    set_log_level(LogLevel::Error);
    Config::global_config()
}

fn create_node(run: &str) -> Result<Node<Ipc>, LinkError> {
    let mut config = global_config().clone();
    config.global.prefix =
        FileName::new(format!("{run}_").as_bytes()).map_err(ipc_err("run name is not a valid file name"))?;
    NodeBuilder::new()
        .config(&config)
        .signal_handling_mode(SignalHandlingMode::Disabled)
        .create::<Ipc>()
        .map_err(ipc_err("cannot create the iceoryx2 node"))
}

fn service_name(run: &str, what: &str) -> Result<ServiceName, LinkError> {
    ServiceName::new(&format!("{run}/{what}")).map_err(ipc_err("bad service name"))
}

/// Sending end: a publisher of slices and the notifier that wakes the peer.
struct Outbox<T: Debug + ZeroCopySend + 'static, H: Debug + ZeroCopySend + 'static> {
    publisher: Publisher<Ipc, [T], H>,
    notifier: Notifier<Ipc>,
    subscribers: iceoryx2::service::port_factory::publish_subscribe::PortFactory<Ipc, [T], H>,
}

/// Receiving end: a subscriber of slices and the listener it blocks on.
struct Inbox<T: Debug + ZeroCopySend + 'static, H: Debug + ZeroCopySend + 'static> {
    subscriber: Subscriber<Ipc, [T], H>,
    listener: Listener<Ipc>,
    service: PubSub<T, H>,
}

type PubSub<T, H> = iceoryx2::service::port_factory::publish_subscribe::PortFactory<Ipc, [T], H>;

impl<T: Debug + ZeroCopySend + 'static, H: Debug + ZeroCopySend + 'static> Inbox<T, H> {
    /// Does the peer still hold its publisher on this service?
    fn has_publisher(&self) -> bool {
        self.service.dynamic_config().number_of_publishers() > 0
    }
}

/// Creates (fluid side) or opens (DEM side) the publish-subscribe service `what`.
fn pubsub<T, H>(
    node: &Node<Ipc>,
    run: &str,
    what: &str,
    create: bool,
) -> Result<iceoryx2::service::port_factory::publish_subscribe::PortFactory<Ipc, [T], H>, LinkError>
where
    T: Debug + ZeroCopySend + 'static,
    H: Debug + ZeroCopySend + Default + 'static,
{
    let builder = node
        .service_builder(&service_name(run, what)?)
        .publish_subscribe::<[T]>()
        .user_header::<H>();
    if create {
        builder
            .max_publishers(1)
            .max_subscribers(1)
            .history_size(0)
            .subscriber_max_buffer_size(2)
            .enable_safe_overflow(false)
            .create()
            .map_err(ipc_err(what))
    } else {
        builder.open().map_err(ipc_err(what))
    }
}

fn event(
    node: &Node<Ipc>,
    run: &str,
    what: &str,
    create: bool,
) -> Result<iceoryx2::service::port_factory::event::PortFactory<Ipc>, LinkError> {
    let builder = node.service_builder(&service_name(run, what)?).event();
    if create {
        builder.create().map_err(ipc_err(what))
    } else {
        builder.open().map_err(ipc_err(what))
    }
}

fn outbox<T, H>(
    node: &Node<Ipc>,
    run: &str,
    what: &str,
    create: bool,
    max_len: usize,
) -> Result<Outbox<T, H>, LinkError>
where
    T: Debug + ZeroCopySend + 'static,
    H: Debug + ZeroCopySend + Default + 'static,
{
    let service = pubsub::<T, H>(node, run, what, create)?;
    let publisher = service
        .publisher_builder()
        .initial_max_slice_len(max_len.max(1))
        .allocation_strategy(AllocationStrategy::PowerOfTwo)
        .create()
        .map_err(ipc_err(what))?;
    let notifier = event(node, run, what, create)?
        .notifier_builder()
        .create()
        .map_err(ipc_err(what))?;
    Ok(Outbox {
        publisher,
        notifier,
        subscribers: service,
    })
}

fn inbox<T, H>(node: &Node<Ipc>, run: &str, what: &str, create: bool) -> Result<Inbox<T, H>, LinkError>
where
    T: Debug + ZeroCopySend + 'static,
    H: Debug + ZeroCopySend + Default + 'static,
{
    let service = pubsub::<T, H>(node, run, what, create)?;
    let subscriber = service.subscriber_builder().create().map_err(ipc_err(what))?;
    let listener = event(node, run, what, create)?
        .listener_builder()
        .create()
        .map_err(ipc_err(what))?;
    Ok(Inbox {
        subscriber,
        listener,
        service,
    })
}

impl<T: Debug + ZeroCopySend + Copy + 'static, H: Debug + ZeroCopySend + Copy + Default + 'static>
    Outbox<T, H>
{
    /// Loans `len` elements, fills them with `fill` in place (zero copy), sends, wakes the peer.
    fn send_with(&self, header: H, len: usize, fill: impl FnMut(usize) -> T) -> Result<(), LinkError> {
        let mut sample = self.publisher.loan_slice_uninit(len).map_err(ipc_err("loan"))?;
        *sample.user_header_mut() = header;
        sample.write_from_fn(fill).send().map_err(ipc_err("send"))?;
        self.notifier.notify().map_err(ipc_err("notify"))?;
        Ok(())
    }

    fn has_subscriber(&self) -> bool {
        self.subscribers.dynamic_config().number_of_subscribers() > 0
    }
}

/// The peer a side waits on: what to call it and, once known, its pid.
#[derive(Debug, Clone, Copy)]
struct Watch {
    peer: Peer,
    pid: Option<u32>,
    /// The peer has connected: its publisher must stay on the awaited service.
    connected: bool,
}

impl Watch {
    /// Blocks until `take` yields, the peer dies or hangs, or it stays idle (no CPU) for `timeout`
    /// or works without answering for [`BUSY_FACTOR`] x `timeout`.
    fn wait<T, H, R>(
        &self,
        inbox: &Inbox<T, H>,
        timeout: Duration,
        interrupt: &dyn Fn() -> bool,
        mut take: impl FnMut(&Inbox<T, H>) -> Result<Option<R>, LinkError>,
    ) -> Result<R, LinkError>
    where
        T: Debug + ZeroCopySend + 'static,
        H: Debug + ZeroCopySend + 'static,
    {
        let mut waiting = Waiting {
            start: Instant::now(),
            stopped_since: None,
            activity: None,
        };
        loop {
            if let Some(r) = take(inbox)? {
                return Ok(r);
            }
            match inbox.listener.timed_wait(|_| {}, POLL) {
                // A signal (Ctrl-C) woke the wait early: look again, the caller decides.
                Ok(_) | Err(ListenerWaitError::InterruptSignal) => {}
                Err(e) => return Err(ipc_err("wait")(e)),
            }
            if let Some(r) = take(inbox)? {
                return Ok(r);
            }
            self.look_at_peer(&mut waiting, timeout)?;
            if self.connected && !inbox.has_publisher() {
                return Err(LinkError::PeerLeft { peer: self.peer });
            }
            if interrupt() {
                return Err(LinkError::Interrupted);
            }
            self.within_time(&mut waiting, timeout)?;
        }
    }

    /// Whether the peer, where its pid is known, still lives and is not stopped past
    /// [`STOPPED_GRACE`]; starts watching its activity at the first look.
    fn look_at_peer(&self, waiting: &mut Waiting, timeout: Duration) -> Result<(), LinkError> {
        let Some(pid) = self.pid else {
            return Ok(());
        };
        match process_state(pid) {
            ProcessState::Dead => return Err(LinkError::PeerDied { peer: self.peer, pid }),
            ProcessState::Stopped => {
                let since = *waiting.stopped_since.get_or_insert_with(Instant::now);
                if since.elapsed() >= STOPPED_GRACE {
                    return Err(LinkError::PeerStopped { peer: self.peer, pid });
                }
            }
            ProcessState::Running => waiting.stopped_since = None,
        }
        let start = waiting.start;
        waiting
            .activity
            .get_or_insert_with(|| Activity::for_timeout(pid, timeout, start));
        Ok(())
    }

    /// Whether the wait is still within its time: the peer idle for less than `timeout`, and
    /// waited on for less than [`BUSY_FACTOR`] x `timeout`.
    fn within_time(&self, waiting: &mut Waiting, timeout: Duration) -> Result<(), LinkError> {
        let start = waiting.start;
        let last_busy = waiting.activity.as_mut().map_or(start, |a| a.last_busy());
        if last_busy.elapsed() >= timeout {
            return Err(LinkError::Timeout {
                peer: self.peer,
                waited: start.elapsed(),
                idle: waiting.activity.is_some().then(|| last_busy.elapsed()),
            });
        }
        if let Some(pid) = self.pid.filter(|_| start.elapsed() >= timeout * BUSY_FACTOR) {
            return Err(LinkError::Busy {
                peer: self.peer,
                pid,
                waited: start.elapsed(),
            });
        }
        Ok(())
    }
}

/// Where one [`Watch::wait`] stands.
struct Waiting {
    start: Instant,
    /// Since when the peer has been seen stopped, if it is.
    stopped_since: Option<Instant>,
    /// Started at the first look at the peer, one poll into the wait (its windows and idle time
    /// still count from the wait's start): an answer that is there at once costs no read.
    activity: Option<Activity>,
}

/// Takes one byte message if there is one.
fn take_bytes(inbox: &Inbox<u8, ()>) -> Result<Option<Vec<u8>>, LinkError> {
    Ok(inbox
        .subscriber
        .receive()
        .map_err(ipc_err("receive"))?
        .map(|s| s.payload().to_vec()))
}

/// Takes one step message if there is one and checks its step index and count.
fn take_step<T: Debug + ZeroCopySend + 'static>(
    inbox: &Inbox<T, StepHeader>,
    peer: Peer,
    expected: u64,
    capacity: usize,
) -> Result<Option<Sample<Ipc, [T], StepHeader>>, LinkError> {
    let Some(sample) = inbox.subscriber.receive().map_err(ipc_err("receive"))? else {
        return Ok(None);
    };
    let header = *sample.user_header();
    if header.step != expected {
        return Err(LinkError::StepMismatch {
            peer,
            expected,
            got: header.step,
        });
    }
    let len = sample.payload().len();
    if header.count != len as u64 || len > capacity {
        return Err(LinkError::BadCount {
            peer,
            count: header.count,
            len,
            capacity,
        });
    }
    Ok(Some(sample))
}

/// A received step: the header and the particles, read in place from shared memory.
pub struct Received<T: Debug + ZeroCopySend + 'static> {
    sample: Sample<Ipc, [T], StepHeader>,
}

impl<T: Debug + ZeroCopySend + 'static> Received<T> {
    pub fn header(&self) -> StepHeader {
        *self.sample.user_header()
    }

    pub fn particles(&self) -> &[T] {
        self.sample.payload()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_timeout_messages_say_whether_the_peer_worked_and_name_the_busy_limit() {
        let waited = Duration::from_secs(12);
        let factor = format!("{BUSY_FACTOR} x");
        for peer in [Peer::Fluid, Peer::Dem] {
            let idle = LinkError::Timeout {
                peer,
                waited,
                idle: Some(Duration::from_secs(10)),
            };
            assert!(
                idle.to_string()
                    .ends_with("used no CPU for the last 10.0 s (hung?)"),
                "{idle}"
            );
            assert!(idle.hint().contains(&factor), "{}", idle.hint());
            let busy = LinkError::Busy { peer, pid: 7, waited };
            assert!(
                busy.to_string().contains(&format!("({factor} the timeout")),
                "{busy}"
            );
            let unknown = LinkError::Timeout {
                peer,
                waited,
                idle: None,
            };
            for e in [idle, busy, unknown] {
                assert!(e.hint().contains("raise coupling.timeout"), "{e}: {}", e.hint());
            }
        }
    }
}

//! The thin DDS layer: a loopback-restricted participant, typed publishers
//! and subscriptions with pinned QoS, and [`RobotNode`], which moves
//! messages between ROS 2 and the [`Bridge`].
//!
//! Every participant is built with RustDDS's
//! `DomainParticipantBuilder::with_only_networks`, so discovery and data
//! use only the listed interfaces (loopback by default, see
//! [`RosConfig::only_networks`](crate::config::RosConfig::only_networks)).

use std::net::{IpAddr, Ipv4Addr};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use ros2_client::dds::{Context, Node, Publisher, Subscription};
use ros2_client::qos::{Durability, History, WhenFull};
use ros2_client::{MessageTypeName, Name, NodeName, NodeOptions, QosProfile};
use rustdds::DomainParticipantBuilder;

use crate::bridge::{Bridge, BridgeError, Outgoing};
use crate::config::ScoutConfig;
use crate::contract::Qos;
use crate::msg::{
    Int8, Joy, MarkerArray, Odometry, Path, PointCloud2, PointStamped, RosMessage, RosString,
    Twist, TwistStamped,
};
use crate::streams::SampleSource;

/// Errors of the DDS layer.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// Creating the participant, node, topic or an endpoint failed.
    #[error("DDS: {0}")]
    Dds(String),
    /// A topic or node name is not a valid ROS name.
    #[error("invalid ROS name `{name}`: {message}")]
    Name {
        /// The name.
        name: String,
        /// Why.
        message: String,
    },
    /// The bridge refused its configuration.
    #[error(transparent)]
    Bridge(#[from] BridgeError),
}

fn dds(e: impl std::fmt::Debug) -> NodeError {
    NodeError::Dds(format!("{e:?}"))
}

/// The QoS profile of [`Qos`] (volatile, keep last `depth`; reliable writers
/// wait up to 100 ms for buffer space).
pub fn qos_profile(q: Qos) -> QosProfile {
    match q {
        Qos::Reliable { depth } => QosProfile::publisher_default()
            .reliability_reliable(WhenFull::Wait(Duration::from_millis(100)))
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth }),
        Qos::BestEffort { depth } => QosProfile::subscription_default()
            .reliability_best_effort()
            .durability(Durability::Volatile)
            .history(History::KeepLast { depth }),
    }
}

/// A ROS 2 context on `domain_id` whose participant uses only the
/// interfaces with the given addresses.
///
/// # Errors
/// [`NodeError::Dds`] when the participant cannot be created, or when
/// `only_networks` is empty (an unrestricted participant is never built).
pub fn context(domain_id: u16, only_networks: &[Ipv4Addr]) -> Result<Context, NodeError> {
    if only_networks.is_empty() {
        return Err(NodeError::Dds(
            "refusing to build a DDS participant on every interface: list the allowed addresses"
                .into(),
        ));
    }
    let participant = DomainParticipantBuilder::new(domain_id)
        .with_only_networks(only_networks.iter().copied().map(IpAddr::V4))
        .build()
        .map_err(dds)?;
    Context::from_domain_participant(participant).map_err(dds)
}

/// A loopback-only context (`127.0.0.1`) on `domain_id`: what tests, the
/// simulated robot and single-computer robots use.
///
/// # Errors
/// As [`context`].
pub fn loopback_context(domain_id: u16) -> Result<Context, NodeError> {
    context(domain_id, &[Ipv4Addr::LOCALHOST])
}

/// A node without rosout and parameter services (no spinner needed).
///
/// # Errors
/// [`NodeError::Name`] for an invalid name, [`NodeError::Dds`].
pub fn ros_node(context: &Context, namespace: &str, name: &str) -> Result<Node, NodeError> {
    let node_name = NodeName::new(namespace, name).map_err(|e| NodeError::Name {
        name: format!("{namespace}/{name}"),
        message: format!("{e:?}"),
    })?;
    context
        .new_node(
            node_name,
            NodeOptions::new()
                .enable_rosout(false)
                .start_parameter_services(false),
        )
        .map_err(dds)
}

fn topic<M: RosMessage>(
    node: &mut Node,
    name: &str,
    qos: Qos,
) -> Result<ros2_client::dds::rustdds::Topic, NodeError> {
    let n = Name::parse(name).map_err(|e| NodeError::Name {
        name: name.to_owned(),
        message: format!("{e:?}"),
    })?;
    node.create_topic(
        &n,
        MessageTypeName::new(M::PACKAGE, M::NAME),
        &qos_profile(qos),
    )
    .map_err(dds)
}

/// A publisher of `M` on `name` with QoS pinned to `qos`.
///
/// # Errors
/// [`NodeError`].
pub fn publisher<M: RosMessage>(
    node: &mut Node,
    name: &str,
    qos: Qos,
) -> Result<Publisher<M>, NodeError> {
    let t = topic::<M>(node, name, qos)?;
    node.create_publisher(&t, Some(qos_profile(qos)))
        .map_err(dds)
}

/// A subscription to `M` on `name` with QoS pinned to `qos`.
///
/// # Errors
/// [`NodeError`].
pub fn subscription<M: RosMessage>(
    node: &mut Node,
    name: &str,
    qos: Qos,
) -> Result<Subscription<M>, NodeError> {
    let t = topic::<M>(node, name, qos)?;
    node.create_subscription(&t, Some(qos_profile(qos)))
        .map_err(dds)
}

/// Takes every sample available now (at most `max`); read errors (a sample
/// that does not decode) are skipped and returned, as messages, in the
/// second value.
pub fn drain<M: RosMessage>(sub: &Subscription<M>, max: usize) -> (Vec<M>, Vec<String>) {
    let (samples, errors) = drain_with_source(sub, max);
    (samples.into_iter().map(|(m, _)| m).collect(), errors)
}

/// [`drain`], with each sample's [`SampleSource`]: its writer's GUID and
/// its sequence number from that writer (for [`Bridge::on_delivery`]).
pub fn drain_with_source<M: RosMessage>(
    sub: &Subscription<M>,
    max: usize,
) -> (Vec<(M, SampleSource)>, Vec<String>) {
    let mut out = Vec::new();
    let mut errors = Vec::new();
    for _ in 0..max {
        match sub.take() {
            Ok(Some((m, info))) => {
                let mut writer = [0u8; 16];
                let gid = info.publisher_gid();
                let bytes = gid.as_bytes();
                let n = bytes.len().min(16);
                writer[..n].copy_from_slice(&bytes[..n]);
                let source = SampleSource {
                    writer,
                    sequence: info.sequence_number(),
                };
                out.push((m, source));
            }
            Ok(None) => break,
            Err(e) => errors.push(e.to_string()),
        }
    }
    (out, errors)
}

/// Takes the samples of a sensor stream available now (at most `max`):
/// each one's delivery goes to [`Bridge::on_delivery`] (loss and silence
/// accounting), then the message to `handle`; samples that fail to decode
/// go to [`Bridge::on_undecodable`].
fn feed<M: RosMessage>(
    bridge: &mut Bridge,
    sub: &Subscription<M>,
    topic: &'static str,
    max: usize,
    now: Duration,
    handle: impl Fn(&mut Bridge, &M, Duration),
) {
    let (samples, errors) = drain_with_source(sub, max);
    for e in &errors {
        bridge.on_undecodable(topic, e, now);
    }
    for (m, source) in &samples {
        bridge.on_delivery(topic, Some(*source), now);
        handle(bridge, m, now);
    }
}

/// The newest sample available now, discarding older ones.
pub fn latest<M: RosMessage>(sub: &Subscription<M>) -> Option<M> {
    drain(sub, 1000).0.pop()
}

/// The robot node over ROS 2: subscriptions, publishers and the bridge.
///
/// Fields drop in declaration order: the endpoints first, then the node,
/// then the participant's context (endpoints dropped after their
/// participant made RustDDS log 11 ERROR lines at every clean Ctrl-C).
pub struct RobotNode {
    bridge: Bridge,
    odometry: Subscription<Odometry>,
    registered: Subscription<PointCloud2>,
    terrain: Subscription<PointCloud2>,
    semantic: Subscription<PointCloud2>,
    target: Subscription<RosString>,
    cmd_vel_in: Option<Subscription<TwistStamped>>,
    way_point: Publisher<PointStamped>,
    joy: Publisher<Joy>,
    stop: Publisher<Int8>,
    status: Publisher<RosString>,
    markers: Publisher<MarkerArray>,
    path: Publisher<Path>,
    cmd_vel_out: Option<Publisher<Twist>>,
    node: Node,
    _context: Context,
    joy_readers: usize,
    joy_resend: Option<Duration>,
    started: Instant,
}

impl std::fmt::Debug for RobotNode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobotNode")
            .field("bridge", &self.bridge)
            .finish_non_exhaustive()
    }
}

impl RobotNode {
    /// Creates the participant (restricted to `ros.only_networks`), the
    /// node and every endpoint of the contract.
    ///
    /// # Errors
    /// [`NodeError`].
    pub fn new(config: ScoutConfig) -> Result<Self, NodeError> {
        let bridge = Bridge::new(config)?;
        let c = bridge.config().clone();
        let context = context(c.ros.domain_id, &c.ros.only_networks)?;
        let mut node = ros_node(&context, &c.ros.namespace, &c.ros.node_name)?;
        let t = &c.topics;
        let relay = c.relay.enabled;
        // The QoS of each endpoint comes from the contract.
        let qos = |role: &str| {
            t.qos(role)
                .ok_or_else(|| NodeError::Dds(format!("the topic contract has no role `{role}`")))
        };
        Ok(Self {
            odometry: subscription(&mut node, &t.state_estimation, qos("odometry")?)?,
            registered: subscription(&mut node, &t.registered_scan, qos("occupancy")?)?,
            terrain: subscription(&mut node, &t.terrain_map, qos("traversability")?)?,
            semantic: subscription(&mut node, &t.semantic_scan, qos("semantics")?)?,
            target: subscription(&mut node, &t.target, qos("target")?)?,
            cmd_vel_in: relay
                .then(|| subscription(&mut node, &t.cmd_vel_in, qos("cmd_vel_in")?))
                .transpose()?,
            way_point: publisher(&mut node, &t.way_point, qos("way_point")?)?,
            joy: publisher(&mut node, &t.joy, qos("joy")?)?,
            stop: publisher(&mut node, &t.stop, qos("stop")?)?,
            status: publisher(&mut node, &t.status, qos("status")?)?,
            markers: publisher(&mut node, &t.markers, qos("markers")?)?,
            path: publisher(&mut node, &t.path, qos("path")?)?,
            cmd_vel_out: relay
                .then(|| publisher(&mut node, &t.cmd_vel_out, qos("cmd_vel_out")?))
                .transpose()?,
            bridge,
            node,
            _context: context,
            joy_readers: 0,
            joy_resend: None,
            started: Instant::now(),
        })
    }

    /// The bridge (state, status, agent).
    pub fn bridge(&self) -> &Bridge {
        &self.bridge
    }

    /// Time since the node was created.
    pub fn now(&self) -> Duration {
        self.started.elapsed()
    }

    fn publish(&self, out: Vec<Outgoing>) {
        for m in out {
            let result = match m {
                Outgoing::WayPoint(m) => self.way_point.publish(m).map_err(dds),
                Outgoing::Joy(m) => self.joy.publish(m).map_err(dds),
                Outgoing::Stop(m) => self.stop.publish(m).map_err(dds),
                Outgoing::Status(m) => self.status.publish(m).map_err(dds),
                Outgoing::Markers(m) => self.markers.publish(m).map_err(dds),
                Outgoing::Path(m) => self.path.publish(m).map_err(dds),
                Outgoing::CmdVel(m) => match &self.cmd_vel_out {
                    Some(p) => p.publish(m).map_err(dds),
                    None => Ok(()),
                },
            };
            if let Err(e) = result {
                tracing::warn!("publish failed: {e}");
            }
        }
    }

    /// One round: every pending message goes to the bridge, then whatever the
    /// bridge has due is published. Also (re-)sends the autonomy-mode `/joy`
    /// and the `/stop` release whenever a new `/joy` reader is discovered
    /// (and once more a second later, in case the writer had not matched it
    /// yet): early samples are lost before discovery.
    pub fn spin_once(&mut self) {
        let now = self.now();
        let mut out = Vec::new();
        let b = &mut self.bridge;
        feed(b, &self.odometry, "odometry", 1000, now, |b, m, now| {
            let _ = b.on_odometry(m, now);
        });
        feed(b, &self.semantic, "semantic_scan", 100, now, |b, m, now| {
            let _ = b.on_semantic_scan(m, now);
        });
        feed(
            b,
            &self.registered,
            "registered_scan",
            100,
            now,
            |b, m, now| {
                let _ = b.on_registered_scan(m, now);
            },
        );
        feed(b, &self.terrain, "terrain_map", 100, now, |b, m, now| {
            let _ = b.on_terrain_map(m, now);
        });
        let (targets, e5) = drain(&self.target, 100);
        self.undecodable("target", &e5, now);
        for m in &targets {
            match self.bridge.on_target(m, now) {
                Ok(msgs) => out.extend(msgs),
                Err(e) => tracing::warn!("target request refused: {e}"),
            }
        }
        if let Some(sub) = &self.cmd_vel_in {
            let (cmds, e6) = drain(sub, 100);
            self.undecodable("cmd_vel", &e6, now);
            for m in &cmds {
                out.extend(self.bridge.on_cmd_vel(m, now));
            }
        }
        let readers = self
            .node
            .subscription_count(&self.bridge.config().topics.joy);
        if readers > self.joy_readers || self.joy_resend.is_some_and(|t| now >= t) {
            self.joy_resend = (readers > self.joy_readers).then_some(now + Duration::from_secs(1));
            out.extend(self.bridge.start(now));
        }
        self.joy_readers = readers;
        out.extend(self.bridge.tick(now));
        self.publish(out);
    }

    /// Publishes the start messages (autonomy-mode `/joy`, `/stop = 0`,
    /// status); they are re-sent when the planner's `/joy` reader appears.
    pub fn start(&mut self) {
        let now = self.now();
        let out = self.bridge.start(now);
        self.publish(out);
    }

    /// Publishes the shutdown messages (hold way point, `/stop = 2`, zero
    /// twist when relaying, final status) and keeps the participant alive
    /// for `linger` so that reliable readers receive them.
    pub fn shutdown(&mut self, linger: Duration) {
        let now = self.now();
        let out = self.bridge.shutdown(now);
        self.publish(out);
        std::thread::sleep(linger);
    }

    /// [`start`](Self::start), then [`spin_once`](Self::spin_once) every
    /// `poll` until `stop` is set, then [`shutdown`](Self::shutdown).
    pub fn run(&mut self, stop: &AtomicBool, poll: Duration, linger: Duration) {
        self.start();
        while !stop.load(Ordering::SeqCst) {
            self.spin_once();
            std::thread::sleep(poll);
        }
        self.shutdown(linger);
    }

    /// Samples that failed to decode so far
    /// ([`BridgeStats::undecodable_samples`](crate::bridge::BridgeStats::undecodable_samples)).
    pub fn read_errors(&self) -> u64 {
        self.bridge.stats().undecodable_samples
    }

    fn undecodable(&mut self, topic: &'static str, errors: &[String], now: Duration) {
        for e in errors {
            self.bridge.on_undecodable(topic, e, now);
        }
    }
}

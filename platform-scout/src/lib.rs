//! SOR-Nav on a real robot: an AgileX Scout Mini with a LiDAR, a panoramic
//! camera and the CMU autonomy stack, over ROS 2 in pure Rust
//! (`ros2-client` + RustDDS: `cargo build` is enough, no ROS install).
//!
//! # Should I use this crate?
//! Use it to drive the [`sornav::Agent`] from a ROS 2 robot whose motion
//! stack takes `geometry_msgs/PointStamped` way points (the CMU autonomy
//! stack's local planner), or to read ROS 2 messages (CDR, PointCloud2) in
//! Rust without generated bindings. The `sornav-robot` binary (in
//! `sornav-examples`) is this crate's node with a command line; the
//! simulated robot `sornav-simbot` publishes the same topics from
//! `sornav-platform-sim` for dry runs. See `docs/ROBOT.md`.
//!
//! # API themes
//! * **Messages** ([`msg`]): serde structs with the `.msg` field order of
//!   `std_msgs`, `geometry_msgs`, `nav_msgs`, `sensor_msgs` and
//!   `visualization_msgs` (Humble and later), each naming its ROS type
//!   ([`msg::RosMessage`]).
//! * **CDR** ([`cdr`]): encapsulated (de)serialisation, byte-compatible with
//!   RustDDS and `rmw`; trailing padding accepted.
//! * **PointCloud2** ([`pointcloud`]): a zero-copy decoder generic over the
//!   field layout (offsets, datatypes, endianness, point and row steps,
//!   `is_dense`) with typed errors, and an encoder.
//! * **Contract** ([`contract`]): the CMU stack's topics (configurable) with
//!   their types, directions and pinned QoS.
//! * **Configuration** ([`config`]): the Scout Mini TOML (footprint, speed
//!   limits, sensor extrinsics, arrival radii, rates, topics, the agent).
//! * **Node logic** ([`bridge`]): a pure state machine from decoded messages
//!   to messages to publish (agent at 1 Hz, arrival from odometry, clouds to
//!   observations, `/way_point`, `/joy`, status, markers, relay, shutdown);
//!   [`markers`] draws the agent's state for RViz.
//! * **DDS** ([`node`]): loopback-restricted participants, typed endpoints,
//!   and [`node::RobotNode`]. The DDS tests run inside a private network
//!   namespace (`sornav_test_support::netns`).
//!
//! # Example
//! Decoding a `/registered_scan` in PCL's padded `PointXYZI` layout
//! (x, y, z, 4 bytes of padding, intensity; 32 bytes per point) that came
//! over the wire as CDR:
//! ```
//! use sornav_platform_scout::cdr::{Endianness, decode, encode};
//! use sornav_platform_scout::msg::{Header, PointCloud2, Time};
//! use sornav_platform_scout::pointcloud::{CloudError, CloudView, encode_cloud, xyzi_fields};
//!
//! let (fields, point_step) = xyzi_fields();
//! let rows = [[1.0, 2.0, 0.3, 0.7], [4.0, -1.0, 0.0, 0.1]];
//! let cloud = encode_cloud(
//!     Header::new(Time { sec: 10, nanosec: 0 }, "map"),
//!     &fields,
//!     point_step,
//!     false,
//!     rows.iter().map(|r| &r[..]),
//! )?;
//! let bytes = encode(&cloud, Endianness::Little).unwrap();
//! let received: PointCloud2 = decode(&bytes).unwrap();
//!
//! let view = CloudView::new(&received)?;
//! assert_eq!(view.len(), 2);
//! let scan = view.points_with("intensity")?;
//! assert_eq!(scan.points[0].0.x, 1.0);
//! assert!((scan.points[1].1 - 0.1).abs() < 1e-6);
//!
//! // A cloud whose data is shorter than row_step * height is rejected.
//! let mut broken = received.clone();
//! broken.data.truncate(40);
//! assert!(matches!(CloudView::new(&broken), Err(CloudError::DataLength { .. })));
//! # Ok::<(), CloudError>(())
//! ```
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

pub mod bridge;
pub mod cdr;
pub mod config;
pub mod contract;
pub mod markers;
pub mod msg;
pub mod node;
pub mod pointcloud;
pub mod streams;

/// ros2-client and RustDDS, re-exported deliberately: [`node`] hands out
/// their (0.x) `Context`, `Node`, publisher, subscription and QoS types, so
/// callers use exactly these versions through these paths.
pub use ros2_client;
/// See [`ros2_client`].
pub use rustdds;

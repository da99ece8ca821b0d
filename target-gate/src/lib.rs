//! Target confirmation for object navigation (SOR-Nav's target gate).
//!
//! Target evidence takes precedence over everything else in SOR-Nav, but a
//! single-frame false positive must never end an episode. This crate decides
//! when a detected object of the requested category `g` is confirmed.
//!
//! A candidate is an object cluster of category `g` with at least `N_min`
//! voxels. With `z_t = 1` when the candidate is detected at update `t`, the
//! gate keeps per candidate
//!
//! * `s_t = s_{t-1} + z_t` (supporting observations) and
//! * `m_t = 0` if `z_t = 1`, else `m_{t-1} + 1` (consecutive misses),
//!
//! and confirms when `s_t >= N_obs`, `m_t <= N_miss` and `b_nav = 1` (the
//! platform reached the candidate, turned toward it and a fresh observation
//! still shows it). Defaults: `N_min = 10`, `N_obs = 3`, `N_miss = 5`.
//!
//! # Should I use this crate?
//! Use it when an object detector (any: semantic segmentation, an
//! open-vocabulary model, LiDAR labels) feeds object clusters to a robot that
//! must not stop on a single false positive: it accumulates evidence per
//! candidate, survives cluster merges and splits, and only confirms after the
//! robot has driven up to the candidate and seen it again. It is standalone
//! (nalgebra and serde only) and leaves detection, mapping and motion to you.
//! If your task ends at the first detection, you do not need it.
//!
//! # API themes
//! * [`Evidence`] and [`success`]: the two recursions and the success
//!   condition, exactly.
//! * [`CandidateTracker`]: per-candidate evidence keyed by [`ObjectId`],
//!   expiry, cluster merge/split remaps ([`CandidateTracker::apply_remap`]),
//!   optional negative evidence through a [`Visibility`] callback, and
//!   best-candidate selection: most support, then reachable, then lowest
//!   path cost ([`CandidateTracker::best_by`] with a [`PathCost`]), or
//!   nearest in a straight line ([`CandidateTracker::best`],
//!   [`StraightLine`]).
//! * [`TargetGate`]: the tracker plus the verification protocol
//!   ([`Phase`]: search -> approach -> verify -> confirmed, or rejected back
//!   to search with a cool-down), driving a [`GateCommand`].
//!   [`TargetGate::update_with`] chooses the candidate to approach by path
//!   cost on the caller's map (an object upstairs is reached over the
//!   stairs, so a nearer-looking one on the robot's floor may win);
//!   [`TargetGate::update`] keeps the straight-line tie-break.
//!
//! The crate is standalone: categories are any `PartialEq` type, positions
//! are nalgebra points, and all public data types are serde-serialisable.
//!
//! # Example
//! ```
//! use nalgebra::Point3;
//! use sornav_target_gate::{CandidateReport, GateCommand, GateConfig, ObjectId, TargetGate};
//!
//! let mut gate = TargetGate::new("toilet", GateConfig::default()).unwrap();
//! let robot = Point3::origin();
//! let seen = |detected| {
//!     vec![CandidateReport {
//!         object: ObjectId(7),
//!         category: "toilet",
//!         voxels: 40,
//!         centre: Point3::new(3.0, 1.0, 0.4),
//!         detected,
//!     }]
//! };
//! // Three detections are needed before the candidate is pursued.
//! for _ in 0..3 {
//!     gate.update(&seen(true), &robot).unwrap();
//! }
//! assert!(matches!(gate.command(), GateCommand::NavToObject { object: ObjectId(7), .. }));
//! // The platform arrives and faces it; a fresh frame still shows it.
//! gate.on_arrived(ObjectId(7)).unwrap();
//! gate.update(&seen(true), &robot).unwrap();
//! assert!(matches!(gate.command(), GateCommand::Stop { object: ObjectId(7), .. }));
//! ```
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod config;
mod error;
mod evidence;
mod gate;
mod id;
mod path_cost;
mod protocol;
mod remap;
mod report;
mod tracker;
mod visibility;

pub use config::GateConfig;
pub use error::GateError;
pub use evidence::{Evidence, success};
pub use gate::TargetGate;
pub use id::ObjectId;
pub use path_cost::{PathCost, Selection, StraightLine};
pub use protocol::{AbandonReason, GateCommand, GateEvent, Phase, RejectReason};
pub use remap::RemapSummary;
pub use report::CandidateReport;
pub use tracker::{CandidateTracker, Track, UpdateSummary};
pub use visibility::{NeverVisible, Visibility};

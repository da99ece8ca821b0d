//! Mission executor for object navigation (SOR-Nav).
//!
//! Every decision of the navigation stack becomes one mission, and exactly
//! one mission is active at a time: [`MissionKind::Explore`] a frontier,
//! [`MissionKind::Relocate`] to another region, or
//! [`MissionKind::NavToObject`] to approach a target candidate. Each mission
//! has a waypoint (a nalgebra point) and, when known, an executable path.
//!
//! # Should I use this crate?
//! Use it when a navigation stack hands goals to a motion stack one at a time
//! and needs a single place that decides when a goal is reached, stuck, timed
//! out or invalidated, and which new goal may pre-empt the active one. It
//! works on any platform through the small `MotionStack` and `Clock` traits,
//! depends only on nalgebra and serde, and knows nothing of maps or planners.
//! If your planner already owns the goal lifecycle (for example a ROS action
//! server with its own feedback), you do not need it.
//!
//! # API themes
//! * [`Executor`]: lifecycle `Active -> Reached | Failed(reason) |
//!   Preempted`, one [`ExecutorEvent::Finished`] per mission.
//! * Arrival from the pose ([`arrived`], per-kind [`ArrivalRule`] with an
//!   optional heading requirement), since motion stacks such as CMU's
//!   autonomy stack emit no "reached" signal.
//! * Distinct failure reasons ([`FailureReason`]): stuck ([`StuckDetector`]
//!   over [`remaining_distance`] along the path), timeout, path invalidated
//!   by the map ([`PathValidity`]), dispatch refused.
//! * SOR-Nav's pre-emption rules ([`admit`]): target pursuit pre-empts
//!   exploration; exploration does not interrupt an active relocation;
//!   completing a relocation asks for global exploration from the new region
//!   ([`ExecutorEvent::ExploreFromRegion`]) and is never a task completion.
//! * Platforms implement [`MotionStack`]; time comes from any [`Clock`]
//!   ([`SimClock`] for simulated steps, [`WallClock`] for robots).
//!
//! The crate is standalone; all public data types are serde-serialisable.
//!
//! # Example
//! ```
//! use std::time::Duration;
//! use nalgebra::Point3;
//! use sornav_executor::*;
//!
//! /// A motion stack that only remembers what it was told.
//! #[derive(Default)]
//! struct Recorder(Vec<Point3<f64>>);
//! impl MotionStack for Recorder {
//!     fn dispatch(&mut self, m: &Mission) -> Result<(), MotionError> {
//!         self.0.push(m.waypoint);
//!         Ok(())
//!     }
//!     fn cancel(&mut self) {}
//! }
//!
//! let clock = SimClock::new(Duration::from_millis(500));
//! let mut exec = Executor::new(ExecutorConfig::default(), Recorder::default(), clock).unwrap();
//! let relocate = Mission::new(MissionKind::Relocate { cluster: ClusterId(4) }, Point3::new(10.0, 0.0, 0.0));
//! let id = exec.submit(relocate).unwrap().id().unwrap();
//!
//! // Exploration decisions do not interrupt an active relocation.
//! let explore = Mission::new(MissionKind::Explore { frontier: FrontierId(1) }, Point3::new(0.0, 5.0, 0.0));
//! assert!(matches!(exec.submit(explore).unwrap(), Submission::Refused { .. }));
//!
//! // The robot arrives: the relocation is reached and global exploration is requested.
//! exec.clock_mut().advance(10);
//! let pose = RobotPose::new(Point3::new(9.5, 0.2, 0.0), 0.0);
//! let outcome = exec.tick(&pose, &AlwaysValid).unwrap().unwrap();
//! assert_eq!((outcome.id, outcome.status.clone()), (id, MissionStatus::Reached));
//! assert!(!outcome.is_target_arrival());
//! let events = exec.drain_events();
//! assert!(matches!(events[1], ExecutorEvent::ExploreFromRegion { cluster: ClusterId(4), .. }));
//! ```
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

mod arrival;
mod clock;
mod config;
mod error;
mod executor;
mod id;
mod mission;
mod motion;
mod outcome;
mod preemption;
mod progress;

pub use arrival::{angle_difference, arrived};
pub use clock::{Clock, SimClock, WallClock};
pub use config::{ArrivalRule, ExecutorConfig, KindConfig};
pub use error::{ExecError, MotionError};
pub use executor::{Executor, Submission};
pub use id::{ClusterId, FrontierId, MissionId, ObjectId};
pub use mission::{Mission, MissionKind, RobotPose};
pub use motion::{AlwaysValid, MotionStack, PathValidity};
pub use outcome::{ExecutorEvent, FailureReason, MissionOutcome, MissionStatus};
pub use preemption::{Admission, RefusalReason, admit};
pub use progress::{StuckDetector, remaining_distance};

//! The runnable programs of sornav and the library code behind them.
//!
//! * [`adapter`]: the SOR-Nav [`Agent`](sornav::Agent) on platform-sim's
//!   ObjectNav protocol ([`adapter::SornavPolicy`]): 12 scan turns, path
//!   following on the agent's own map, verification turns, STOP on
//!   confirmation.
//! * [`harness`]: the evaluation behind `sornav-sim` — scenes
//!   ([`scenes`]), generated or Habitat episodes, the five variants,
//!   parallel jobs, resume, shards and [`harness::merge`].
//! * [`record`], [`summary`], [`report`], [`figures`], [`topdown`]: the
//!   outputs (`episodes.jsonl`, `summary.json`, `report.md`, PNG figures
//!   and top-down maps).
//! * [`failure_analysis`]: the report's failure analysis (example maps per
//!   failure class).
//! * [`output`]: the output directory's lock and atomic file writes.
//! * [`compare`]: the paired comparison of two runs (`sornav-sim compare`).
//! * [`ros`]: the start-up shared by the ROS 2 binaries `sornav-robot` and
//!   `sornav-simbot` (logging, Ctrl-C).
//!
//! These modules hold no navigation algorithm: the algorithms live in the
//! `sornav-*` crates and the simulator in `sornav-platform-sim`.
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod adapter;
pub mod compare;
pub mod decision_log;
pub mod failure_analysis;
pub mod figures;
pub mod harness;
pub mod histogram;
pub mod output;
pub mod record;
pub mod report;
pub mod ros;
pub mod scenes;
pub mod summary;
pub mod topdown;
pub mod walk;

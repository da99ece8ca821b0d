//! Mutation fuzz targets for every parser and decoder of sornav, on the
//! stable toolchain (no nightly, no libFuzzer).
//!
//! # Should I use this crate?
//! It is the workspace's own robustness check, not a published library: run
//! the `sornav-fuzz` binary (see the README) or the short test in CI.
//!
//! # API themes
//! * [`targets`]: one [`targets::Target`] per parser (glTF/GLB, Sweet Home 3D
//!   XML and `.sh3d` ZIP, OBJ, Habitat JSON and JSON.gz, TSPLIB instances and
//!   tours, CDR messages, PointCloud2 decoding, LLM answers, the agent and
//!   robot TOML configs), with built-in seeds plus the real files of
//!   `../shared/data`.
//! * [`mutate`]: the seeded mutation engine (flips, inserts, deletes,
//!   splices and cross-overs of corpus entries, interesting integers and
//!   numbers as text, dictionary tokens).
//! * [`run`]: the loop. A parser may return `Ok` or `Err`; a panic, an abort
//!   or exceeding the time or memory bound is a crash, saved to disk.
//!
//! # Example
//! ```
//! use std::time::Duration;
//! use sornav_fuzz::{run, targets};
//! let target = targets::find("tsplib-tour").unwrap();
//! let options = run::Options { duration: Duration::from_millis(100), ..Default::default() };
//! let report = run::run(&target, &options)?;
//! assert!(report.inputs > 0);
//! assert_eq!(report.crashes, 0);
//! # Ok::<(), run::FuzzError>(())
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

/// The README's example, compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod mutate;
pub mod run;
pub mod targets;

//! Locates sornav's shared, real test data and applies the project's rule for
//! tests that depend on it.
//!
//! The data lives outside the repository, in `../shared/data` relative to the
//! workspace root (override with the `SORNAV_SHARED` environment variable,
//! which names the `shared` directory itself). It is never copied into the
//! repository.
//!
//! * [`shared_data`] returns `Some(path)` when the requested file or folder
//!   exists. When it does not, it panics with a clear message if `CI=true`
//!   (CI must never silently skip), and otherwise prints a skip message and
//!   returns `None`.
//! * [`shared_root`] only locates the root, without the rule.
//! * [`chat_server`] is a loopback OpenAI-compatible server for the tests
//!   of the LLM context policy.
//! * [`log_capture::LogSink`] captures log output in memory.
//! * [`netns`] runs DDS tests inside a private network namespace
//!   (`unshare --net`, only `lo`).
//!
//! # Example
//! ```no_run
//! let Some(dir) = sornav_test_support::shared_data("tsp-fuel") else {
//!     return; // skipped: data not present on this machine
//! };
//! assert!(dir.join("reference.tsv").is_file());
//! ```
#![forbid(unsafe_code)]
#![cfg_attr(docsrs, feature(doc_cfg))]
#![deny(missing_docs)]

/// The README's examples, compiled and run as doctests.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

pub mod chat_server;
pub mod log_capture;
pub mod netns;

use std::path::{Path, PathBuf};

/// The `shared` directory: `$SORNAV_SHARED` if set, else `<workspace>/../shared`.
///
/// The returned path may not exist.
pub fn shared_root() -> PathBuf {
    if let Some(p) = std::env::var_os("SORNAV_SHARED") {
        return PathBuf::from(p);
    }
    // test-support lives one level below the workspace root.
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("..")
        .join("shared")
}

/// Whether we run under CI (`CI` set to `true` or `1`).
pub fn in_ci() -> bool {
    matches!(
        std::env::var("CI")
            .as_deref()
            .map(str::to_ascii_lowercase)
            .as_deref(),
        Ok("true") | Ok("1")
    )
}

/// Path of `shared/data/<rel>` if it exists.
///
/// # Panics
/// When the path is missing and [`in_ci`] is true: CI must not pass by
/// skipping the tests that use real data. Outside CI a missing path prints a
/// skip message to stderr and returns `None`.
pub fn shared_data(rel: &str) -> Option<PathBuf> {
    let path = shared_root().join("data").join(rel);
    if path.exists() {
        return Some(path);
    }
    if in_ci() {
        panic!(
            "shared test data missing: {} (expected ../shared beside the repository, \
             or set SORNAV_SHARED); CI=true, so this is a failure, not a skip",
            path.display()
        );
    }
    eprintln!(
        "SKIPPED: shared test data not found at {} (set SORNAV_SHARED or place ../shared beside the repository)",
        path.display()
    );
    None
}

/// Path of `shared/tools/<rel>` if it exists (no CI rule: tools are optional).
pub fn shared_tool(rel: &str) -> Option<PathBuf> {
    let path = shared_root().join("tools").join(rel);
    path.exists().then_some(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn root_points_beside_the_workspace() {
        let root = shared_root();
        assert!(root.ends_with("shared") || std::env::var_os("SORNAV_SHARED").is_some());
    }

    #[test]
    fn missing_path_is_none_outside_ci() {
        if in_ci() {
            return;
        }
        assert!(shared_data("definitely/not/here.xyz").is_none());
    }
}

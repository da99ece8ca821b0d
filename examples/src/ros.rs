//! Start-up shared by the ROS 2 binaries (`sornav-robot`, `sornav-simbot`):
//! logging to stderr and a stop flag set by Ctrl-C.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Logs `tracing` events to stderr, filtered by `RUST_LOG` (default
/// `info`).
///
/// # Panics
/// When a global subscriber is already installed (call it once, first).
pub fn init_logging() {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()),
        )
        .with_writer(std::io::stderr)
        .init();
}

/// A flag that Ctrl-C sets (the process keeps running: the caller polls the
/// flag and shuts down in order).
///
/// # Errors
/// When the handler cannot be installed (there is one per process).
pub fn stop_on_ctrl_c() -> Result<Arc<AtomicBool>, ctrlc::Error> {
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst))?;
    Ok(stop)
}

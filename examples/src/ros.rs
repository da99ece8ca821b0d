//! Start-up shared by the ROS 2 binaries (`sornav-robot`, `sornav-simbot`):
//! logging to stderr and a stop flag set by Ctrl-C.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// The log filter when `RUST_LOG` is not set: `info`, but RustDDS at
/// `warn` (with reliable cloud publishers it logs about 7,100
/// "HeartbeatFrag handling not implemented" lines a minute at `info`), two
/// of its modules at `error`, and ros2-client's check of `ROS_DISTRO` at
/// `error` (no ROS install is needed, so "ROS_DISTRO is not set" is no
/// news). The two modules warn at every send, not once: in the 30-minute
/// robot soak (README) `rustdds::rtps::writer` logged "No locators for
/// RtpsReaderProxy" about 1,300 times a minute on a loopback-only
/// participant (1.7 MB of log a minute) and `rustdds::network::udp_sender`
/// "try_send_to_locator: Message size = ..." at every fragmented cloud
/// (3 MB a minute in `sornav-simbot`). Their errors still show; set
/// `RUST_LOG` to see their warnings.
pub const DEFAULT_LOG_FILTER: &str = "info,rustdds=warn,rustdds::rtps::writer=error,\
rustdds::network::udp_sender=error,ros2_client::distributions=error";

/// The log filter: `RUST_LOG` when set (and valid), else
/// [`DEFAULT_LOG_FILTER`].
pub fn log_filter() -> tracing_subscriber::EnvFilter {
    tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(DEFAULT_LOG_FILTER))
}

/// Logs `tracing` events (and the `log` records of RustDDS and ros2-client)
/// to stderr, filtered by [`log_filter`].
///
/// # Panics
/// When a global subscriber is already installed (call it once, first).
pub fn init_logging() {
    tracing_subscriber::fmt()
        .with_env_filter(log_filter())
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

#[cfg(test)]
mod tests {
    use tracing_subscriber::layer::SubscriberExt;

    use super::DEFAULT_LOG_FILTER;

    /// Issue 21: the default filter keeps RustDDS at warn (but its two
    /// per-send warnings) and our own crates at info.
    #[test]
    fn default_filter_keeps_rustdds_at_warn() {
        let sink = sornav_test_support::log_capture::LogSink::default();
        let writer = sink.clone();
        let subscriber = tracing_subscriber::registry()
            .with(tracing_subscriber::EnvFilter::new(DEFAULT_LOG_FILTER))
            .with(
                tracing_subscriber::fmt::layer()
                    .with_ansi(false)
                    .with_writer(move || writer.clone()),
            );
        tracing::subscriber::with_default(subscriber, || {
            tracing::info!(target: "rustdds::rtps::reader", "HeartbeatFrag handling not implemented");
            tracing::warn!(target: "rustdds::discovery", "dds warning kept");
            tracing::warn!(target: "rustdds::rtps::writer", "No locators for RtpsReaderProxy");
            tracing::warn!(target: "rustdds::network::udp_sender", "Message size = 65348");
            tracing::error!(target: "rustdds::rtps::writer", "dds error kept");
            tracing::warn!(target: "ros2_client::distributions", "ROS_DISTRO is not set");
            tracing::info!(target: "sornav_platform_scout::bridge", "bridge info kept");
        });
        let text = sink.text();
        assert!(!text.contains("HeartbeatFrag"), "{text}");
        assert!(!text.contains("ROS_DISTRO"), "{text}");
        assert!(
            !text.contains("No locators") && !text.contains("Message size"),
            "{text}"
        );
        assert!(text.contains("dds error kept"), "{text}");
        assert!(
            text.contains("dds warning kept") && text.contains("bridge info kept"),
            "{text}"
        );
    }
}

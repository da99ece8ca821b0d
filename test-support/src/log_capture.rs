//! An in-memory log writer for tests that check what was logged.

use std::sync::{Arc, Mutex, PoisonError};

/// A cloneable `io::Write` whose clones share one buffer: hand a clone to
/// a logger (e.g. `tracing_subscriber::fmt::layer().with_writer(move ||
/// sink.clone())`) and read everything written with [`LogSink::text`].
#[derive(Debug, Clone, Default)]
pub struct LogSink(Arc<Mutex<Vec<u8>>>);

impl LogSink {
    /// Everything written so far (invalid UTF-8 replaced).
    pub fn text(&self) -> String {
        let bytes = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        String::from_utf8_lossy(&bytes).into_owned()
    }
}

impl std::io::Write for LogSink {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .extend_from_slice(b);
        Ok(b.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

//! Input stream health: samples lost *before* they reach the bridge.
//!
//! DDS does not always say when it loses a sample. RustDDS (0.15) drops a
//! fragmented sample it cannot reassemble (for example a point cloud of
//! more than about 10 MB on a best-effort reader, whose fragments overflow
//! the socket buffer on loopback) without any status event, and a reader
//! that is not matched, or a publisher that stalls, looks the same: nothing
//! arrives. So the bridge watches every sensor stream itself:
//!
//! * **Gaps.** A [`StreamMonitor`] keeps the last [`PERIOD_WINDOW`]
//!   intervals between consecutive samples (header stamps; the arrival time
//!   for unstamped messages) and takes their median as the stream's period.
//!   An interval longer than [`GAP_FACTOR`] periods is a gap of
//!   `round(interval / period) - 1` missing samples. The count is an
//!   *estimate*: exact for a periodic publisher while the stamps' jitter
//!   and the period estimate's error, summed over the gap, stay under half
//!   a period (property-tested against the dropped set with 2 % jitter and
//!   up to 5 samples lost in a row); rough for a publisher without a
//!   steady rate.
//! * **Silence.** A stream that delivered samples and then nothing for
//!   `max(SILENCE_MIN, SILENCE_PERIODS x period)` is *silent*: counted once
//!   per silence and logged at warn, and logged again when it resumes. Every
//!   sample of a stream vanishing (each cloud above the reassembly limit)
//!   shows up here.
//!
//! The counts are in the status document ([`crate::bridge::Status::streams`]).
//! Complexity: `O(PERIOD_WINDOW log PERIOD_WINDOW)` per sample (the median
//! of a small window), `O(1)` per silence check.

use std::collections::VecDeque;
use std::time::Duration;

use serde::{Deserialize, Serialize};

/// Intervals kept for the period estimate.
pub const PERIOD_WINDOW: usize = 16;
/// Intervals needed before gaps are counted.
pub const MIN_INTERVALS: usize = 4;
/// An interval of more than this many periods is a gap.
pub const GAP_FACTOR: f64 = 1.8;
/// A stream is silent after at least this long without a sample.
pub const SILENCE_MIN: Duration = Duration::from_secs(5);
/// ... and at least this many periods.
pub const SILENCE_PERIODS: f64 = 10.0;

/// Samples missing between two consecutive samples of a stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gap {
    /// Estimated samples missing.
    pub missing: u64,
    /// The interval between the two samples (s).
    pub interval_s: f64,
    /// The stream's period when the gap was seen (s).
    pub period_s: f64,
}

/// What happened to a stream's silence at a check.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Silence {
    /// The stream has just become silent, `for_s` seconds after its last
    /// sample.
    Began {
        /// Seconds since the last sample.
        for_s: f64,
    },
    /// A sample arrived after a silence of `lasted_s` seconds.
    Ended {
        /// Seconds between the last sample before the silence and this one.
        lasted_s: f64,
    },
}

/// Health of one input stream, as reported in the status.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StreamStatus {
    /// Samples that arrived (decoded, whether used or rejected afterwards).
    pub received: u64,
    /// Gaps seen (intervals of more than [`GAP_FACTOR`] periods).
    pub gaps: u64,
    /// Estimated samples missing in those gaps.
    pub missing_estimate: u64,
    /// Times the stream fell silent.
    pub silences: u64,
    /// Whether it is silent now.
    pub silent: bool,
    /// The period estimate (s), once [`MIN_INTERVALS`] intervals are known.
    pub period_s: Option<f64>,
    /// Seconds since the last sample (node clock).
    pub last_age_s: Option<f64>,
}

/// Watches one stream's sample times; see the [module docs](self).
#[derive(Debug, Clone, Default)]
pub struct StreamMonitor {
    intervals: VecDeque<f64>,
    last_time: Option<f64>,
    last_arrival: Option<Duration>,
    status: StreamStatus,
}

impl StreamMonitor {
    /// A monitor that has seen nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// The period estimate (s): the median of the last intervals, once
    /// [`MIN_INTERVALS`] are known.
    pub fn period_s(&self) -> Option<f64> {
        if self.intervals.len() < MIN_INTERVALS {
            return None;
        }
        let mut v: Vec<f64> = self.intervals.iter().copied().collect();
        v.sort_by(f64::total_cmp);
        Some(v[v.len() / 2])
    }

    /// A sample arrived at `now` (node clock) with header time `stamp_s`
    /// (seconds; `None` or non-finite for an unstamped message, which uses
    /// the arrival time). Returns the gap before it, if any, and whether
    /// it ended a silence.
    ///
    /// A time that does not increase (a restarted publisher, reordering)
    /// restarts the interval chain without counting anything.
    pub fn on_sample(
        &mut self,
        stamp_s: Option<f64>,
        now: Duration,
    ) -> (Option<Gap>, Option<Silence>) {
        let t = stamp_s
            .filter(|s| s.is_finite())
            .unwrap_or(now.as_secs_f64());
        let ended = if self.status.silent {
            self.status.silent = false;
            self.last_arrival.map(|a| Silence::Ended {
                lasted_s: now.saturating_sub(a).as_secs_f64(),
            })
        } else {
            None
        };
        self.status.received += 1;
        self.last_arrival = Some(now);
        let previous = self.last_time.replace(t);
        let Some(dt) = previous
            .map(|p| t - p)
            .filter(|dt| *dt > 0.0 && dt.is_finite())
        else {
            return (None, ended);
        };
        if let Some(period) = self.period_s().filter(|p| *p > 0.0)
            && dt > GAP_FACTOR * period
        {
            // Saturating float-to-int cast: a huge jump counts u64::MAX.
            let missing = ((dt / period).round() as u64).saturating_sub(1).max(1);
            self.status.gaps += 1;
            self.status.missing_estimate = self.status.missing_estimate.saturating_add(missing);
            let gap = Gap {
                missing,
                interval_s: dt,
                period_s: period,
            };
            return (Some(gap), ended);
        }
        if self.intervals.len() == PERIOD_WINDOW {
            self.intervals.pop_front();
        }
        self.intervals.push_back(dt);
        (None, ended)
    }

    /// Checks for silence at `now`: returns [`Silence::Began`] once when a
    /// stream that delivered samples has had none for `max(SILENCE_MIN,
    /// SILENCE_PERIODS x period)`.
    pub fn check_silence(&mut self, now: Duration) -> Option<Silence> {
        let last = self.last_arrival?;
        if self.status.silent {
            return None;
        }
        let quiet = now.saturating_sub(last).as_secs_f64();
        let limit = self
            .period_s()
            .map_or(0.0, |p| SILENCE_PERIODS * p)
            .max(SILENCE_MIN.as_secs_f64());
        if quiet < limit {
            return None;
        }
        self.status.silent = true;
        self.status.silences += 1;
        Some(Silence::Began { for_s: quiet })
    }

    /// The stream's status at `now`.
    pub fn status(&self, now: Duration) -> StreamStatus {
        StreamStatus {
            period_s: self.period_s(),
            last_age_s: self
                .last_arrival
                .map(|a| now.saturating_sub(a).as_secs_f64()),
            ..self.status
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn at(s: f64) -> Duration {
        Duration::from_secs_f64(s)
    }

    #[test]
    fn a_regular_stream_has_no_gaps_and_one_dropped_sample_is_one_missing() {
        let mut m = StreamMonitor::new();
        for i in 0..10 {
            let t = 100.0 + 0.1 * f64::from(i);
            assert_eq!(m.on_sample(Some(t), at(t)).0, None);
        }
        // Sample 10 dropped.
        let (gap, _) = m.on_sample(Some(101.1), at(101.1));
        let gap = gap.expect("a gap");
        assert_eq!(gap.missing, 1);
        approx::assert_relative_eq!(gap.period_s, 0.1, epsilon = 1e-9);
        let s = m.status(at(101.1));
        assert_eq!((s.received, s.gaps, s.missing_estimate), (11, 1, 1));
    }

    #[test]
    fn silence_begins_once_and_ends_with_the_next_sample() {
        let mut m = StreamMonitor::new();
        assert_eq!(m.check_silence(at(100.0)), None, "nothing seen yet");
        for i in 0..6 {
            let t = f64::from(i) * 0.1;
            m.on_sample(None, at(t));
        }
        assert_eq!(m.check_silence(at(4.0)), None);
        assert!(matches!(
            m.check_silence(at(5.6)),
            Some(Silence::Began { .. })
        ));
        assert_eq!(m.check_silence(at(9.0)), None, "counted once");
        assert!(m.status(at(9.0)).silent);
        let (_, ended) = m.on_sample(None, at(10.5));
        assert!(
            matches!(ended, Some(Silence::Ended { lasted_s }) if (lasted_s - 10.0).abs() < 1e-9)
        );
        let s = m.status(at(10.5));
        assert!(!s.silent);
        assert_eq!(s.silences, 1);
    }

    #[test]
    fn stamps_that_go_back_restart_the_chain_without_counting() {
        let mut m = StreamMonitor::new();
        for i in 0..8 {
            m.on_sample(Some(50.0 + f64::from(i)), at(f64::from(i)));
        }
        // Publisher restarted: stamps from an earlier clock.
        assert_eq!(m.on_sample(Some(10.0), at(8.0)).0, None);
        assert_eq!(m.on_sample(Some(11.0), at(9.0)).0, None);
        assert_eq!(m.status(at(9.0)).missing_estimate, 0);
    }

    #[test]
    fn non_finite_stamps_use_the_arrival_time() {
        let mut m = StreamMonitor::new();
        for i in 0..6 {
            let t = f64::from(i);
            let stamp = if i % 2 == 0 { f64::NAN } else { f64::INFINITY };
            m.on_sample(Some(stamp), at(t));
        }
        let p = m.period_s().expect("period");
        approx::assert_relative_eq!(p, 1.0, epsilon = 1e-9);
    }

    proptest! {
        /// Differential test against the dropped set itself: a periodic
        /// publisher (period p, stamps jittered by up to 2 % of p) whose
        /// first samples arrive and up to 5 in a row of the later ones are
        /// dropped; the estimate equals the number of dropped samples
        /// between the first and the last received one (drops after the
        /// last sample are silence, not gaps).
        #[test]
        fn missing_estimate_counts_the_dropped_samples(
            period in 0.01f64..2.0,
            jitter in proptest::collection::vec(-0.02f64..0.02, 20..200),
            drops in proptest::collection::vec(0.0f64..1.0, 20..200),
            rate in 0.0f64..0.5,
        ) {
            let n = jitter.len().min(drops.len());
            let keep: Vec<bool> = (0..n)
                .map(|i| i < MIN_INTERVALS + 2 || i % 6 == 5 || drops[i] >= rate)
                .collect();
            let mut m = StreamMonitor::new();
            for i in (0..n).filter(|&i| keep[i]) {
                let t = 1000.0 + (i as f64 + jitter[i]) * period;
                m.on_sample(Some(t), at(i as f64));
            }
            let last = (0..n).rev().find(|&i| keep[i]).unwrap();
            let dropped = (0..last).filter(|&i| !keep[i]).count() as u64;
            let s = m.status(at(n as f64));
            prop_assert_eq!(s.missing_estimate, dropped);
            prop_assert_eq!(s.received, keep.iter().filter(|k| **k).count() as u64);
            prop_assert!(s.gaps <= s.missing_estimate);
        }

        /// Any times (including NaN, infinities, repeats and jumps back)
        /// never panic, and the counters stay consistent.
        #[test]
        fn arbitrary_times_keep_the_counters_consistent(
            samples in proptest::collection::vec((proptest::option::of(proptest::num::f64::ANY), 0u64..10_000), 0..100),
        ) {
            let mut m = StreamMonitor::new();
            let mut now = 0u64;
            for (stamp, dt_ms) in samples {
                now += dt_ms;
                m.on_sample(stamp, Duration::from_millis(now));
                m.check_silence(Duration::from_millis(now + dt_ms));
            }
            let s = m.status(Duration::from_millis(now));
            prop_assert!(s.gaps <= s.missing_estimate);
            prop_assert!(s.period_s.is_none_or(|p| p.is_finite() && p > 0.0));
        }
    }
}

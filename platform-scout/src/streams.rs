//! Input stream health: samples lost *before* they reach the bridge.
//!
//! DDS does not always say when it loses a sample. RustDDS (0.15) drops a
//! fragmented sample it cannot reassemble (for example a point cloud of
//! more than about 10 MB on a best-effort reader, whose fragments overflow
//! the socket buffer on loopback) without any status event, a best-effort
//! reader loses whatever the network drops, and a reader's history
//! (`KEEP_LAST`) overwrites samples not taken in time. So the node watches
//! every input stream itself:
//!
//! * **Lost samples**, exactly: every DDS writer numbers its samples
//!   1, 2, 3, ... (the RTPS sequence number, carried to the reader with the
//!   writer's GUID). A [`StreamMonitor`] remembers the last number taken
//!   from each writer; a jump from `a` to `b > a + 1` is a gap of `b - a -
//!   1` samples that never reached the node, whatever lost them. A sample
//!   that arrived but failed to decode also leaves a gap (it is counted
//!   separately as undecodable as well). Timing plays no part, so a
//!   publisher that is late or irregular never counts as a loss.
//! * **Silence.** A stream that delivered samples and then nothing for
//!   `max(SILENCE_MIN, SILENCE_PERIODS x period)` is *silent* (the period is
//!   the median of the last [`PERIOD_WINDOW`] intervals between arrivals):
//!   counted once per silence and logged at warn, and logged again when it
//!   resumes. When *every* sample of a stream is lost (each cloud above the
//!   reassembly limit), nothing arrives to number: this is how it shows.
//!
//! The counts are in the status document ([`crate::bridge::Status::streams`]).
//! Complexity: `O(log W + PERIOD_WINDOW log PERIOD_WINDOW)` per sample for
//! `W` writers remembered (at most [`MAX_WRITERS`]; `O(W)` more for the
//! sample that makes one too many), `O(1)` per silence check and status.

use std::collections::{BTreeMap, VecDeque};
use std::time::Duration;

use serde::{Deserialize, Serialize};

/// Arrival intervals kept for the period estimate.
pub const PERIOD_WINDOW: usize = 16;
/// Intervals needed before the period is known.
pub const MIN_INTERVALS: usize = 4;
/// A stream is silent after at least this long without a sample.
pub const SILENCE_MIN: Duration = Duration::from_secs(5);
/// ... and at least this many periods.
pub const SILENCE_PERIODS: f64 = 10.0;
/// Writers remembered per stream; when more appear (writers restarting
/// again and again), the oldest entries are forgotten (their next sample
/// starts a new chain and counts nothing).
pub const MAX_WRITERS: usize = 64;

/// Where a sample came from: its DDS writer and its number from that
/// writer (RTPS sequence number, 1 for the first sample).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct SampleSource {
    /// The writer's GUID.
    pub writer: [u8; 16],
    /// The sample's sequence number from that writer.
    pub sequence: i64,
}

/// Samples missing between two consecutive samples of one writer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Gap {
    /// Samples that never arrived.
    pub missing: u64,
    /// The sequence number taken before the gap.
    pub after: i64,
    /// The sequence number that ended it.
    pub next: i64,
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
    /// Gaps in the writers' sequence numbers.
    pub gaps: u64,
    /// Samples lost in those gaps (sent by a writer, never taken here).
    pub lost: u64,
    /// Times the stream fell silent.
    pub silences: u64,
    /// Whether it is silent now.
    pub silent: bool,
    /// The period estimate between arrivals (s), once [`MIN_INTERVALS`]
    /// intervals are known.
    pub period_s: Option<f64>,
    /// Seconds since the last sample (node clock).
    pub last_age_s: Option<f64>,
}

/// Watches one stream; see the [module docs](self).
#[derive(Debug, Clone, Default)]
pub struct StreamMonitor {
    intervals: VecDeque<f64>,
    /// The median of `intervals`, updated when a sample arrives (silence
    /// checks and status reads, which run far more often, only read it).
    period: Option<f64>,
    last_arrival: Option<Duration>,
    /// Last sequence number taken per writer, with the arrival count when
    /// it was last seen (to forget the oldest writer first).
    writers: BTreeMap<[u8; 16], (i64, u64)>,
    status: StreamStatus,
}

impl StreamMonitor {
    /// A monitor that has seen nothing.
    pub fn new() -> Self {
        Self::default()
    }

    /// The period estimate between arrivals (s): the median of the last
    /// intervals, once [`MIN_INTERVALS`] are known.
    pub fn period_s(&self) -> Option<f64> {
        self.period
    }

    /// A sample arrived at `now` (node clock) from `source` (`None` when
    /// the transport does not say). Returns the gap in its writer's
    /// numbering before it, if any, and whether it ended a silence.
    ///
    /// A number that does not increase (a duplicate, reordering) counts
    /// nothing and restarts that writer's chain.
    pub fn on_sample(
        &mut self,
        source: Option<SampleSource>,
        now: Duration,
    ) -> (Option<Gap>, Option<Silence>) {
        let ended = if self.status.silent {
            self.status.silent = false;
            self.last_arrival.map(|a| Silence::Ended {
                lasted_s: now.saturating_sub(a).as_secs_f64(),
            })
        } else {
            None
        };
        self.status.received += 1;
        if let Some(dt) = self
            .last_arrival
            .map(|a| now.saturating_sub(a).as_secs_f64())
            .filter(|dt| *dt > 0.0)
        {
            if self.intervals.len() == PERIOD_WINDOW {
                self.intervals.pop_front();
            }
            self.intervals.push_back(dt);
            if self.intervals.len() >= MIN_INTERVALS {
                let mut v: Vec<f64> = self.intervals.iter().copied().collect();
                v.sort_by(f64::total_cmp);
                self.period = Some(v[v.len() / 2]);
            }
        }
        self.last_arrival = Some(now);
        let Some(source) = source else {
            return (None, ended);
        };
        let arrival = self.status.received;
        let previous = self
            .writers
            .insert(source.writer, (source.sequence, arrival))
            .map(|(seq, _)| seq);
        if self.writers.len() > MAX_WRITERS
            && let Some(oldest) = self
                .writers
                .iter()
                .min_by_key(|(_, (_, seen))| *seen)
                .map(|(w, _)| *w)
        {
            self.writers.remove(&oldest);
        }
        let gap = previous
            .filter(|after| source.sequence > after.saturating_add(1))
            .map(|after| Gap {
                missing: source.sequence.abs_diff(after) - 1,
                after,
                next: source.sequence,
            });
        if let Some(g) = gap {
            self.status.gaps += 1;
            self.status.lost = self.status.lost.saturating_add(g.missing);
        }
        (gap, ended)
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

    fn from(writer: u8, sequence: i64) -> Option<SampleSource> {
        Some(SampleSource {
            writer: [writer; 16],
            sequence,
        })
    }

    #[test]
    fn a_jump_in_a_writers_numbers_is_a_gap_whatever_the_timing() {
        let mut m = StreamMonitor::new();
        for seq in 1..=10 {
            // irregular arrivals: never a loss by themselves
            let t = f64::from(seq as u32).powf(1.5);
            assert_eq!(m.on_sample(from(1, seq), at(t)).0, None);
        }
        let (gap, _) = m.on_sample(from(1, 13), at(40.0));
        assert_eq!(
            gap,
            Some(Gap {
                missing: 2,
                after: 10,
                next: 13
            })
        );
        // another writer on the same topic has its own numbering
        assert_eq!(m.on_sample(from(2, 1), at(41.0)).0, None);
        assert_eq!(m.on_sample(from(2, 2), at(42.0)).0, None);
        // a duplicate or a reordered sample counts nothing
        assert_eq!(m.on_sample(from(1, 12), at(43.0)).0, None);
        let s = m.status(at(43.0));
        assert_eq!((s.received, s.gaps, s.lost), (14, 1, 2));
    }

    #[test]
    fn silence_begins_once_and_ends_with_the_next_sample() {
        let mut m = StreamMonitor::new();
        assert_eq!(m.check_silence(at(100.0)), None, "nothing seen yet");
        for i in 0..6 {
            m.on_sample(None, at(f64::from(i) * 0.1));
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
    fn a_slow_stream_is_silent_only_after_ten_periods() {
        let mut m = StreamMonitor::new();
        for i in 0..8 {
            m.on_sample(None, at(f64::from(i) * 2.0));
        }
        assert_eq!(m.status(at(14.0)).period_s, Some(2.0));
        assert_eq!(m.check_silence(at(14.0 + 19.0)), None);
        assert!(m.check_silence(at(14.0 + 20.5)).is_some());
    }

    #[test]
    fn the_oldest_writer_is_forgotten_beyond_the_cap() {
        let mut m = StreamMonitor::new();
        for w in 0..=MAX_WRITERS as u8 {
            m.on_sample(from(w, 1), at(f64::from(w)));
        }
        // writer 0 was forgotten: its next sample starts a new chain
        assert_eq!(m.on_sample(from(0, 5), at(100.0)).0, None);
        // ... which pushed out writer 1, the oldest then; the newest is
        // remembered
        assert_eq!(m.on_sample(from(1, 5), at(101.0)).0, None);
        assert!(
            m.on_sample(from(MAX_WRITERS as u8, 5), at(102.0))
                .0
                .is_some()
        );
    }

    proptest! {
        /// Differential test against the dropped set itself: up to three
        /// writers interleaved on one topic, each numbering its samples
        /// 1, 2, 3, ...; some samples are dropped. The monitor's `lost`
        /// equals the number of dropped samples between each writer's
        /// first and last delivered one (the ones after the last are
        /// silence, not gaps), whatever the arrival times.
        #[test]
        fn lost_counts_exactly_the_dropped_samples(
            sends in proptest::collection::vec((0u8..3, any::<bool>(), 0u64..2000), 1..300),
        ) {
            let mut m = StreamMonitor::new();
            let mut next = [0i64; 3];
            let mut delivered: [Vec<i64>; 3] = Default::default();
            let mut now = 0u64;
            for (w, keep, dt) in sends {
                next[w as usize] += 1;
                now += dt;
                if keep {
                    delivered[w as usize].push(next[w as usize]);
                    m.on_sample(from(w, next[w as usize]), Duration::from_millis(now));
                }
            }
            let expected: u64 = delivered
                .iter()
                .filter(|d| !d.is_empty())
                .map(|d| (d[d.len() - 1] - d[0] + 1) as u64 - d.len() as u64)
                .sum();
            let s = m.status(Duration::from_millis(now));
            prop_assert_eq!(s.lost, expected);
            prop_assert_eq!(s.received, delivered.iter().map(|d| d.len() as u64).sum::<u64>());
            prop_assert!(s.gaps <= s.lost);
        }

        /// Any sources (extreme numbers, repeats, jumps back) and times
        /// never panic, and the counters stay consistent.
        #[test]
        fn arbitrary_samples_keep_the_counters_consistent(
            samples in proptest::collection::vec(
                (proptest::option::of((0u8..4, any::<i64>())), 0u64..20_000), 0..100),
        ) {
            let mut m = StreamMonitor::new();
            let mut now = 0u64;
            for (source, dt_ms) in samples {
                now += dt_ms;
                m.on_sample(source.and_then(|(w, s)| from(w, s)), Duration::from_millis(now));
                m.check_silence(Duration::from_millis(now + dt_ms));
            }
            let s = m.status(Duration::from_millis(now));
            prop_assert!(s.gaps <= s.lost);
            prop_assert!(s.period_s.is_none_or(|p| p.is_finite() && p > 0.0));
        }
    }
}

//! A mergeable latency histogram with 1 % logarithmic bins, so that
//! percentiles of millions of decisions survive sharding and merging.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Bins per factor e (1 % wide bins: ln(1.01) = 0.00995).
const BINS_PER_E: f64 = 1.0 / 0.009_950_330_853_168_083;

/// Counts of positive values in logarithmic bins of relative width 1 %.
///
/// Quantiles are exact to within one bin (1 %); values at or below zero
/// and non-finite values are counted separately and never binned.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    /// `(bin, count)`, bin `b` holding values in `[e^(b/B), e^((b+1)/B))`.
    bins: BTreeMap<i32, u64>,
    /// Values that were zero or negative.
    zeros: u64,
    /// Non-finite values (ignored by the quantiles).
    invalid: u64,
}

impl Histogram {
    /// An empty histogram.
    pub fn new() -> Self {
        Self::default()
    }

    /// A histogram of `values`.
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let mut h = Self::new();
        for v in values {
            h.add(v);
        }
        h
    }

    /// Adds one value.
    pub fn add(&mut self, v: f64) {
        if !v.is_finite() {
            self.invalid += 1;
        } else if v <= 0.0 {
            self.zeros += 1;
        } else {
            let b = (v.ln() * BINS_PER_E).floor();
            // Finite positive f64 logs are within +-745 * 100.5.
            *self.bins.entry(b as i32).or_insert(0) += 1;
        }
    }

    /// Adds every count of `other`.
    pub fn merge(&mut self, other: &Histogram) {
        for (b, c) in &other.bins {
            *self.bins.entry(*b).or_insert(0) += c;
        }
        self.zeros += other.zeros;
        self.invalid += other.invalid;
    }

    /// Number of valid (finite) values.
    pub fn count(&self) -> u64 {
        self.zeros + self.bins.values().sum::<u64>()
    }

    /// Non-finite values seen.
    pub fn invalid(&self) -> u64 {
        self.invalid
    }

    /// The `q`-quantile (`q` in [0, 1]): the geometric centre of the bin
    /// holding the value of rank `ceil(q n)`; `None` when empty.
    pub fn quantile(&self, q: f64) -> Option<f64> {
        let n = self.count();
        if n == 0 || !q.is_finite() {
            return None;
        }
        let rank = ((q.clamp(0.0, 1.0) * n as f64).ceil() as u64).max(1);
        if rank <= self.zeros {
            return Some(0.0);
        }
        let mut seen = self.zeros;
        for (b, c) in &self.bins {
            seen += c;
            if seen >= rank {
                return Some(((f64::from(*b) + 0.5) / BINS_PER_E).exp());
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The value of rank ceil(q n) of the sorted values (the reference).
    fn exact(values: &[f64], q: f64) -> f64 {
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let rank = ((q * v.len() as f64).ceil() as usize).max(1);
        v[rank - 1]
    }

    proptest! {
        #[test]
        fn quantiles_are_within_one_percent_of_the_exact_ones(
            values in prop::collection::vec(1e-3f64..1e4, 1..400),
            q in 0.0f64..=1.0,
        ) {
            let h = Histogram::of(values.iter().copied());
            let got = h.quantile(q).unwrap();
            let want = exact(&values, q);
            prop_assert!((got / want - 1.0).abs() <= 0.0101, "got {got} want {want}");
        }

        #[test]
        fn merging_equals_one_histogram_of_everything(
            a in prop::collection::vec(1e-3f64..1e4, 0..100),
            b in prop::collection::vec(1e-3f64..1e4, 0..100),
        ) {
            let mut h = Histogram::of(a.iter().copied());
            h.merge(&Histogram::of(b.iter().copied()));
            prop_assert_eq!(h, Histogram::of(a.iter().chain(&b).copied()));
        }
    }

    #[test]
    fn zeros_and_invalid_values() {
        let h = Histogram::of([0.0, -1.0, f64::NAN, f64::INFINITY, 2.0]);
        assert_eq!(h.count(), 3);
        assert_eq!(h.invalid(), 2);
        assert_eq!(h.quantile(0.5), Some(0.0));
        assert!((h.quantile(1.0).unwrap() / 2.0 - 1.0).abs() < 0.01);
        assert_eq!(Histogram::new().quantile(0.5), None);
        let json = serde_json::to_string(&h).unwrap();
        assert_eq!(serde_json::from_str::<Histogram>(&json).unwrap(), h);
    }
}

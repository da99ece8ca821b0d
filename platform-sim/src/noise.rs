//! Optional sensor noise for the camera, all off by default: depth noise,
//! missing depth returns, semantic label flips at object boundaries, per-object
//! missed detections and spurious false-positive blobs. Their purpose is to
//! test a target gate honestly (a perfect semantic sensor never lies).
//!
//! Noise is deterministic: the same configuration, frame and frame seed give
//! the same corrupted frame.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::render::{Frame, NO_INSTANCE, RenderError};

/// Rates and magnitudes of the noise models (all zero: noiseless).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct NoiseConfig {
    /// Depth noise: Gaussian with standard deviation `depth_sigma * z^2`
    /// metres at depth z (structured-light sensors grow quadratically).
    pub depth_sigma: f64,
    /// Probability that a depth return is dropped (reads 0).
    pub missing_rate: f64,
    /// Probability that a pixel on an instance boundary (a 4-neighbour has
    /// another instance) takes its neighbour's label.
    pub boundary_flip_rate: f64,
    /// Probability, per object instance visible in a frame, that the object is
    /// not detected at all (its pixels lose their label).
    pub missed_detection_rate: f64,
    /// Probability per frame of one spurious blob labelled as a random object
    /// that is not there.
    pub false_positive_rate: f64,
    /// Radius of a spurious blob, as a fraction of the image width.
    pub false_positive_radius: f64,
    /// Seed of the noise streams.
    pub seed: u64,
}

impl Default for NoiseConfig {
    fn default() -> Self {
        NoiseConfig {
            depth_sigma: 0.0,
            missing_rate: 0.0,
            boundary_flip_rate: 0.0,
            missed_detection_rate: 0.0,
            false_positive_rate: 0.0,
            false_positive_radius: 0.03,
            seed: 0,
        }
    }
}

impl NoiseConfig {
    /// True when any noise model is enabled.
    pub fn is_active(&self) -> bool {
        self.depth_sigma > 0.0
            || self.missing_rate > 0.0
            || self.boundary_flip_rate > 0.0
            || self.missed_detection_rate > 0.0
            || self.false_positive_rate > 0.0
    }

    /// Checks ranges: rates in [0, 1], sigma and radius finite and >= 0.
    ///
    /// # Errors
    /// [`RenderError::Config`] naming the first invalid field.
    pub fn validate(&self) -> Result<(), RenderError> {
        let rates = [
            ("noise.missing_rate", self.missing_rate),
            ("noise.boundary_flip_rate", self.boundary_flip_rate),
            ("noise.missed_detection_rate", self.missed_detection_rate),
            ("noise.false_positive_rate", self.false_positive_rate),
        ];
        for (field, r) in rates {
            if !(0.0..=1.0).contains(&r) {
                return Err(RenderError::Config {
                    field,
                    message: format!("{r} is not a rate in [0, 1]"),
                });
            }
        }
        for (field, v) in [
            ("noise.depth_sigma", self.depth_sigma),
            ("noise.false_positive_radius", self.false_positive_radius),
        ] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(RenderError::Config {
                    field,
                    message: format!("{v} must be finite and >= 0"),
                });
            }
        }
        Ok(())
    }
}

/// A configured noise model with the instance ids it may hallucinate.
#[derive(Debug, Clone)]
pub struct NoiseModel {
    config: NoiseConfig,
    /// Object instance ids: the ones that can be missed, and the labels of
    /// false positives. Empty: every instance can be missed, no false positives.
    objects: Vec<u32>,
}

impl NoiseModel {
    /// A model; `objects` lists the instance ids that are objects (sorted or not).
    pub fn new(config: NoiseConfig, mut objects: Vec<u32>) -> NoiseModel {
        objects.sort_unstable();
        objects.dedup();
        NoiseModel { config, objects }
    }

    /// The configuration.
    pub fn config(&self) -> &NoiseConfig {
        &self.config
    }

    fn is_object(&self, id: u32) -> bool {
        id != NO_INSTANCE && (self.objects.is_empty() || self.objects.binary_search(&id).is_ok())
    }

    /// Corrupts `frame` in place, deterministically for `(config.seed, frame_seed)`.
    ///
    /// Order: missed detections, boundary flips, false-positive blob, depth
    /// noise, missing returns.
    ///
    /// # Complexity
    /// O(W H + K log K) for a W x H frame with K visible instances.
    pub fn apply(&self, frame: &mut Frame, frame_seed: u64) {
        let c = &self.config;
        let mut rng =
            ChaCha8Rng::seed_from_u64(c.seed ^ frame_seed.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let (w, h) = (frame.width as usize, frame.height as usize);
        if c.missed_detection_rate > 0.0 {
            let mut visible: Vec<u32> = frame
                .instance
                .iter()
                .copied()
                .filter(|&i| self.is_object(i))
                .collect();
            visible.sort_unstable();
            visible.dedup();
            let missed: Vec<u32> = visible
                .into_iter()
                .filter(|_| rng.random_bool(c.missed_detection_rate))
                .collect();
            if !missed.is_empty() {
                for i in frame.instance.iter_mut() {
                    if missed.binary_search(i).is_ok() {
                        *i = NO_INSTANCE;
                    }
                }
            }
        }
        if c.boundary_flip_rate > 0.0 {
            let src = frame.instance.clone();
            for v in 0..h {
                for u in 0..w {
                    let me = src[v * w + u];
                    let neighbours = [
                        (u > 0).then(|| src[v * w + u - 1]),
                        (u + 1 < w).then(|| src[v * w + u + 1]),
                        (v > 0).then(|| src[(v - 1) * w + u]),
                        (v + 1 < h).then(|| src[(v + 1) * w + u]),
                    ];
                    let mut other = neighbours.into_iter().flatten().filter(|&n| n != me);
                    if let Some(n) = other.next()
                        && rng.random_bool(c.boundary_flip_rate)
                    {
                        frame.instance[v * w + u] = n;
                    }
                }
            }
        }
        if c.false_positive_rate > 0.0
            && !self.objects.is_empty()
            && rng.random_bool(c.false_positive_rate)
        {
            let label = self.objects[rng.random_range(0..self.objects.len())];
            let r = (c.false_positive_radius * w as f64).max(1.0);
            let cu = rng.random_range(0.0..w as f64);
            let cv = rng.random_range(0.0..h as f64);
            for v in 0..h {
                for u in 0..w {
                    let (du, dv) = (u as f64 + 0.5 - cu, v as f64 + 0.5 - cv);
                    if du * du + dv * dv <= r * r {
                        frame.instance[v * w + u] = label;
                    }
                }
            }
        }
        if c.depth_sigma > 0.0 {
            for d in frame.depth.iter_mut().filter(|d| **d > 0.0) {
                let z = f64::from(*d);
                let n: f64 = rng.sample(rand_distr::StandardNormal);
                *d = (z + c.depth_sigma * z * z * n).max(1e-3) as f32;
            }
        }
        if c.missing_rate > 0.0 {
            for d in frame.depth.iter_mut() {
                if *d > 0.0 && rng.random_bool(c.missing_rate) {
                    *d = 0.0;
                }
            }
        }
    }
}

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

/// A named set of noise rates (`sornav-sim --noise NAME`).
///
/// Where each rate of [`NoisePreset::Detector`] comes from (paper, venue,
/// table or figure, or why a value had to be chosen without a published
/// figure) is documented in the crate README, section "Sensor noise
/// presets".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NoisePreset {
    /// Noiseless: every rate zero ([`NoiseConfig::default`]).
    #[default]
    Off,
    /// An open-vocabulary detector on a structured-light depth camera:
    /// depth noise `0.0016 z^2` (about 4 cm at 5 m), 2 % dropped returns,
    /// 10 % label flips on instance boundaries, 30 % of the objects in view
    /// missed per frame, one false-positive blob in 5 % of the frames.
    Detector,
}

/// A `--noise` name that is not a preset.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown noise preset '{name}' (known: {known})")]
pub struct UnknownNoisePreset {
    /// The name given.
    pub name: String,
    /// The presets, comma-separated.
    pub known: String,
}

impl NoisePreset {
    /// Every preset, in documentation order.
    pub const ALL: [NoisePreset; 2] = [NoisePreset::Off, NoisePreset::Detector];

    /// The command-line name (`off`, `detector`).
    pub fn name(self) -> &'static str {
        match self {
            NoisePreset::Off => "off",
            NoisePreset::Detector => "detector",
        }
    }

    /// Parses a command-line name (exact, lower case).
    ///
    /// # Errors
    /// [`UnknownNoisePreset`] naming the known presets.
    pub fn from_name(name: &str) -> Result<Self, UnknownNoisePreset> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == name)
            .ok_or_else(|| UnknownNoisePreset {
                name: name.to_owned(),
                known: Self::ALL.map(NoisePreset::name).join(", "),
            })
    }

    /// The preset's rates (seed 0: the simulator's frame seeds vary the
    /// noise per episode and step).
    pub fn config(self) -> NoiseConfig {
        match self {
            NoisePreset::Off => NoiseConfig::default(),
            NoisePreset::Detector => NoiseConfig {
                depth_sigma: 0.0016,
                missing_rate: 0.02,
                boundary_flip_rate: 0.10,
                missed_detection_rate: 0.30,
                false_positive_rate: 0.05,
                ..NoiseConfig::default()
            },
        }
    }
}

impl std::str::FromStr for NoisePreset {
    type Err = UnknownNoisePreset;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::from_name(s)
    }
}

impl std::fmt::Display for NoisePreset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_parse_validate_and_name_themselves() {
        for p in NoisePreset::ALL {
            assert_eq!(NoisePreset::from_name(p.name()), Ok(p));
            assert_eq!(p.name().parse::<NoisePreset>(), Ok(p));
            p.config().validate().unwrap();
        }
        assert_eq!(NoisePreset::Off.config(), NoiseConfig::default());
        assert!(!NoisePreset::Off.config().is_active());
        assert!(NoisePreset::Detector.config().is_active());
        let e = NoisePreset::from_name("Detector").unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown noise preset 'Detector' (known: off, detector)"
        );
    }
}

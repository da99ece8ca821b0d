//! Reader for `SORPCLD1`, the project's labelled point-cloud benchmark
//! format (written by `shared/tools/pcld-gen`): a header, then frames of
//! world-frame points with a sensor origin.
//!
//! ```text
//! offset 0  : 8 bytes ASCII "SORPCLD1"
//! offset 8  : u32 version = 1
//! offset 12 : u32 n_frames
//! n_frames times:
//!   u32 n_points, u32 reserved
//!   f32 origin_x, origin_y, origin_z, f32 reserved
//!   n_points x { f32 x, f32 y, f32 z, u32 label }
//! ```
//! All little-endian.

use std::path::Path;

use nalgebra::Point3;
use thiserror::Error;

use crate::integrate::LabeledPoint;
use crate::label::LabelId;

/// One frame: sensor origin and world-frame labelled points.
#[derive(Debug, Clone, PartialEq)]
pub struct PointFrame {
    /// Sensor origin (world frame).
    pub origin: Point3<f64>,
    /// Points in file order.
    pub points: Vec<LabeledPoint>,
}

/// Errors reading a `SORPCLD1` file.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum PcldError {
    /// The file could not be read.
    #[error("reading point-cloud file: {0}")]
    Io(#[from] std::io::Error),
    /// The first 8 bytes are not `SORPCLD1`.
    #[error("not a SORPCLD1 file (bad magic)")]
    BadMagic,
    /// Only version 1 exists.
    #[error("unsupported SORPCLD1 version {0}")]
    UnsupportedVersion(u32),
    /// The data ends inside a header or frame.
    #[error("file truncated in frame {frame}")]
    Truncated {
        /// Index of the incomplete frame (`u32::MAX` for the file header).
        frame: u32,
    },
    /// A label does not fit a [`LabelId`] (16 bits).
    #[error("frame {frame}: label {label} does not fit 16 bits")]
    LabelOutOfRange {
        /// Frame index.
        frame: u32,
        /// The offending label.
        label: u32,
    },
    /// Bytes remain after the declared frames.
    #[error("{0} trailing bytes after the last frame")]
    TrailingBytes(usize),
}

struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.pos.checked_add(n)?;
        let s = self.data.get(self.pos..end)?;
        self.pos = end;
        Some(s)
    }
    fn u32(&mut self) -> Option<u32> {
        self.take(4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
    fn f32(&mut self) -> Option<f32> {
        self.u32().map(f32::from_bits)
    }
}

/// Parses a whole `SORPCLD1` buffer.
///
/// # Errors
/// Every malformation is a [`PcldError`]; nothing panics.
///
/// # Complexity
/// O(file size).
pub fn parse_sorpcld(data: &[u8]) -> Result<Vec<PointFrame>, PcldError> {
    let mut c = Cursor { data, pos: 0 };
    const HEADER: u32 = u32::MAX;
    if c.take(8).ok_or(PcldError::Truncated { frame: HEADER })? != b"SORPCLD1" {
        return Err(PcldError::BadMagic);
    }
    let version = c.u32().ok_or(PcldError::Truncated { frame: HEADER })?;
    if version != 1 {
        return Err(PcldError::UnsupportedVersion(version));
    }
    let n_frames = c.u32().ok_or(PcldError::Truncated { frame: HEADER })?;
    let mut frames = Vec::new();
    for f in 0..n_frames {
        let trunc = PcldError::Truncated { frame: f };
        let n = c.u32().ok_or(PcldError::Truncated { frame: f })? as usize;
        let _reserved = c.u32().ok_or(PcldError::Truncated { frame: f })?;
        let mut o = [0f32; 4];
        for v in &mut o {
            *v = c.f32().ok_or(PcldError::Truncated { frame: f })?;
        }
        let body = c.take(n.checked_mul(16).ok_or(PcldError::Truncated { frame: f })?);
        let body = body.ok_or(trunc)?;
        let mut points = Vec::with_capacity(n);
        for rec in body.chunks_exact(16) {
            let w = |i: usize| u32::from_le_bytes([rec[i], rec[i + 1], rec[i + 2], rec[i + 3]]);
            let label = w(12);
            let label =
                LabelId::from_u32(label).ok_or(PcldError::LabelOutOfRange { frame: f, label })?;
            points.push(LabeledPoint::new(
                f32::from_bits(w(0)),
                f32::from_bits(w(4)),
                f32::from_bits(w(8)),
                label,
            ));
        }
        frames.push(PointFrame {
            origin: Point3::new(f64::from(o[0]), f64::from(o[1]), f64::from(o[2])),
            points,
        });
    }
    let rest = data.len() - c.pos;
    if rest != 0 {
        return Err(PcldError::TrailingBytes(rest));
    }
    Ok(frames)
}

/// Reads and parses a `SORPCLD1` file.
///
/// # Errors
/// [`PcldError::Io`] or any parse error of [`parse_sorpcld`].
pub fn read_sorpcld(path: impl AsRef<Path>) -> Result<Vec<PointFrame>, PcldError> {
    parse_sorpcld(&std::fs::read(path)?)
}

/// Encodes frames as `SORPCLD1` (the inverse of [`parse_sorpcld`]).
pub fn encode_sorpcld(frames: &[PointFrame]) -> Vec<u8> {
    let mut out = Vec::new();
    out.extend_from_slice(b"SORPCLD1");
    out.extend_from_slice(&1u32.to_le_bytes());
    out.extend_from_slice(&(frames.len() as u32).to_le_bytes());
    for f in frames {
        out.extend_from_slice(&(f.points.len() as u32).to_le_bytes());
        out.extend_from_slice(&0u32.to_le_bytes());
        for v in [f.origin.x as f32, f.origin.y as f32, f.origin.z as f32, 0.0] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for p in &f.points {
            for v in [p.position.x, p.position.y, p.position.z] {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.extend_from_slice(&u32::from(p.label.0).to_le_bytes());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<PointFrame> {
        vec![
            PointFrame {
                origin: Point3::new(1.0, 2.0, 0.5),
                points: vec![
                    LabeledPoint::new(1.5, 2.0, 0.25, LabelId(10)),
                    LabeledPoint::new(-3.0, 0.0, 1.0, LabelId(2)),
                ],
            },
            PointFrame {
                origin: Point3::origin(),
                points: vec![],
            },
        ]
    }

    #[test]
    fn round_trip() {
        let bytes = encode_sorpcld(&sample());
        assert_eq!(parse_sorpcld(&bytes).unwrap(), sample());
    }

    #[test]
    fn malformed_inputs_are_errors() {
        let bytes = encode_sorpcld(&sample());
        assert!(matches!(
            parse_sorpcld(b"NOTPCLD1xxxxxxxx"),
            Err(PcldError::BadMagic)
        ));
        assert!(matches!(
            parse_sorpcld(b"SORP"),
            Err(PcldError::Truncated { .. })
        ));
        let mut v2 = bytes.clone();
        v2[8] = 2;
        assert!(matches!(
            parse_sorpcld(&v2),
            Err(PcldError::UnsupportedVersion(2))
        ));
        for cut in [12, 20, 40, bytes.len() - 1] {
            assert!(
                matches!(
                    parse_sorpcld(&bytes[..cut]),
                    Err(PcldError::Truncated { .. })
                ),
                "cut {cut}"
            );
        }
        let mut extra = bytes.clone();
        extra.push(0);
        assert!(matches!(
            parse_sorpcld(&extra),
            Err(PcldError::TrailingBytes(1))
        ));
        let mut big_label = bytes.clone();
        // Label of the first point: header 16 + frame header 24 + 12.
        big_label[16 + 24 + 12..16 + 24 + 16].copy_from_slice(&70_000u32.to_le_bytes());
        assert!(matches!(
            parse_sorpcld(&big_label),
            Err(PcldError::LabelOutOfRange {
                frame: 0,
                label: 70_000
            })
        ));
        // A huge declared point count must not allocate or panic.
        let mut huge = bytes;
        huge[16..20].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(matches!(
            parse_sorpcld(&huge),
            Err(PcldError::Truncated { frame: 0 })
        ));
        assert!(matches!(
            read_sorpcld("/definitely/not/here.bin"),
            Err(PcldError::Io(_))
        ));
    }
}

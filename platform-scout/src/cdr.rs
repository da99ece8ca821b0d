//! CDR encoding of ROS 2 messages with the 4-byte encapsulation header, as
//! carried in an RTPS serialized payload (and stored by `ros2 bag`).
//!
//! Layout: `00 00` (big-endian, `CDR_BE`) or `00 01` (little-endian,
//! `CDR_LE`), two option bytes, then the plain CDR body. Inside the body a
//! primitive of size `n` is aligned to `n` bytes counted from the start of
//! the body (so doubles sit on 8-byte boundaries of the body, not of the
//! buffer); strings and sequences carry a `uint32` length; strings include
//! their NUL terminator. The body is written by the same `cdr-encoding`
//! crate RustDDS uses, so these bytes are what a ROS 2 node sends.
//!
//! [`encode`] pads the body to a multiple of 4 bytes and records the padding
//! count in the low two bits of the options, as DDS-XTypes 1.3 (7.4.3.5.3)
//! specifies; [`decode`] accepts any trailing bytes after the value (padding
//! from other vendors), and [`decode_exact`] reports how many there were.
//!
//! # Example
//! ```
//! use sornav_platform_scout::cdr::{Endianness, decode, encode};
//! use sornav_platform_scout::msg::{Header, Point, PointStamped, Time};
//!
//! let msg = PointStamped {
//!     header: Header::new(Time { sec: 1, nanosec: 2 }, "map"),
//!     point: Point::new(1.0, 2.0, 0.0),
//! };
//! let bytes = encode(&msg, Endianness::Little)?;
//! assert_eq!(&bytes[..4], &[0, 1, 0, 0]);
//! // header.stamp (8) + frame_id (4 + "map\0") = 16 bytes, already 8-aligned:
//! // the first double starts right after, at body offset 16.
//! assert_eq!(&bytes[4 + 16..4 + 24], &1.0f64.to_le_bytes());
//! assert_eq!(decode::<PointStamped>(&bytes)?, msg);
//! # Ok::<(), sornav_platform_scout::cdr::CdrError>(())
//! ```

use byteorder::{BigEndian, LittleEndian};
use cdr_encoding::{from_bytes, to_vec};
use serde::Serialize;
use serde::de::DeserializeOwned;

/// Byte order of a CDR body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Endianness {
    /// `CDR_LE` (what ROS 2 sends on x86 and ARM).
    Little,
    /// `CDR_BE`.
    Big,
}

impl Endianness {
    /// The two representation-identifier bytes.
    pub fn identifier(self) -> [u8; 2] {
        match self {
            Endianness::Big => [0x00, 0x00],
            Endianness::Little => [0x00, 0x01],
        }
    }
}

/// Errors of CDR encoding and decoding.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    /// Fewer than 4 bytes: no encapsulation header.
    #[error("CDR payload of {0} bytes has no 4-byte encapsulation header")]
    MissingHeader(usize),
    /// The representation identifier is not plain CDR (`00 00` / `00 01`),
    /// for example parameter-list or XCDR2 encodings.
    #[error("unsupported CDR representation identifier {0:02x?}")]
    UnsupportedRepresentation([u8; 2]),
    /// The body does not hold a value of the type (truncated, bad string,
    /// invalid bool, ...).
    #[error("cannot decode {type_name}: {message}")]
    Decode {
        /// The Rust type.
        type_name: &'static str,
        /// The decoder's message.
        message: String,
    },
    /// The value cannot be encoded (e.g. a sequence longer than `u32::MAX`).
    #[error("cannot encode: {0}")]
    Encode(String),
}

/// Encodes `value` with the encapsulation header.
///
/// # Errors
/// [`CdrError::Encode`] when the serializer refuses the value.
///
/// # Complexity
/// O(size of the value).
pub fn encode<T: Serialize>(value: &T, endianness: Endianness) -> Result<Vec<u8>, CdrError> {
    let body = match endianness {
        Endianness::Little => to_vec::<T, LittleEndian>(value),
        Endianness::Big => to_vec::<T, BigEndian>(value),
    }
    .map_err(|e| CdrError::Encode(e.to_string()))?;
    let padding = (4 - body.len() % 4) % 4;
    let id = endianness.identifier();
    let mut out = Vec::with_capacity(4 + body.len() + padding);
    out.extend_from_slice(&[id[0], id[1], 0x00, padding as u8]);
    out.extend_from_slice(&body);
    out.resize(out.len() + padding, 0);
    Ok(out)
}

/// Decodes a value from an encapsulated payload, ignoring trailing bytes.
///
/// # Errors
/// [`CdrError::MissingHeader`], [`CdrError::UnsupportedRepresentation`],
/// [`CdrError::Decode`].
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, CdrError> {
    decode_exact(bytes).map(|(v, _)| v)
}

/// Decodes a value and returns it with the number of trailing bytes that
/// followed it in the body (alignment padding).
///
/// # Errors
/// As [`decode`].
pub fn decode_exact<T: DeserializeOwned>(bytes: &[u8]) -> Result<(T, usize), CdrError> {
    if bytes.len() < 4 {
        return Err(CdrError::MissingHeader(bytes.len()));
    }
    let body = &bytes[4..];
    let decoded = match [bytes[0], bytes[1]] {
        [0x00, 0x01] => from_bytes::<T, LittleEndian>(body),
        [0x00, 0x00] => from_bytes::<T, BigEndian>(body),
        other => return Err(CdrError::UnsupportedRepresentation(other)),
    };
    let (value, consumed) = decoded.map_err(|e| CdrError::Decode {
        type_name: std::any::type_name::<T>(),
        message: e.to_string(),
    })?;
    Ok((value, body.len().saturating_sub(consumed)))
}

//! The one TOML loader of the project: typed parse, read and write of any
//! serde configuration type ([`AgentConfig`](crate::AgentConfig), and the
//! platforms' own files such as `sornav-platform-scout`'s `ScoutConfig`).
//!
//! Errors are this crate's [`TomlError`]: the `toml` crate's error types
//! (0.x) do not appear in the public API, so upgrading it is not a breaking
//! change.
//!
//! # Example
//! ```
//! use serde::{Deserialize, Serialize};
//!
//! #[derive(Debug, PartialEq, Serialize, Deserialize)]
//! #[serde(deny_unknown_fields)]
//! struct Settings {
//!     rate_hz: f64,
//! }
//! let s: Settings = sornav::toml_file::from_str("rate_hz = 5.0")?;
//! assert_eq!(s, Settings { rate_hz: 5.0 });
//! assert_eq!(sornav::toml_file::to_string(&s)?, "rate_hz = 5.0\n");
//!
//! let err = sornav::toml_file::from_str::<Settings>("rate_hz = 5.0\nspeed = 1\n").unwrap_err();
//! assert!(matches!(err, sornav::TomlError::Parse { line: Some(2), .. }));
//! # Ok::<(), sornav::TomlError>(())
//! ```

use std::path::{Path, PathBuf};

use serde::Serialize;
use serde::de::DeserializeOwned;
use thiserror::Error;

/// Why a TOML document could not be read, parsed or written.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum TomlError {
    /// Reading the file failed.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// Malformed TOML, a wrong type, a missing or an unknown field.
    #[error("{}{message}", location(path.as_deref(), *line))]
    Parse {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// The 1-based line of the error, when known.
        line: Option<usize>,
        /// What is wrong (the parser's message).
        message: String,
    },
    /// The value cannot be written as TOML (for example a map with
    /// non-string keys).
    #[error("cannot write TOML: {message}")]
    Serialize {
        /// The serialiser's message.
        message: String,
    },
}

fn location(path: Option<&Path>, line: Option<usize>) -> String {
    match (path, line) {
        (Some(p), Some(l)) => format!("{}:{l}: ", p.display()),
        (Some(p), None) => format!("{}: ", p.display()),
        (None, Some(l)) => format!("line {l}: "),
        (None, None) => String::new(),
    }
}

fn parse<T: DeserializeOwned>(text: &str, path: Option<&Path>) -> Result<T, TomlError> {
    toml::from_str(text).map_err(|e: toml::de::Error| TomlError::Parse {
        path: path.map(Path::to_path_buf),
        line: e
            .span()
            .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1),
        message: e.message().trim_end().to_owned(),
    })
}

/// Parses a TOML document into `T`.
///
/// # Errors
/// [`TomlError::Parse`] with the line of the first error.
pub fn from_str<T: DeserializeOwned>(text: &str) -> Result<T, TomlError> {
    parse(text, None)
}

/// Reads and parses a TOML file into `T`.
///
/// # Errors
/// [`TomlError::Io`] when the file cannot be read, [`TomlError::Parse`]
/// (naming the file and line) when it does not parse into `T`.
pub fn from_file<T: DeserializeOwned>(path: &Path) -> Result<T, TomlError> {
    let text = std::fs::read_to_string(path).map_err(|source| TomlError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse(&text, Some(path))
}

/// Writes `value` as a TOML document.
///
/// # Errors
/// [`TomlError::Serialize`] when `value` has no TOML form.
pub fn to_string<T: Serialize + ?Sized>(value: &T) -> Result<String, TomlError> {
    toml::to_string(value).map_err(|e| TomlError::Serialize {
        message: e.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn parse_errors_carry_the_line() {
        let e = from_str::<BTreeMap<String, f64>>("a = 1.0\nb = \"x\"\n").unwrap_err();
        match e {
            TomlError::Parse { line, path, .. } => {
                assert_eq!(line, Some(2));
                assert!(path.is_none());
            }
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn missing_files_are_io_errors_naming_the_file() {
        let p = Path::new("/nonexistent/sornav.toml");
        let e = from_file::<BTreeMap<String, f64>>(p).unwrap_err();
        assert!(matches!(&e, TomlError::Io { path, .. } if path == p));
        assert!(e.to_string().contains("/nonexistent/sornav.toml"));
    }

    #[test]
    fn round_trip() {
        let m = BTreeMap::from([("x".to_owned(), 1.5)]);
        let back: BTreeMap<String, f64> = from_str(&to_string(&m).unwrap()).unwrap();
        assert_eq!(back, m);
    }
}

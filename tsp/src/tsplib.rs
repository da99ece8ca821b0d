//! Reader for TSPLIB95 problem files (`TYPE: TSP` / `ATSP`) and tour files.
//!
//! Supported: `EDGE_WEIGHT_TYPE` `EUC_2D`, `CEIL_2D`, `ATT`, `GEO` (from a
//! `NODE_COORD_SECTION`) and `EXPLICIT` with `EDGE_WEIGHT_FORMAT`
//! `FULL_MATRIX`, `UPPER_ROW`, `LOWER_ROW`, `UPPER_DIAG_ROW`,
//! `LOWER_DIAG_ROW`, `UPPER_COL`, `LOWER_COL`, `UPPER_DIAG_COL`,
//! `LOWER_DIAG_COL` (ATSP: `FULL_MATRIX` only). Distances follow Reinelt's
//! TSPLIB95 definitions exactly (integer results; `GEO` truncates degrees
//! as the reference implementation does). `DISPLAY_DATA_SECTION` is
//! skipped; unknown specification keywords are ignored; anything else
//! (other types, unknown sections, `FIXED_EDGES_SECTION`) is a typed error.

use std::path::Path;

use nalgebra::Point2;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::error::TspError;
use crate::matrix::CostMatrix;

/// Largest `DIMENSION` accepted (the dense matrix of 5,000 nodes is 200 MB).
pub const MAX_DIMENSION: usize = 5_000;

/// Why a TSPLIB file was rejected. Line numbers are 1-based.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum TsplibError {
    /// Reading the file failed.
    #[error("reading {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A required specification entry is absent.
    #[error("missing {0}")]
    Missing(&'static str),
    /// `TYPE` is not `TSP`, `ATSP` (problems) or `TOUR` (tours).
    #[error("unsupported TYPE {0}")]
    UnsupportedType(String),
    /// `EDGE_WEIGHT_TYPE` not among the supported ones.
    #[error("unsupported EDGE_WEIGHT_TYPE {0}")]
    UnsupportedWeightType(String),
    /// `EDGE_WEIGHT_FORMAT` not supported (for this `TYPE`).
    #[error("unsupported EDGE_WEIGHT_FORMAT {format} for TYPE {kind}")]
    UnsupportedFormat {
        /// The format.
        format: String,
        /// The problem type.
        kind: String,
    },
    /// A section this reader does not implement.
    #[error("line {line}: unsupported section {name}")]
    UnsupportedSection {
        /// Line of the section header.
        line: usize,
        /// Section name.
        name: String,
    },
    /// A line that is neither `KEY : value`, a section header nor data.
    #[error("line {line}: cannot parse {text:?}")]
    Syntax {
        /// Line number.
        line: usize,
        /// The text.
        text: String,
    },
    /// A token that should be a number is not (or is not finite).
    #[error("line {line}: {token:?} is not a valid number")]
    BadNumber {
        /// Line number.
        line: usize,
        /// The token.
        token: String,
    },
    /// `DIMENSION` is zero, unparsable or above [`MAX_DIMENSION`].
    #[error("invalid DIMENSION {0}")]
    BadDimension(String),
    /// A section holds too few or too many entries.
    #[error("{section}: expected {expected} numbers, found {found}")]
    WrongCount {
        /// The section.
        section: &'static str,
        /// Expected count.
        expected: usize,
        /// Found count.
        found: usize,
    },
    /// A node id outside `1..=DIMENSION`, or given twice.
    #[error("line {line}: bad or repeated node id {id}")]
    BadNode {
        /// Line number.
        line: usize,
        /// The id.
        id: i64,
    },
    /// The data section required by the weight type is absent.
    #[error("missing {0}")]
    MissingSection(&'static str),
    /// The resulting matrix was rejected.
    #[error(transparent)]
    Matrix(#[from] TspError),
}

/// Symmetric or asymmetric problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ProblemKind {
    /// `TYPE: TSP`.
    Symmetric,
    /// `TYPE: ATSP`.
    Asymmetric,
}

/// A parsed problem: its name and dense cost matrix (node `i` of the file is
/// index `i - 1`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Instance {
    /// `NAME`.
    pub name: String,
    /// `COMMENT` lines joined by newlines (may be empty).
    pub comment: String,
    /// `TYPE`.
    pub kind: ProblemKind,
    /// Node coordinates when the file has a `NODE_COORD_SECTION`.
    pub coords: Option<Vec<Point2<f64>>>,
    /// Costs.
    pub matrix: CostMatrix,
}

/// Weight types.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Weight {
    Euc2d,
    Ceil2d,
    Att,
    Geo,
    Explicit,
}

/// TSPLIB `nint`.
fn nint(x: f64) -> f64 {
    (x + 0.5).floor()
}

/// Distance between two coordinates under a coordinate weight type.
fn coord_distance(w: Weight, p: &Point2<f64>, q: &Point2<f64>) -> f64 {
    let (dx, dy) = (p.x - q.x, p.y - q.y);
    match w {
        Weight::Euc2d => nint((dx * dx + dy * dy).sqrt()),
        Weight::Ceil2d => (dx * dx + dy * dy).sqrt().ceil(),
        Weight::Att => {
            let r = ((dx * dx + dy * dy) / 10.0).sqrt();
            let t = nint(r);
            if t < r { t + 1.0 } else { t }
        }
        Weight::Geo => {
            // TSPLIB95 prescribes this truncated value, not `f64::consts::PI`.
            #[allow(clippy::approx_constant)]
            const PI: f64 = 3.141592;
            const RRR: f64 = 6378.388;
            let rad = |x: f64| {
                let deg = x.trunc();
                PI * (deg + 5.0 * (x - deg) / 3.0) / 180.0
            };
            let (lat_i, lon_i, lat_j, lon_j) = (rad(p.x), rad(p.y), rad(q.x), rad(q.y));
            let q1 = (lon_i - lon_j).cos();
            let q2 = (lat_i - lat_j).cos();
            let q3 = (lat_i + lat_j).cos();
            let arg = (0.5 * ((1.0 + q1) * q2 - (1.0 - q1) * q3)).clamp(-1.0, 1.0);
            (RRR * arg.acos() + 1.0).trunc()
        }
        Weight::Explicit => 0.0,
    }
}

/// Entries of the `EDGE_WEIGHT_SECTION` in file order, as `(row, col)` pairs.
fn explicit_cells(format: &str, n: usize) -> Option<Vec<(usize, usize)>> {
    let mut cells = Vec::new();
    // Column-wise triangles of a symmetric matrix list the same cells as
    // the opposite row-wise triangle (transposed).
    let (upper, diag) = match format {
        "FULL_MATRIX" => {
            for i in 0..n {
                for j in 0..n {
                    cells.push((i, j));
                }
            }
            return Some(cells);
        }
        "UPPER_ROW" | "LOWER_COL" => (true, false),
        "LOWER_ROW" | "UPPER_COL" => (false, false),
        "UPPER_DIAG_ROW" | "LOWER_DIAG_COL" => (true, true),
        "LOWER_DIAG_ROW" | "UPPER_DIAG_COL" => (false, true),
        _ => return None,
    };
    for i in 0..n {
        let range = match (upper, diag) {
            (true, true) => i..n,
            (true, false) => i + 1..n,
            (false, true) => 0..i + 1,
            (false, false) => 0..i,
        };
        for j in range {
            cells.push((i, j));
        }
    }
    Some(cells)
}

/// Tokenised data lines: `(line number, token)`.
struct Lines<'a> {
    lines: Vec<(usize, &'a str)>,
    at: usize,
}

impl<'a> Lines<'a> {
    fn new(text: &'a str) -> Self {
        Self {
            lines: text
                .lines()
                .enumerate()
                .map(|(i, l)| (i + 1, l.trim()))
                .filter(|(_, l)| !l.is_empty())
                .collect(),
            at: 0,
        }
    }

    fn peek(&self) -> Option<(usize, &'a str)> {
        self.lines.get(self.at).copied()
    }

    /// Whether a line begins a keyword or a section (not data).
    fn is_keyword(line: &str) -> bool {
        line.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
    }

    /// Consumes data lines until the next keyword line; returns the numbers.
    fn numbers(&mut self) -> Result<Vec<(usize, f64)>, TsplibError> {
        let mut out = Vec::new();
        while let Some((line, text)) = self.peek() {
            if Self::is_keyword(text) {
                break;
            }
            self.at += 1;
            for tok in text.split_whitespace() {
                match tok.parse::<f64>() {
                    Ok(v) if v.is_finite() => out.push((line, v)),
                    _ => {
                        return Err(TsplibError::BadNumber {
                            line,
                            token: tok.to_string(),
                        });
                    }
                }
            }
        }
        Ok(out)
    }
}

/// Splits `KEY : value` (the colon may be absent before a section name).
fn split_key(text: &str) -> (String, String) {
    match text.split_once(':') {
        Some((k, v)) => (k.trim().to_ascii_uppercase(), v.trim().to_string()),
        None => (text.trim().to_ascii_uppercase(), String::new()),
    }
}

/// Parses a TSPLIB problem (`TYPE: TSP` or `ATSP`).
///
/// # Errors
/// A [`TsplibError`] describing the first problem found.
///
/// # Complexity
/// `O(n^2)` for the matrix.
///
/// # Examples
/// ```
/// let text = "NAME: tri\nTYPE: TSP\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EUC_2D\n\
///             NODE_COORD_SECTION\n1 0 0\n2 3 0\n3 3 4\nEOF\n";
/// let inst = sornav_tsp::tsplib::parse(text)?;
/// assert_eq!(inst.matrix.cost(0, 2), 5.0);
/// # Ok::<(), sornav_tsp::tsplib::TsplibError>(())
/// ```
pub fn parse(text: &str) -> Result<Instance, TsplibError> {
    let mut lines = Lines::new(text);
    let mut name = String::new();
    let mut comment = Vec::new();
    let mut kind = None;
    let mut dimension = None;
    let mut weight = None;
    let mut format = None;
    let mut coords: Option<Vec<Point2<f64>>> = None;
    let mut weights: Option<Vec<(usize, f64)>> = None;
    while let Some((line, text)) = lines.peek() {
        lines.at += 1;
        let (key, value) = split_key(text);
        match key.as_str() {
            "EOF" => break,
            "NAME" => name = value,
            "COMMENT" => comment.push(value),
            "TYPE" => {
                kind = Some(match value.to_ascii_uppercase().as_str() {
                    "TSP" => ProblemKind::Symmetric,
                    "ATSP" => ProblemKind::Asymmetric,
                    _ => return Err(TsplibError::UnsupportedType(value)),
                })
            }
            "DIMENSION" => {
                let n = value
                    .parse::<usize>()
                    .ok()
                    .filter(|&n| (1..=MAX_DIMENSION).contains(&n))
                    .ok_or_else(|| TsplibError::BadDimension(value.clone()))?;
                dimension = Some(n);
            }
            "EDGE_WEIGHT_TYPE" => {
                weight = Some(match value.to_ascii_uppercase().as_str() {
                    "EUC_2D" => Weight::Euc2d,
                    "CEIL_2D" => Weight::Ceil2d,
                    "ATT" => Weight::Att,
                    "GEO" => Weight::Geo,
                    "EXPLICIT" => Weight::Explicit,
                    _ => return Err(TsplibError::UnsupportedWeightType(value)),
                })
            }
            "EDGE_WEIGHT_FORMAT" => format = Some(value.to_ascii_uppercase()),
            "NODE_COORD_SECTION" => {
                let n =
                    dimension.ok_or(TsplibError::Missing("DIMENSION before NODE_COORD_SECTION"))?;
                coords = Some(read_coords(&mut lines, n)?);
            }
            "EDGE_WEIGHT_SECTION" => weights = Some(lines.numbers()?),
            "DISPLAY_DATA_SECTION" => {
                lines.numbers()?;
            }
            _ if key.ends_with("_SECTION") => {
                return Err(TsplibError::UnsupportedSection { line, name: key });
            }
            _ if text.contains(':') => {} // other specification keywords
            _ => {
                return Err(TsplibError::Syntax {
                    line,
                    text: text.to_string(),
                });
            }
        }
    }
    let kind = kind.ok_or(TsplibError::Missing("TYPE"))?;
    let n = dimension.ok_or(TsplibError::Missing("DIMENSION"))?;
    let weight = weight.ok_or(TsplibError::Missing("EDGE_WEIGHT_TYPE"))?;
    let matrix = if weight == Weight::Explicit {
        let format = format.ok_or(TsplibError::Missing("EDGE_WEIGHT_FORMAT"))?;
        let kind_name = match kind {
            ProblemKind::Symmetric => "TSP",
            ProblemKind::Asymmetric => "ATSP",
        };
        let cells = explicit_cells(&format, n)
            .filter(|_| kind == ProblemKind::Symmetric || format == "FULL_MATRIX")
            .ok_or_else(|| TsplibError::UnsupportedFormat {
                format: format.clone(),
                kind: kind_name.into(),
            })?;
        let values = weights.ok_or(TsplibError::MissingSection("EDGE_WEIGHT_SECTION"))?;
        if values.len() != cells.len() {
            return Err(TsplibError::WrongCount {
                section: "EDGE_WEIGHT_SECTION",
                expected: cells.len(),
                found: values.len(),
            });
        }
        let mut data = vec![0.0; n * n];
        for (&(i, j), &(_, v)) in cells.iter().zip(&values) {
            data[i * n + j] = v;
            if format != "FULL_MATRIX" {
                data[j * n + i] = v;
            }
        }
        CostMatrix::new(n, data)?
    } else {
        let pts = coords
            .as_ref()
            .ok_or(TsplibError::MissingSection("NODE_COORD_SECTION"))?;
        CostMatrix::from_fn(n, |i, j| {
            if i == j {
                0.0
            } else {
                coord_distance(weight, &pts[i], &pts[j])
            }
        })?
    };
    Ok(Instance {
        name,
        comment: comment.join("\n"),
        kind,
        coords,
        matrix,
    })
}

fn read_coords(lines: &mut Lines<'_>, n: usize) -> Result<Vec<Point2<f64>>, TsplibError> {
    let nums = lines.numbers()?;
    if nums.len() != 3 * n {
        return Err(TsplibError::WrongCount {
            section: "NODE_COORD_SECTION",
            expected: 3 * n,
            found: nums.len(),
        });
    }
    let mut pts = vec![None; n];
    for t in nums.chunks_exact(3) {
        let (line, id) = t[0];
        let slot = (id.fract() == 0.0 && id >= 1.0 && id <= n as f64)
            .then(|| id as usize - 1)
            .filter(|&k| pts[k].is_none())
            .ok_or(TsplibError::BadNode {
                line,
                id: id as i64,
            })?;
        pts[slot] = Some(Point2::new(t[1].1, t[2].1));
    }
    // All `n` ids were distinct and in range, so every slot is filled.
    Ok(pts.into_iter().flatten().collect())
}

/// Parses a TSPLIB tour file (`TOUR_SECTION`, ids ending with `-1`) into
/// 0-based node indices.
///
/// # Errors
/// [`TsplibError`] for a missing section, bad numbers or ids outside
/// `1..=DIMENSION` (when a dimension is given).
pub fn parse_tour(text: &str) -> Result<Vec<usize>, TsplibError> {
    let mut lines = Lines::new(text);
    let mut dimension = None;
    while let Some((line, text)) = lines.peek() {
        lines.at += 1;
        let (key, value) = split_key(text);
        match key.as_str() {
            "DIMENSION" => {
                dimension = Some(
                    value
                        .parse::<usize>()
                        .map_err(|_| TsplibError::BadDimension(value.clone()))?,
                )
            }
            "TYPE" if !value.eq_ignore_ascii_case("TOUR") => {
                return Err(TsplibError::UnsupportedType(value));
            }
            "TOUR_SECTION" => {
                let mut tour = Vec::new();
                for (line, v) in lines.numbers()? {
                    if v == -1.0 {
                        break;
                    }
                    let ok =
                        v.fract() == 0.0 && v >= 1.0 && dimension.is_none_or(|n| v <= n as f64);
                    if !ok {
                        return Err(TsplibError::BadNode { line, id: v as i64 });
                    }
                    tour.push(v as usize - 1);
                }
                if let Some(n) = dimension.filter(|&n| n != tour.len()) {
                    return Err(TsplibError::WrongCount {
                        section: "TOUR_SECTION",
                        expected: n,
                        found: tour.len(),
                    });
                }
                return Ok(tour);
            }
            "EOF" => break,
            _ if key.ends_with("_SECTION") => {
                return Err(TsplibError::UnsupportedSection { line, name: key });
            }
            _ => {}
        }
    }
    Err(TsplibError::MissingSection("TOUR_SECTION"))
}

/// Reads and parses a problem file.
///
/// # Errors
/// [`TsplibError::Io`] or any parse error.
pub fn read(path: impl AsRef<Path>) -> Result<Instance, TsplibError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| TsplibError::Io {
        path: path.display().to_string(),
        source,
    })?;
    parse(&text)
}

/// Reads and parses a tour file.
///
/// # Errors
/// [`TsplibError::Io`] or any parse error.
pub fn read_tour(path: impl AsRef<Path>) -> Result<Vec<usize>, TsplibError> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|source| TsplibError::Io {
        path: path.display().to_string(),
        source,
    })?;
    parse_tour(&text)
}

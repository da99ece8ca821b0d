//! Semantic label ids and the [`LabelSet`] vocabulary (id <-> name, plus the
//! labels that never form objects, such as wall, floor and ceiling).

use std::collections::BTreeMap;
use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};

use crate::error::MapError;

/// A semantic class id, as produced by a segmentation model or a simulator.
///
/// Labels are plain 16-bit integers; a [`LabelSet`] gives them names. Any id
/// may be integrated, named or not.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct LabelId(pub u16);

impl LabelId {
    /// Converts a wider id (for example a `u32` label from a file), or `None`
    /// when it does not fit in 16 bits.
    pub fn from_u32(id: u32) -> Option<Self> {
        u16::try_from(id).ok().map(LabelId)
    }
}

impl std::fmt::Display for LabelId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// The label vocabulary of a map: names for ids, and the set of labels that
/// are *ignored for objects* (structure such as wall, floor, ceiling).
///
/// Ignored labels are still fused as evidence in the voxels (a voxel that is
/// mostly floor is not a chair), but voxels whose dominant label is ignored
/// never join an object cluster.
///
/// # Examples
/// ```
/// use sornav_semantic_map::{LabelId, LabelSet};
/// let mut labels = LabelSet::new();
/// labels.insert(LabelId(1), "wall", true).unwrap();
/// labels.insert(LabelId(14), "toilet", false).unwrap();
/// assert_eq!(labels.id("toilet"), Some(LabelId(14)));
/// assert!(labels.is_ignored(LabelId(1)));
/// assert!(!labels.is_ignored(LabelId(14)));
/// ```
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(try_from = "LabelSetRepr", into = "LabelSetRepr")]
pub struct LabelSet {
    names: BTreeMap<LabelId, String>,
    by_name: BTreeMap<String, LabelId>,
    ignored: BTreeSet<LabelId>,
}

/// Serialised form of a [`LabelSet`] (validated on load).
#[derive(Serialize, Deserialize)]
struct LabelSetRepr {
    names: BTreeMap<LabelId, String>,
    ignored: BTreeSet<LabelId>,
}

impl TryFrom<LabelSetRepr> for LabelSet {
    type Error = MapError;
    fn try_from(repr: LabelSetRepr) -> Result<Self, MapError> {
        let mut set = LabelSet::new();
        for (id, name) in repr.names {
            set.insert(id, &name, false)?;
        }
        for id in repr.ignored {
            set.set_ignored(id, true);
        }
        Ok(set)
    }
}

impl From<LabelSet> for LabelSetRepr {
    fn from(set: LabelSet) -> Self {
        LabelSetRepr {
            names: set.names,
            ignored: set.ignored,
        }
    }
}

impl LabelSet {
    /// An empty vocabulary: every label is an object label.
    pub fn new() -> Self {
        Self::default()
    }

    /// The vocabulary of the project's benchmark scenes (`pcld-gen`) and of
    /// the procedural houses: 1 wall, 2 floor, 3 ceiling (ignored), 10 chair,
    /// 11 table, 12 bed, 13 sofa, 14 toilet, 15 tv, 16 plant, 17 cabinet.
    pub fn household() -> Self {
        let mut set = Self::new();
        let entries: [(u16, &str, bool); 11] = [
            (1, "wall", true),
            (2, "floor", true),
            (3, "ceiling", true),
            (10, "chair", false),
            (11, "table", false),
            (12, "bed", false),
            (13, "sofa", false),
            (14, "toilet", false),
            (15, "tv", false),
            (16, "plant", false),
            (17, "cabinet", false),
        ];
        for (id, name, ignored) in entries {
            // The fixed table has unique ids and names.
            let _ = set.insert(LabelId(id), name, ignored);
        }
        set
    }

    /// Names `id` and sets whether it is ignored for objects.
    ///
    /// # Errors
    /// [`MapError::DuplicateLabelName`] when `name` already names another id,
    /// [`MapError::EmptyLabelName`] for an empty name. Re-inserting an id
    /// renames it.
    pub fn insert(&mut self, id: LabelId, name: &str, ignored: bool) -> Result<(), MapError> {
        if name.is_empty() {
            return Err(MapError::EmptyLabelName(id));
        }
        if let Some(&other) = self.by_name.get(name)
            && other != id
        {
            return Err(MapError::DuplicateLabelName {
                name: name.to_owned(),
                existing: other,
            });
        }
        if let Some(old) = self.names.insert(id, name.to_owned()) {
            self.by_name.remove(&old);
        }
        self.by_name.insert(name.to_owned(), id);
        self.set_ignored(id, ignored);
        Ok(())
    }

    /// Marks `id` (named or not) as ignored for objects, or clears the mark.
    pub fn set_ignored(&mut self, id: LabelId, ignored: bool) {
        if ignored {
            self.ignored.insert(id);
        } else {
            self.ignored.remove(&id);
        }
    }

    /// Whether voxels dominated by `id` are excluded from object clusters.
    pub fn is_ignored(&self, id: LabelId) -> bool {
        self.ignored.contains(&id)
    }

    /// The name of `id`, if named.
    pub fn name(&self, id: LabelId) -> Option<&str> {
        self.names.get(&id).map(String::as_str)
    }

    /// The id named `name`, if any.
    pub fn id(&self, name: &str) -> Option<LabelId> {
        self.by_name.get(name).copied()
    }

    /// Named labels in id order.
    pub fn iter(&self) -> impl Iterator<Item = (LabelId, &str)> {
        self.names.iter().map(|(&id, n)| (id, n.as_str()))
    }

    /// Ignored labels in id order.
    pub fn ignored(&self) -> impl Iterator<Item = LabelId> + '_ {
        self.ignored.iter().copied()
    }

    /// A dense bitmap of the ignored ids, for the integration hot path.
    pub(crate) fn ignored_bitmap(&self) -> IgnoredBitmap {
        let mut bits = vec![0u64; 1 << 10].into_boxed_slice();
        for id in &self.ignored {
            bits[usize::from(id.0 >> 6)] |= 1 << (id.0 & 63);
        }
        IgnoredBitmap { bits }
    }
}

/// One bit per possible [`LabelId`] (8 KiB): constant-time "ignored?" tests.
#[derive(Debug, Clone)]
pub(crate) struct IgnoredBitmap {
    bits: Box<[u64]>,
}

impl IgnoredBitmap {
    #[inline]
    pub(crate) fn contains(&self, id: LabelId) -> bool {
        self.bits[usize::from(id.0 >> 6)] & (1 << (id.0 & 63)) != 0
    }

    /// The object label of a dominant label: `None` when absent or ignored.
    #[inline]
    pub(crate) fn object(&self, dominant: Option<LabelId>) -> Option<LabelId> {
        dominant.filter(|&l| !self.contains(l))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_rename() {
        let mut s = LabelSet::household();
        assert_eq!(s.id("toilet"), Some(LabelId(14)));
        assert_eq!(s.name(LabelId(2)), Some("floor"));
        s.insert(LabelId(14), "wc", false).unwrap();
        assert_eq!(s.id("toilet"), None);
        assert_eq!(s.id("wc"), Some(LabelId(14)));
        assert!(matches!(
            s.insert(LabelId(99), "wc", false),
            Err(MapError::DuplicateLabelName { .. })
        ));
        assert!(s.insert(LabelId(99), "", false).is_err());
        let json = serde_json::to_string(&s).unwrap();
        let back: LabelSet = serde_json::from_str(&json).unwrap();
        assert_eq!(back, s);
    }

    #[test]
    fn duplicate_names_rejected_on_load() {
        let json = r#"{"names":{"1":"a","2":"a"},"ignored":[]}"#;
        assert!(serde_json::from_str::<LabelSet>(json).is_err());
    }

    #[test]
    fn bitmap_matches_set() {
        let mut s = LabelSet::household();
        s.set_ignored(LabelId(u16::MAX), true);
        let b = s.ignored_bitmap();
        for id in [0u16, 1, 2, 3, 4, 10, 17, 63, 64, u16::MAX] {
            assert_eq!(b.contains(LabelId(id)), s.is_ignored(LabelId(id)), "{id}");
        }
        assert_eq!(b.object(Some(LabelId(1))), None);
        assert_eq!(b.object(Some(LabelId(10))), Some(LabelId(10)));
    }
}

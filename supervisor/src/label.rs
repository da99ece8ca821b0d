//! The normalised label vocabulary shared by the prior, the policies and the
//! HM3D statistics reader.
//!
//! Object detectors, HM3D-Semantics annotations and users spell the same
//! thing differently (`couch`, `Sofa`, `sectional_sofa`; `tv`, `television`,
//! `tv_monitor`). Every label entering the supervisor goes through
//! [`normalize_label`], so the prior built from HM3D and the contexts seen by
//! a robot share one vocabulary.

/// The six ObjectNav target categories of the HM3D challenge, in the
/// normalised vocabulary.
pub const OBJECTNAV_CATEGORIES: [&str; 6] =
    ["chair", "bed", "plant", "toilet", "tv_monitor", "sofa"];

/// Labels that describe building structure rather than a room's use. They
/// carry no evidence about which objects a region holds (HM3D's own tag
/// tables exclude the same set) and are dropped by [`normalize_label`].
pub const STRUCTURAL_LABELS: [&str; 8] = [
    "wall",
    "ceiling",
    "floor",
    "door",
    "door frame",
    "window",
    "window frame",
    "unknown",
];

/// Synonyms folded onto one canonical label (`from`, `to`), after case and
/// separator normalisation. The ObjectNav categories follow the groupings of
/// the Habitat HM3D ObjectNav task (chair includes armchairs and office
/// chairs; tv_monitor includes televisions and monitors; plant includes
/// potted and decorative plants).
const SYNONYMS: [(&str, &str); 34] = [
    ("couch", "sofa"),
    ("sofa seat", "sofa"),
    ("sectional sofa", "sofa"),
    ("tv", "tv_monitor"),
    ("tv monitor", "tv_monitor"),
    ("television", "tv_monitor"),
    ("led tv", "tv_monitor"),
    ("monitor", "tv_monitor"),
    ("computer monitor", "tv_monitor"),
    ("tv screen", "tv_monitor"),
    ("armchair", "chair"),
    ("desk chair", "chair"),
    ("office chair", "chair"),
    ("dining chair", "chair"),
    ("sofa chair", "chair"),
    ("decorative plant", "plant"),
    ("flowerpot", "plant"),
    ("flower pot", "plant"),
    ("potted plant", "plant"),
    ("plants", "plant"),
    ("flower", "plant"),
    ("house plant", "plant"),
    ("bunk bed", "bed"),
    ("double bed", "bed"),
    ("single bed", "bed"),
    ("trashcan", "trash can"),
    ("bin", "trash can"),
    ("garbage bin", "trash can"),
    ("fridge", "refrigerator"),
    ("bed table", "nightstand"),
    ("bedside table", "nightstand"),
    ("night stand", "nightstand"),
    ("bath tub", "bathtub"),
    ("washbasin", "sink"),
];

/// Normalises a raw object label into the supervisor's vocabulary.
///
/// Lower-cases, turns `_` and `-` into spaces, collapses white space, maps
/// synonyms (see the module docs) and drops structural labels.
///
/// # Returns
/// `None` for empty or structural labels (they carry no evidence), the
/// canonical label otherwise. Labels outside the prior's vocabulary are kept:
/// the prior ignores what it does not know.
///
/// # Complexity
/// O(n + s) for a label of n bytes and s synonyms.
///
/// # Examples
/// ```
/// use sornav_supervisor::normalize_label;
/// assert_eq!(normalize_label("Couch").as_deref(), Some("sofa"));
/// assert_eq!(normalize_label("TV_Monitor").as_deref(), Some("tv_monitor"));
/// assert_eq!(normalize_label("door-frame"), None);
/// ```
pub fn normalize_label(raw: &str) -> Option<String> {
    let mut out = String::with_capacity(raw.len());
    for word in raw
        .split(|c: char| c.is_whitespace() || c == '_' || c == '-')
        .filter(|w| !w.is_empty())
    {
        if !out.is_empty() {
            out.push(' ');
        }
        out.extend(word.chars().flat_map(char::to_lowercase));
    }
    if out.is_empty() || STRUCTURAL_LABELS.contains(&out.as_str()) {
        return None;
    }
    match SYNONYMS.iter().find(|(from, _)| *from == out) {
        Some((_, to)) => Some((*to).to_owned()),
        None => Some(out),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objectnav_categories_are_fixed_points() {
        for c in OBJECTNAV_CATEGORIES {
            assert_eq!(normalize_label(c).as_deref(), Some(c));
        }
    }

    #[test]
    fn synonyms_and_separators() {
        assert_eq!(
            normalize_label("  Sectional_Sofa ").as_deref(),
            Some("sofa")
        );
        assert_eq!(normalize_label("Television").as_deref(), Some("tv_monitor"));
        assert_eq!(normalize_label("office-chair").as_deref(), Some("chair"));
        assert_eq!(
            normalize_label("Kitchen  Cabinet").as_deref(),
            Some("kitchen cabinet")
        );
        assert_eq!(normalize_label(""), None);
        assert_eq!(normalize_label("   "), None);
        assert_eq!(normalize_label("WALL"), None);
    }

    #[test]
    fn normalisation_is_idempotent_on_canonical_labels() {
        for (_, to) in SYNONYMS {
            assert_eq!(normalize_label(to).as_deref(), Some(to));
        }
    }
}

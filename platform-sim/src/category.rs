//! Object categories and room types from free-text names.
//!
//! [`objectnav_category`] maps a furniture or object name to the ObjectNav
//! vocabulary: HM3D's six goal categories (chair, bed, plant, toilet,
//! tv_monitor, sofa) and MP3D's 21 (table, cabinet, cushion, picture, sink,
//! stool, towel, shower, bathtub, counter, fireplace, gym_equipment, seating,
//! clothes, chest_of_drawers, ...). [`classify`] applies the Sweet Home 3D rule:
//! name first, catalog id second, otherwise the piece keeps its own label.
//!
//! # One label vocabulary with the agent
//! The agent reads every label through the supervisor's
//! [`normalize_label`], so the simulator
//! uses the same function and the same synonym table (`couch` -> `sofa`,
//! `television` -> `tv_monitor`, `bedside table` -> `nightstand`) instead of
//! a copy: a name's category is its agent label, then folded by this
//! module's coarser catalogue table ([`COARSE`]: a wardrobe or a nightstand
//! is a `cabinet`, as in the procedural houses' statistics). Every label the
//! simulator emits is therefore a fixed point of the agent's normaliser
//! (written with `_` for spaces), and the goal lists are the agent's
//! ([`HM3D_GOALS`] is [`OBJECTNAV_CATEGORIES`]).
//! The tests check both.

use std::sync::OnceLock;

use sornav_supervisor::{OBJECTNAV_CATEGORIES, normalize_label};

use crate::scene::RoomType;

/// HM3D ObjectNav goal categories: the agent's
/// [`OBJECTNAV_CATEGORIES`].
pub const HM3D_GOALS: [&str; 6] = OBJECTNAV_CATEGORIES;

/// MP3D ObjectNav goal categories (the 21 of the Habitat challenge).
pub const MP3D_GOALS: [&str; 21] = [
    "chair",
    "table",
    "picture",
    "cabinet",
    "cushion",
    "sofa",
    "bed",
    "chest_of_drawers",
    "plant",
    "sink",
    "toilet",
    "stool",
    "towel",
    "tv_monitor",
    "shower",
    "bathtub",
    "counter",
    "fireplace",
    "gym_equipment",
    "seating",
    "clothes",
];

/// Catalogue phrases that name an object, searched in this order: the
/// first phrase contained in the normalised name (as whole words) wins, so
/// specific phrases come first. A phrase's category is its agent label
/// (synonyms folded by the supervisor's table), folded by [`COARSE`].
const PHRASES: &[&str] = &[
    "tv unit",
    "tv table",
    "tv stand",
    "tv cabinet",
    "television",
    "tv",
    "monitor",
    "screen",
    "toilet paper",
    "toilet",
    "wc",
    "bedside table",
    "bedside",
    "nightstand",
    "night stand",
    "bed",
    "beds",
    "bunk",
    "sofa",
    "couch",
    "settee",
    "armchair",
    "chair",
    "chairs",
    "stool",
    "bench",
    "bank",
    "seat",
    "plant",
    "plants",
    "flowers",
    "flower",
    "potted",
    "bathtub",
    "bath tub",
    "fitted bath",
    "bath",
    "tub",
    "shower",
    "washbasin",
    "wash basin",
    "sink",
    "basin",
    "chest of drawers",
    "dresser",
    "drawers",
    "chest",
    "table",
    "desk",
    "wardrobe",
    "cupboard",
    "cabinet",
    "sideboard",
    "bookcase",
    "bookshelf",
    "shelf",
    "shelves",
    "counter",
    "worktop",
    "fireplace",
    "towel",
    "towels",
    "cushion",
    "pillow",
    "picture",
    "painting",
    "poster",
    "frame",
    "clothes washer",
    "washing machine",
    "clothes",
    "treadmill",
    "exercise",
    "gym",
    "fridge",
    "refrigerator",
    "cooker",
    "stove",
    "oven",
    "dishwasher",
    "mirror",
    "lamp",
    "light",
    "uplight",
    "spotlight",
    "radiator",
    "piano",
];

/// The simulator's catalogue folds: agent labels (the supervisor's
/// vocabulary, `_` for spaces) that the simulator's coarser ObjectNav
/// categories group (MP3D's grouping: wardrobes and nightstands are
/// cabinets, desks are tables). Not synonyms: the agent keeps these labels
/// apart, the simulator never emits them. Every label without a fold here
/// is its own category.
pub const COARSE: &[(&str, &str)] = &[
    ("tv_unit", "tv_monitor"),
    ("tv_table", "table"),
    ("tv_stand", "cabinet"),
    ("tv_cabinet", "cabinet"),
    ("screen", "tv_monitor"),
    ("wc", "toilet"),
    ("bedside", "cabinet"),
    ("nightstand", "cabinet"),
    ("beds", "bed"),
    ("bunk", "bed"),
    ("settee", "sofa"),
    ("chairs", "chair"),
    ("bench", "seating"),
    ("bank", "seating"),
    ("seat", "seating"),
    ("flowers", "plant"),
    ("potted", "plant"),
    ("fitted_bath", "bathtub"),
    ("bath", "bathtub"),
    ("tub", "bathtub"),
    ("wash_basin", "sink"),
    ("basin", "sink"),
    ("dresser", "chest_of_drawers"),
    ("drawers", "chest_of_drawers"),
    ("chest", "chest_of_drawers"),
    ("desk", "table"),
    ("wardrobe", "cabinet"),
    ("cupboard", "cabinet"),
    ("sideboard", "cabinet"),
    ("bookcase", "shelving"),
    ("bookshelf", "shelving"),
    ("shelf", "shelving"),
    ("shelves", "shelving"),
    ("worktop", "counter"),
    ("towels", "towel"),
    ("pillow", "cushion"),
    ("painting", "picture"),
    ("poster", "picture"),
    ("frame", "picture"),
    ("clothes_washer", "washing_machine"),
    ("treadmill", "gym_equipment"),
    ("exercise", "gym_equipment"),
    ("gym", "gym_equipment"),
    ("cooker", "stove"),
    ("oven", "stove"),
    ("light", "lamp"),
    ("uplight", "lamp"),
    ("spotlight", "lamp"),
];

/// The agent's label of `name` (the supervisor's
/// [`normalize_label`]: case,
/// separators, synonyms), written with `_` for spaces as the simulator's
/// labels are; `None` for empty and structural names (wall, floor, door,
/// ...).
///
/// # Examples
/// ```
/// use sornav_platform_sim::category::agent_label;
/// assert_eq!(agent_label("Couch").as_deref(), Some("sofa"));
/// assert_eq!(agent_label("chest of drawers").as_deref(), Some("chest_of_drawers"));
/// assert_eq!(agent_label("Wall"), None);
/// ```
pub fn agent_label(name: &str) -> Option<String> {
    normalize_label(name).map(|l| l.replace(' ', "_"))
}

/// The simulator's category of an agent label: its [`COARSE`] fold, or
/// the label itself.
fn coarse(label: String) -> String {
    COARSE
        .iter()
        .find(|(from, _)| *from == label)
        .map_or(label, |(_, to)| (*to).to_owned())
}

/// `(phrase, category)` for every entry of [`PHRASES`], computed once.
fn rules() -> &'static [(&'static str, String)] {
    static RULES: OnceLock<Vec<(&'static str, String)>> = OnceLock::new();
    RULES.get_or_init(|| {
        PHRASES
            .iter()
            .map(|&p| {
                let label = agent_label(p).unwrap_or_else(|| p.replace(' ', "_"));
                (p, coarse(label))
            })
            .collect()
    })
}

/// Lower-cases, splits camelCase and keeps letters/digits as space-separated words.
pub fn normalise(name: &str) -> String {
    let mut out = String::with_capacity(name.len() + 4);
    let mut prev_lower = false;
    for ch in name.chars() {
        if ch.is_alphanumeric() {
            if ch.is_uppercase() && prev_lower {
                out.push(' ');
            }
            prev_lower = ch.is_lowercase() || ch.is_ascii_digit();
            out.extend(ch.to_lowercase());
        } else {
            prev_lower = false;
            if !out.ends_with(' ') {
                out.push(' ');
            }
        }
    }
    out.trim().to_string()
}

fn contains_phrase(words: &str, phrase: &str) -> bool {
    let padded = format!(" {words} ");
    padded.contains(&format!(" {phrase} "))
}

/// ObjectNav category of a name ("Toilet unit" -> "toilet", "Flat TV" ->
/// "tv_monitor"), or `None` when no rule applies.
///
/// # Complexity
/// O(R * L) for R rules and a name of length L.
pub fn objectnav_category(name: &str) -> Option<&'static str> {
    let n = normalise(name);
    if n.is_empty() {
        return None;
    }
    rules()
        .iter()
        .find(|(p, _)| contains_phrase(&n, p))
        .map(|(_, c)| c.as_str())
}

/// The label of an object name that no catalogue phrase recognises: its
/// agent label folded by [`COARSE`] (so "Flowerpot" is a plant to the
/// simulator too), or, for names the agent's normaliser drops (structural
/// words), the normalised name with `_` for spaces; `None` for an empty
/// name.
pub fn own_label(name: &str) -> Option<String> {
    let n = normalise(name);
    if n.is_empty() {
        return None;
    }
    Some(agent_label(&n).map_or_else(|| n.replace(' ', "_"), coarse))
}

/// Sweet Home 3D classification: `name` first, then the catalog id
/// (`eTeks#toiletUnit` -> "toilet unit"), otherwise the piece's own label
/// ([`own_label`] of the name, else of the catalog id, else "object").
pub fn classify(name: &str, catalog_id: Option<&str>) -> String {
    if let Some(c) = objectnav_category(name) {
        return c.to_string();
    }
    let cat_name = catalog_id
        .map(|id| id.rsplit('#').next().unwrap_or(id))
        .unwrap_or("");
    if let Some(c) = objectnav_category(cat_name) {
        return c.to_string();
    }
    own_label(name)
        .or_else(|| own_label(cat_name))
        .unwrap_or_else(|| "object".to_string())
}

/// Room type from a room name ("Bedroom #2" -> bedroom, "Corridor" -> hallway).
pub fn room_type_from_name(name: &str) -> RoomType {
    let n = normalise(name);
    let has = |ws: &[&str]| {
        ws.iter()
            .any(|w| contains_phrase(&n, w) || n.split(' ').any(|t| t.starts_with(w)))
    };
    if has(&["bedroom", "bedrom", "bed room", "nursery", "guest room"]) {
        RoomType::Bedroom
    } else if has(&["bathroom", "bath", "shower room", "washroom"]) {
        RoomType::Bathroom
    } else if has(&["toilet", "wc", "lavatory", "restroom"]) {
        RoomType::Toilet
    } else if has(&["kitchen", "kitchenette"]) {
        RoomType::Kitchen
    } else if has(&["dining"]) {
        RoomType::DiningRoom
    } else if has(&[
        "living",
        "lounge",
        "salon",
        "family room",
        "rec room",
        "sitting",
    ]) {
        RoomType::LivingRoom
    } else if has(&["stair"]) {
        RoomType::Stairs
    } else if has(&[
        "corridor", "hall", "hallway", "entrance", "entry", "landing", "foyer", "lobby",
    ]) {
        RoomType::Hallway
    } else if has(&["office", "study", "library", "workroom"]) {
        RoomType::Office
    } else if has(&["laundry", "utility"]) {
        RoomType::Laundry
    } else if has(&["closet", "dressing", "pantry", "wardrobe"]) {
        RoomType::Closet
    } else if has(&["garage", "carport"]) {
        RoomType::Garage
    } else if has(&[
        "balcony", "terrace", "porch", "garden", "patio", "exterior", "deck",
    ]) {
        RoomType::Outdoor
    } else if has(&["attic", "basement", "cellar", "storage", "loft"]) {
        RoomType::Storage
    } else {
        RoomType::Other
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_sweet_home_names() {
        assert_eq!(objectnav_category("Toilet unit"), Some("toilet"));
        assert_eq!(objectnav_category("Flat TV"), Some("tv_monitor"));
        assert_eq!(objectnav_category("TV unit"), Some("tv_monitor"));
        assert_eq!(objectnav_category("TV table"), Some("table"));
        assert_eq!(objectnav_category("Bed 90x190"), Some("bed"));
        assert_eq!(objectnav_category("Bedside table"), Some("cabinet"));
        assert_eq!(objectnav_category("Corner sofa"), Some("sofa"));
        assert_eq!(objectnav_category("Washbasin with cabinet"), Some("sink"));
        assert_eq!(objectnav_category("Pendant lamp"), Some("lamp"));
        assert_eq!(objectnav_category("Box"), None);
        assert_eq!(classify("Box", Some("eTeks#texturableBox")), "box");
        assert_eq!(classify("", Some("eTeks#toiletUnit")), "toilet");
        assert_eq!(classify("Kitchen", Some("eTeks#kitchenCabinet")), "cabinet");
        assert_eq!(classify("Railing", None), "railing");
        assert_eq!(classify("", None), "object");
    }

    /// The agent's synonyms decide where they apply: the simulator's old
    /// copy called a bedside table a table, the agent a nightstand (now a
    /// cabinet to the simulator, as every nightstand); a flowerpot was not
    /// a plant to the simulator but was one to the agent.
    #[test]
    fn agent_synonyms_apply_in_the_simulator() {
        assert_eq!(objectnav_category("Bedside table"), Some("cabinet"));
        assert_eq!(objectnav_category("Night stand"), Some("cabinet"));
        assert_eq!(objectnav_category("Corner couch"), Some("sofa"));
        assert_eq!(objectnav_category("Fridge & Freezer"), Some("refrigerator"));
        assert_eq!(classify("Flowerpot", None), "plant");
        assert_eq!(classify("Trashcan", None), "trash_can");
    }

    /// Every label the simulator can emit means the same to the agent: a
    /// fixed point of the agent's normaliser and of the catalogue folds.
    #[test]
    fn emitted_labels_are_agent_labels() {
        let fixed = |c: &str| {
            assert_eq!(agent_label(c).as_deref(), Some(c), "agent relabels {c}");
            assert_eq!(coarse(c.to_owned()), c, "folded twice: {c}");
        };
        for (phrase, c) in rules() {
            assert!(!c.is_empty(), "{phrase}");
            fixed(c);
        }
        for c in HM3D_GOALS.iter().chain(&MP3D_GOALS) {
            fixed(c);
        }
        for (from, to) in COARSE {
            // A fold applies to agent labels only (a key the agent renames
            // would never be reached) and lands on a category.
            assert_eq!(agent_label(from).as_deref(), Some(*from), "{from}");
            fixed(to);
            assert!(
                PHRASES.iter().any(|p| p.replace(' ', "_") == *from),
                "{from}"
            );
        }
        // The procedural houses' categories.
        let stats: serde_json::Value =
            serde_json::from_str(include_str!("../data/hm3d_val_stats.json")).unwrap();
        for room in stats["room_types"].as_array().unwrap() {
            for o in room["objects"].as_array().unwrap() {
                fixed(o["category"].as_str().unwrap());
            }
        }
    }

    #[test]
    fn room_types() {
        assert_eq!(room_type_from_name("Bedroom #2"), RoomType::Bedroom);
        assert_eq!(room_type_from_name("Bedrom #3"), RoomType::Bedroom);
        assert_eq!(room_type_from_name("Corridor"), RoomType::Hallway);
        assert_eq!(room_type_from_name("2nd floor corridor"), RoomType::Hallway);
        assert_eq!(room_type_from_name("Living Room"), RoomType::LivingRoom);
        assert_eq!(room_type_from_name("Bathroom"), RoomType::Bathroom);
        assert_eq!(room_type_from_name("Balcony"), RoomType::Outdoor);
        assert_eq!(room_type_from_name(""), RoomType::Other);
    }
}

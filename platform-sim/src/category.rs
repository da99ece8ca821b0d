//! Object categories and room types from free-text names.
//!
//! [`objectnav_category`] maps a furniture or object name to the ObjectNav
//! vocabulary: HM3D's six goal categories (chair, bed, plant, toilet,
//! tv_monitor, sofa) and MP3D's 21 (table, cabinet, cushion, picture, sink,
//! stool, towel, shower, bathtub, counter, fireplace, gym_equipment, seating,
//! clothes, chest_of_drawers, ...). [`classify`] applies the Sweet Home 3D rule:
//! name first, catalog id second, otherwise the piece keeps its own label.

use crate::scene::RoomType;

/// HM3D ObjectNav goal categories.
pub const HM3D_GOALS: [&str; 6] = ["chair", "bed", "plant", "toilet", "tv_monitor", "sofa"];

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

/// Ordered (phrase, category) rules; the first phrase contained in the
/// normalised name (as whole words) wins, so specific phrases come first.
const RULES: &[(&str, &str)] = &[
    ("tv unit", "tv_monitor"),
    ("tv table", "table"),
    ("tv stand", "cabinet"),
    ("tv cabinet", "cabinet"),
    ("television", "tv_monitor"),
    ("tv", "tv_monitor"),
    ("monitor", "tv_monitor"),
    ("screen", "tv_monitor"),
    ("toilet paper", "toilet_paper"),
    ("toilet", "toilet"),
    ("wc", "toilet"),
    ("bedside table", "table"),
    ("bedside", "cabinet"),
    ("nightstand", "cabinet"),
    ("night stand", "cabinet"),
    ("bed", "bed"),
    ("beds", "bed"),
    ("bunk", "bed"),
    ("sofa", "sofa"),
    ("couch", "sofa"),
    ("settee", "sofa"),
    ("armchair", "chair"),
    ("chair", "chair"),
    ("chairs", "chair"),
    ("stool", "stool"),
    ("bench", "seating"),
    ("bank", "seating"),
    ("seat", "seating"),
    ("plant", "plant"),
    ("plants", "plant"),
    ("flowers", "plant"),
    ("flower", "plant"),
    ("potted", "plant"),
    ("bathtub", "bathtub"),
    ("bath tub", "bathtub"),
    ("fitted bath", "bathtub"),
    ("bath", "bathtub"),
    ("tub", "bathtub"),
    ("shower", "shower"),
    ("washbasin", "sink"),
    ("wash basin", "sink"),
    ("sink", "sink"),
    ("basin", "sink"),
    ("chest of drawers", "chest_of_drawers"),
    ("dresser", "chest_of_drawers"),
    ("drawers", "chest_of_drawers"),
    ("chest", "chest_of_drawers"),
    ("table", "table"),
    ("desk", "table"),
    ("wardrobe", "cabinet"),
    ("cupboard", "cabinet"),
    ("cabinet", "cabinet"),
    ("sideboard", "cabinet"),
    ("bookcase", "shelving"),
    ("bookshelf", "shelving"),
    ("shelf", "shelving"),
    ("shelves", "shelving"),
    ("counter", "counter"),
    ("worktop", "counter"),
    ("fireplace", "fireplace"),
    ("towel", "towel"),
    ("towels", "towel"),
    ("cushion", "cushion"),
    ("pillow", "cushion"),
    ("picture", "picture"),
    ("painting", "picture"),
    ("poster", "picture"),
    ("frame", "picture"),
    ("clothes washer", "washing_machine"),
    ("washing machine", "washing_machine"),
    ("clothes", "clothes"),
    ("treadmill", "gym_equipment"),
    ("exercise", "gym_equipment"),
    ("gym", "gym_equipment"),
    ("fridge", "refrigerator"),
    ("refrigerator", "refrigerator"),
    ("cooker", "stove"),
    ("stove", "stove"),
    ("oven", "stove"),
    ("dishwasher", "dishwasher"),
    ("mirror", "mirror"),
    ("lamp", "lamp"),
    ("light", "lamp"),
    ("uplight", "lamp"),
    ("spotlight", "lamp"),
    ("radiator", "radiator"),
    ("piano", "piano"),
];

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
    RULES
        .iter()
        .find(|(p, _)| contains_phrase(&n, p))
        .map(|(_, c)| *c)
}

/// Sweet Home 3D classification: `name` first, then the catalog id
/// (`eTeks#toiletUnit` -> "toilet unit"), otherwise the piece's own label
/// (normalised name with `_` for spaces, or "object" when both are empty).
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
    let own = normalise(name);
    let own = if own.is_empty() {
        normalise(cat_name)
    } else {
        own
    };
    if own.is_empty() {
        "object".to_string()
    } else {
        own.replace(' ', "_")
    }
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
        assert_eq!(objectnav_category("Bedside table"), Some("table"));
        assert_eq!(objectnav_category("Corner sofa"), Some("sofa"));
        assert_eq!(objectnav_category("Washbasin with cabinet"), Some("sink"));
        assert_eq!(objectnav_category("Pendant lamp"), Some("lamp"));
        assert_eq!(objectnav_category("Box"), None);
        assert_eq!(classify("Box", Some("eTeks#texturableBox")), "box");
        assert_eq!(classify("", Some("eTeks#toiletUnit")), "toilet");
        assert_eq!(classify("Kitchen", Some("eTeks#kitchenCabinet")), "cabinet");
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

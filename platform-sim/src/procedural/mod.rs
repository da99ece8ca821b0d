//! Procedural houses: the embedded default scene source, no data files needed.
//!
//! [`generate`] builds a seeded multi-room house with one to four floors
//! that imitates one HM3D validation house (statistics in [`HouseStats`],
//! derived from HM3D-Semantics v0.2 by the `derive_hm3d_stats` example):
//!
//! 1. **Size** — the number of floors is drawn from HM3D's floor counts
//!    over all 900 scenes ([`HM3D_FLOOR_COUNTS`]: 35 / 41 / 21 / 3 % for
//!    1 / 2 / 3 / 4+ floors), then a validation house of that floor class
//!    (floors, rooms, navigable area) uniformly ([`house_record`]; four or
//!    more floors are built as four). The house gets that many rooms (a
//!    house of F > 1 floors at least F + 2), where the stairwell (the core
//!    [`STAIRWELL`] on the ground floor and its upper parts
//!    [`STAIRWELL_LANDING`]) counts as one Hall/stairwell room, as HM3D
//!    annotates a stairwell spanning floors as one region. The footprint
//!    of a floor is the navigable area times [`FOOTPRINT_PER_NAVIGABLE`]
//!    shared by the floors plus half the stairwell's void, at least
//!    [`MIN_ROOM_AREA`] per room plus the stairwell core.
//! 2. **Room types** — a house of R rooms expects `mean_t R / M` rooms of
//!    type t (HM3D's mean per scene `mean_t`, `M` their sum; HM3D's stairs
//!    regions count as hallways). Each type is present with HM3D's fraction
//!    of scenes holding it (lowered for houses too small to expect one), and
//!    the remaining rooms go to the types present in proportion to their
//!    expected extra rooms (see `sample_room_types`). Rooms are dealt to the
//!    floors evenly, in the order kitchens, living and dining rooms,
//!    garages, laundries, offices ... bedrooms, so that the ground floor
//!    gets the day rooms and the top floor the bedrooms.
//! 3. **Stairs** — houses with several floors reserve a stairwell core at
//!    one corner on every floor: two lanes of [`STAIR_WIDTH`] side by side,
//!    a floor landing of [`STAIR_END`] at each end. Each storey gets,
//!    with probability 1/2 each ([`StairShape`]), a straight flight (from
//!    one end to the other) or a switchback (a flight up to a half landing
//!    of [`HALF_LANDING`] at half the storey height, a flight back); the
//!    next storey's stair starts where it arrives, its first flight in the
//!    lane beside the last flight below, so the stairs stack and no flight
//!    runs right above the top of another (head room over every tread and
//!    landing: at least half a storey). Risers are the storey height over
//!    `ceil(h / MAX_RISER)` ([`MAX_RISER`] 0.18 m, under the agent's 0.2 m
//!    step; 0.177 m straight and 0.166 m switchback at the default 2.65 m),
//!    treads [`STAIR_RUN`] deep. Upstairs the core has a floor only at its
//!    landing end (the stairwell hole) and opens there onto the floor (a
//!    door, or the landing strip beside a north landing); the ground floor
//!    core opens beside the foot of the stairs. The rest of each floor is
//!    cut recursively into one rectangle per room, areas in proportion to
//!    the room type (a living room about three times a bathroom), no
//!    narrower than `min_room_side`.
//! 4. **Doors** — a random spanning tree of the room adjacency graph (plus
//!    extra doors with probability [`EXTRA_DOOR_PROBABILITY`]) gets door
//!    openings, so every room is reachable; walls are extruded with
//!    thickness and lintels over doors.
//! 5. **Furniture** — each room (but the stairwell) draws its objects from
//!    its type's statistics: every category the generator can build
//!    ([`furniture::SHAPES`], 31 categories) is present with HM3D's
//!    probability for that room type and has `1 + G` instances, G geometric
//!    with mean `mean_count - 1`, at most the shape's `max_per_room`.
//!    Pieces are composite boxes ([`furniture`]) placed against walls (side by
//!    side, keeping [`WALL_FRONT_CLEARANCE`] in front), in the free area, at
//!    tables (chairs, stools) or hung on walls at [`MOUNT_HEIGHT`], keeping
//!    [`DOOR_CLEARANCE`] at doorways. A piece is kept only if, on a 0.1 m grid
//!    where pieces are inflated by 0.3 m, all doorways of the room stay in one
//!    free component and every piece keeps a free cell of it within 0.8 m (so
//!    every room is reachable and every object has a view point). First
//!    instances of every category are placed before second ones, large and
//!    common pieces first; pieces that do not fit are dropped (about 5 % of
//!    the category presences in the `procedural_stats` test houses). With
//!    `shuffled_semantics` the rooms' object lists are drawn as usual and
//!    then dealt to the rooms in random order: the house keeps its objects,
//!    the room-object association is gone.
//!
//! The `procedural_stats` test checks the outcome against the statistics
//! (floors, rooms and area per house, room-type frequencies, objects per
//! room type, shuffled semantics).
//!
//! Same seed and configuration, same house.

pub mod furniture;
pub mod stats;

use nalgebra::{Point2, Point3};
use petgraph::unionfind::UnionFind;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

pub use stats::{CategoryStats, HouseSize, HouseStats, RoomTypeStats};

use crate::SceneError;
use crate::geometry::MeshBuilder;
use crate::scene::{InstanceKind, Level, Room, RoomType, Scene};
use furniture::{Placement, shape};

/// Parameters of the procedural house generator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ProceduralConfig {
    /// Number of floors (1 to 4); `None` draws it from HM3D's floor counts
    /// ([`HM3D_FLOOR_COUNTS`]).
    pub floors: Option<u32>,
    /// Place objects ignoring room types (tests robustness when commonsense fails).
    pub shuffled_semantics: bool,
    /// Wall thickness (m).
    pub wall_thickness: f64,
    /// Wall height (m).
    pub wall_height: f64,
    /// Floor slab thickness (m).
    pub floor_thickness: f64,
    /// Door opening width (m).
    pub door_width: f64,
    /// Door opening height (m).
    pub door_height: f64,
    /// Smallest room side (m).
    pub min_room_side: f64,
    /// Most rooms per floor (the stairwell not counted; a house with stairs
    /// has at least two rooms downstairs and one on every upper floor). The default, 20,
    /// leaves HM3D's room counts uncapped.
    pub max_rooms_per_floor: u32,
    /// Footprint of every floor, `[width (x), depth (y)]` in m; `None` (the
    /// default) derives it from the imitated HM3D house's navigable area
    /// (30 to 500 m^2 per floor, a random aspect ratio). Set it for
    /// buildings of a given size, e.g. stress tests and benchmarks; each side
    /// must be in [6, 200] m and is still widened to fit the stairwell.
    pub footprint: Option<[f64; 2]>,
}

impl Default for ProceduralConfig {
    fn default() -> Self {
        ProceduralConfig {
            floors: None,
            shuffled_semantics: false,
            wall_thickness: 0.1,
            wall_height: 2.5,
            floor_thickness: 0.15,
            door_width: 0.9,
            door_height: 2.1,
            min_room_side: 2.4,
            max_rooms_per_floor: 20,
            footprint: None,
        }
    }
}

impl ProceduralConfig {
    /// Checks ranges.
    ///
    /// # Errors
    /// [`SceneError::Config`] naming the first invalid field.
    pub fn validate(&self) -> Result<(), SceneError> {
        let bad = |field: &'static str, message: &str| {
            Err(SceneError::Config {
                field,
                message: message.into(),
            })
        };
        if self.floors.is_some_and(|f| !(1..=MAX_FLOORS).contains(&f)) {
            return bad("floors", "must be in [1, 4]");
        }
        let t = self.wall_thickness;
        if !(t.is_finite() && (0.02..=0.5).contains(&t)) {
            return bad("wall_thickness", "must be in [0.02, 0.5]");
        }
        if !(self.wall_height.is_finite() && (2.0..=5.0).contains(&self.wall_height)) {
            return bad("wall_height", "must be in [2, 5]");
        }
        if !(self.floor_thickness.is_finite() && (0.02..=0.5).contains(&self.floor_thickness)) {
            return bad("floor_thickness", "must be in [0.02, 0.5]");
        }
        if !(self.door_width.is_finite() && (0.7..=2.0).contains(&self.door_width)) {
            return bad("door_width", "must be in [0.7, 2]");
        }
        if !(self.door_height.is_finite()
            && self.door_height >= 1.5
            && self.door_height < self.wall_height)
        {
            return bad("door_height", "must be in [1.5, wall_height)");
        }
        if !(self.min_room_side.is_finite() && (1.8..=6.0).contains(&self.min_room_side)) {
            return bad("min_room_side", "must be in [1.8, 6]");
        }
        if !(1..=40).contains(&self.max_rooms_per_floor) {
            return bad("max_rooms_per_floor", "must be in [1, 40]");
        }
        if self
            .footprint
            .is_some_and(|f| !f.iter().all(|s| s.is_finite() && (6.0..=200.0).contains(s)))
        {
            return bad("footprint", "each side must be in [6, 200] m");
        }
        Ok(())
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Rect {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
}

impl Rect {
    fn w(&self) -> f64 {
        self.x1 - self.x0
    }
    fn d(&self) -> f64 {
        self.y1 - self.y0
    }
    fn area(&self) -> f64 {
        self.w() * self.d()
    }
    fn overlaps(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
    /// The `w` x `d` rectangle centred at `c`.
    fn centred(c: Point2<f64>, w: f64, d: f64) -> Rect {
        Rect {
            x0: c.x - w * 0.5,
            x1: c.x + w * 0.5,
            y0: c.y - d * 0.5,
            y1: c.y + d * 0.5,
        }
    }
    /// Whether some side of `self` lies outside `r`.
    fn sticks_out_of(&self, r: &Rect) -> bool {
        self.x0 < r.x0 || self.x1 > r.x1 || self.y0 < r.y0 || self.y1 > r.y1
    }
    fn inflate(&self, m: f64) -> Rect {
        Rect {
            x0: self.x0 - m,
            y0: self.y0 - m,
            x1: self.x1 + m,
            y1: self.y1 + m,
        }
    }
    fn polygon(&self) -> Vec<Point2<f64>> {
        vec![
            Point2::new(self.x0, self.y0),
            Point2::new(self.x1, self.y0),
            Point2::new(self.x1, self.y1),
            Point2::new(self.x0, self.y1),
        ]
    }
}

/// A shared wall segment between two rooms: axis (0: wall along x at y = c;
/// 1: wall along y at x = c) and interval.
#[derive(Debug, Clone, Copy)]
struct Shared {
    axis: usize,
    c: f64,
    lo: f64,
    hi: f64,
}

fn shared(a: &Rect, b: &Rect) -> Option<Shared> {
    const E: f64 = 1e-6;
    if (a.x1 - b.x0).abs() < E || (b.x1 - a.x0).abs() < E {
        let c = if (a.x1 - b.x0).abs() < E { a.x1 } else { a.x0 };
        let (lo, hi) = (a.y0.max(b.y0), a.y1.min(b.y1));
        return (hi > lo).then_some(Shared { axis: 1, c, lo, hi });
    }
    if (a.y1 - b.y0).abs() < E || (b.y1 - a.y0).abs() < E {
        let c = if (a.y1 - b.y0).abs() < E { a.y1 } else { a.y0 };
        let (lo, hi) = (a.x0.max(b.x0), a.x1.min(b.x1));
        return (hi > lo).then_some(Shared { axis: 0, c, lo, hi });
    }
    None
}

struct FloorRoom {
    rect: Rect,
    room_type: RoomType,
    /// Stair block (no furniture; special door rules).
    stair: bool,
    /// Landing strip beside the stair block.
    landing: bool,
}

/// A door or open passage on a floor.
#[derive(Debug, Clone, Copy)]
struct Opening {
    seg: Shared,
    /// Full-height opening (stairwell exit) rather than a door with a lintel.
    open: bool,
    rooms: (usize, usize),
}

/// Relative floor area of a room type (a living room is about three times
/// a bathroom).
fn area_weight(t: RoomType) -> f64 {
    match t {
        RoomType::LivingRoom | RoomType::Garage => 2.0,
        RoomType::Kitchen | RoomType::DiningRoom => 1.4,
        RoomType::Bedroom => 1.3,
        RoomType::Office | RoomType::Other | RoomType::Storage | RoomType::Outdoor => 1.0,
        RoomType::Hallway | RoomType::Stairs => 0.8,
        RoomType::Laundry | RoomType::Bathroom => 0.8,
        RoomType::Toilet | RoomType::Closet => 0.5,
    }
}

/// Footprint (m^2) per m^2 of HM3D navigable area: walls, the agent-radius
/// band along them and furniture take the rest (calibrated so that the
/// walkable area of generated houses follows HM3D's navigable area, see the
/// `procedural_stats` test).
pub const FOOTPRINT_PER_NAVIGABLE: f64 = 1.95;

/// Name of the stairwell core on the ground floor of a house with stairs.
pub const STAIRWELL: &str = "stairwell";

/// Name of the stairwell's rooms on the upper floors (the core with its
/// landing, and the landing strip beside it); with the [`STAIRWELL`] below
/// they form one Hall/stairwell room in the statistics.
pub const STAIRWELL_LANDING: &str = "stairwell landing";

/// Largest share of a room's footprint that floor-standing furniture may take.
pub const MAX_FURNISHED_SHARE: f64 = 0.35;

/// Draws the objects of one room of type `rs`: each category the generator
/// can build is present with its HM3D probability (`presence`); a present
/// category gets `1 + G` instances, G geometric with mean `mean_count - 1`
/// (success probability capped at 0.9), at most the shape's `max_per_room`.
fn draw_objects(rng: &mut ChaCha8Rng, rs: &RoomTypeStats) -> Vec<Drawn> {
    let mut out = Vec::new();
    for cs in &rs.objects {
        let Some(sh) = shape(&cs.category) else {
            continue;
        };
        if rng.random::<f64>() >= cs.presence {
            continue;
        }
        let mut count = 1u32;
        let p_more = ((cs.mean_count - 1.0) / cs.mean_count).clamp(0.0, 0.9);
        while count < sh.max_per_room && rng.random::<f64>() < p_more {
            count += 1;
        }
        out.push(Drawn {
            shape: sh,
            count,
            presence: cs.presence,
        });
    }
    out
}

/// A category drawn for a room: its shape, number of instances and HM3D
/// presence (the placement priority).
#[derive(Debug, Clone, Copy)]
struct Drawn {
    shape: &'static furniture::Shape,
    count: u32,
    presence: f64,
}

/// Height above the floor of wall-mounted pieces (pictures, towels, mirrors).
pub const MOUNT_HEIGHT: f64 = 1.2;

/// Depth (m) of the floor kept clear on both sides of a doorway.
pub const DOOR_CLEARANCE: f64 = 0.7;

/// Probability of a door between adjacent rooms beyond the spanning tree.
pub const EXTRA_DOOR_PROBABILITY: f64 = 0.15;

/// Depth (m) of the floor kept clear in front of a piece standing against a
/// wall (nothing else may stand there).
pub const WALL_FRONT_CLEARANCE: f64 = 0.6;

/// Smallest footprint (m^2) reserved per room when a house has many rooms
/// for its area.
pub const MIN_ROOM_AREA: f64 = 9.0;

/// Floor preference of room types in houses with stairs (lower: ground floor).
fn ground_rank(t: RoomType) -> u32 {
    match t {
        RoomType::Garage | RoomType::Outdoor => 0,
        RoomType::Kitchen => 1,
        RoomType::LivingRoom => 2,
        RoomType::DiningRoom => 3,
        RoomType::Laundry | RoomType::Storage => 4,
        RoomType::Hallway | RoomType::Stairs => 5,
        RoomType::Office | RoomType::Other => 6,
        RoomType::Toilet | RoomType::Bathroom => 7,
        RoomType::Closet => 8,
        RoomType::Bedroom => 9,
    }
}

/// Mean rooms per scene of each room type the generator builds, with HM3D's
/// "stairs" regions merged into hallways (HM3D's Hall/stairwell class).
fn type_means(stats: &HouseStats) -> Vec<(RoomType, f64, f64)> {
    let stairs = stats
        .room_type(RoomType::Stairs)
        .map_or(0.0, |r| r.mean_per_scene);
    stats
        .room_types
        .iter()
        .filter(|r| r.room_type != RoomType::Stairs && r.mean_per_scene > 0.0)
        .map(|r| {
            let extra = if r.room_type == RoomType::Hallway {
                stairs
            } else {
                0.0
            };
            (
                r.room_type,
                r.mean_per_scene + extra,
                r.scene_presence.max(1e-6),
            )
        })
        .collect()
}

/// Draws the types of `n` rooms of one house (the stairwell of a two-floor
/// house not included) so that room-type frequencies and the fraction of
/// houses holding a type follow HM3D:
///
/// * a house of `R` rooms expects `mean_t * R / M` rooms of type t, with
///   `mean_t` the HM3D mean per scene and `M` their sum;
/// * type t is present ("anchored") with probability
///   `q_t = min(presence_t, mean_t * R / M)`, HM3D's fraction of scenes
///   holding it, lowered for houses too small to expect one;
/// * the remaining rooms go to anchored types, in proportion to their
///   expected extra rooms `(mean_t * R / M - q_t) / q_t`.
///
/// The stairwell counts as the house's Hall/stairwell anchor.
fn sample_room_types(
    rng: &mut ChaCha8Rng,
    stats: &HouseStats,
    n: usize,
    stairwell: bool,
) -> Vec<RoomType> {
    let means = type_means(stats);
    let m_total: f64 = means.iter().map(|m| m.1).sum::<f64>().max(1e-9);
    let total = n + usize::from(stairwell);
    let s = total as f64 / m_total;
    // (type, expected rooms, anchor probability, rooms so far)
    let mut table: Vec<(RoomType, f64, f64, usize)> = means
        .iter()
        .map(|&(t, mean, presence)| {
            let expected = mean * s;
            if stairwell && t == RoomType::Hallway {
                (t, expected, 1.0, 1)
            } else {
                (t, expected, presence.min(expected), 0)
            }
        })
        .collect();
    // anchors, most likely types first (random order among equals)
    let mut order: Vec<usize> = (0..table.len()).collect();
    shuffle(rng, &mut order);
    order.sort_by(|&a, &b| table[b].2.total_cmp(&table[a].2));
    let mut out = Vec::with_capacity(n);
    for i in order {
        if table[i].3 > 0 {
            continue;
        }
        if rng.random::<f64>() < table[i].2 && out.len() < n {
            table[i].3 += 1;
            out.push(table[i].0);
        }
    }
    // extra rooms among the types present
    while out.len() < n {
        let weights: Vec<(usize, f64)> = table
            .iter()
            .enumerate()
            .filter(|(_, r)| r.3 > 0)
            .map(|(i, r)| (i, ((r.1 - r.2) / r.2).max(0.0)))
            .collect();
        let pick = weighted_pick(rng, &weights).or_else(|| {
            let all: Vec<(usize, f64)> = table.iter().enumerate().map(|(i, r)| (i, r.1)).collect();
            weighted_pick(rng, &all)
        });
        let Some(i) = pick else {
            out.push(RoomType::Bedroom);
            continue;
        };
        table[i].3 += 1;
        out.push(table[i].0);
    }
    out
}

/// Splits `area` into one room per type, areas in proportion to
/// [`area_weight`]: the types are dealt into two groups of similar weight
/// (largest first, each to the lighter group), the rectangle is cut across
/// its longer side in that proportion (jittered by up to 15 %, keeping both
/// parts at least `min_side` wide), and both parts recurse. A rectangle that
/// cannot be cut keeps the first type of its group (the others are dropped).
///
/// # Complexity
/// O(n log n) for n types.
fn split_rooms(
    rng: &mut ChaCha8Rng,
    area: Rect,
    types: &[RoomType],
    min_side: f64,
    out: &mut Vec<(Rect, RoomType)>,
) {
    let Some(&first) = types.first() else {
        return;
    };
    if types.len() == 1 {
        out.push((area, first));
        return;
    }
    let mut order: Vec<RoomType> = types.to_vec();
    order.sort_by(|a, b| area_weight(*b).total_cmp(&area_weight(*a)));
    let (mut ga, mut gb) = (Vec::new(), Vec::new());
    let (mut wa, mut wb) = (0.0, 0.0);
    for t in order {
        if wa <= wb {
            wa += area_weight(t);
            ga.push(t);
        } else {
            wb += area_weight(t);
            gb.push(t);
        }
    }
    if rng.random::<bool>() {
        std::mem::swap(&mut ga, &mut gb);
        std::mem::swap(&mut wa, &mut wb);
    }
    let along_x = area.w() >= area.d();
    for x_axis in [along_x, !along_x] {
        let len = if x_axis { area.w() } else { area.d() };
        if len < 2.0 * min_side {
            continue;
        }
        let base = wa / (wa + wb);
        let jitter = rng.random_range(-0.15..=0.15) * base.min(1.0 - base);
        let frac = (base + jitter).clamp(min_side / len, 1.0 - min_side / len);
        let (a, b) = if x_axis {
            let x = area.x0 + frac * area.w();
            (Rect { x1: x, ..area }, Rect { x0: x, ..area })
        } else {
            let y = area.y0 + frac * area.d();
            (Rect { y1: y, ..area }, Rect { y0: y, ..area })
        };
        split_rooms(rng, a, &ga, min_side, out);
        split_rooms(rng, b, &gb, min_side, out);
        return;
    }
    out.push((area, first));
}

/// Fisher-Yates shuffle (from the back, one `random_range(0..=i)` per step).
fn shuffle<T>(rng: &mut ChaCha8Rng, v: &mut [T]) {
    for i in (1..v.len()).rev() {
        v.swap(i, rng.random_range(0..=i));
    }
}

fn weighted_pick<T: Copy>(rng: &mut ChaCha8Rng, items: &[(T, f64)]) -> Option<T> {
    let total: f64 = items.iter().map(|i| i.1).sum();
    if total <= 0.0 {
        return None;
    }
    let mut x = rng.random::<f64>() * total;
    for &(t, w) in items {
        if x < w {
            return Some(t);
        }
        x -= w;
    }
    items.last().map(|i| i.0)
}

/// Number of HM3D scenes by number of floors: 1, 2, 3 and 4 or more
/// (315, 369, 193 and 23 of the 900 scenes: 35.0, 41.0, 21.4 and 2.6 %).
///
/// Derived from the `num_floors` column of `hm3d_scene_metadata.csv` of the
/// HM3D-Semantics v0.2 statistics (Yadav et al. 2023,
/// matterport/habitat-matterport-3dresearch; train and validation scenes,
/// used under the Matterport academic terms); the 23 scenes of four or more
/// floors (20 of four, one each of five, six and eight) form one class.
/// No raw file is shipped.
pub const HM3D_FLOOR_COUNTS: [u32; 4] = [315, 369, 193, 23];

/// Most floors of a procedural house (HM3D's "four or more" class).
pub const MAX_FLOORS: u32 = 4;

/// Highest stair riser (m) of a procedural house: below the agent's 0.2 m
/// step ([`crate::NavMeshConfig::max_step`]).
pub const MAX_RISER: f64 = 0.18;

/// Tread depth (going) of the procedural stairs (m).
pub const STAIR_RUN: f64 = 0.26;

/// Clear width of a procedural stair flight between its wall and the
/// neighbouring flight (m).
pub const STAIR_WIDTH: f64 = 1.05;

/// Length (m) of the floor landing at each end of the stairwell (longer
/// when a door and its margins need more).
pub const STAIR_END: f64 = 1.5;

/// Length (m) of the half landing where a switchback stair turns.
pub const HALF_LANDING: f64 = 1.3;

/// Shape of the stair between two consecutive floors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum StairShape {
    /// One flight from one end of the stairwell to the other.
    Straight,
    /// Two flights in opposite directions joined by a half landing at half
    /// the storey height (a U / switchback stair); it ends where it starts.
    Switchback,
}

/// The stair joining floor `f` to floor `f + 1` in the stairwell core.
#[derive(Debug, Clone, Copy)]
struct StairModule {
    shape: StairShape,
    /// Departs from the south end (y = 0) of the core (else the north end).
    south: bool,
    /// Lane (0: x in [0, lane], 1: x in [lane, 2 lane]) of the first flight.
    first_lane: usize,
}

impl StairModule {
    fn last_lane(&self) -> usize {
        match self.shape {
            StairShape::Straight => self.first_lane,
            StairShape::Switchback => 1 - self.first_lane,
        }
    }
    /// End of the core where the stair arrives (south?).
    fn arrives_south(&self) -> bool {
        match self.shape {
            StairShape::Straight => !self.south,
            StairShape::Switchback => self.south,
        }
    }
}

/// Dimensions of the stairwell core (two lanes side by side along y).
#[derive(Debug, Clone, Copy)]
struct StairGeom {
    /// Lane width including half a wall thickness.
    lane: f64,
    /// Core width (two lanes).
    cw: f64,
    /// Core depth (along y).
    sd: f64,
    /// Floor landing length at each end.
    end: f64,
    /// Storey height.
    level_h: f64,
    /// Risers of a straight flight and their height.
    n: usize,
    rise: f64,
    /// Risers of each half of a switchback and their height.
    nh: usize,
    rise_h: f64,
}

impl StairGeom {
    fn new(cfg: &ProceduralConfig) -> StairGeom {
        let level_h = cfg.wall_height + cfg.floor_thickness;
        let n = ((level_h / MAX_RISER) - 1e-9).ceil().max(2.0) as usize;
        let nh = ((0.5 * level_h / MAX_RISER) - 1e-9).ceil().max(2.0) as usize;
        let lane = STAIR_WIDTH + 0.5 * cfg.wall_thickness;
        let end = STAIR_END.max(cfg.door_width + cfg.wall_thickness + 0.2);
        StairGeom {
            end,
            lane,
            cw: 2.0 * lane,
            sd: 2.0 * end + STAIR_RUN * (n - 1) as f64,
            level_h,
            n,
            rise: level_h / n as f64,
            nh,
            rise_h: 0.5 * level_h / nh as f64,
        }
    }

    /// Builds the stair of `m` from height `z` into instance `inst`:
    /// treads of [`STAIR_RUN`] as boxes a riser (plus 3 cm) thick, so that
    /// the space under a flight stays free; the half landing a slab of
    /// `slab` thickness.
    fn build(&self, b: &mut MeshBuilder, inst: u32, m: &StairModule, z: f64, t: f64, slab: f64) {
        let y_of = |s: f64| if m.south { s } else { self.sd - s };
        let lane_x = |lane: usize| {
            if lane == 0 {
                (0.5 * t, self.lane)
            } else {
                (self.lane, self.cw - 0.5 * t)
            }
        };
        let tread = |b: &mut MeshBuilder, lane: usize, s0: f64, s1: f64, h: f64, thick: f64| {
            let (x0, x1) = lane_x(lane);
            let (ya, yb) = (y_of(s0), y_of(s1));
            b.aabb_box(
                Point3::new(x0, ya.min(yb), h - thick),
                Point3::new(x1, ya.max(yb), h),
                inst,
            );
        };
        match m.shape {
            StairShape::Straight => {
                for i in 1..self.n {
                    let s0 = self.end + STAIR_RUN * (i - 1) as f64;
                    let h = z + self.rise * i as f64;
                    tread(b, m.first_lane, s0, s0 + STAIR_RUN, h, self.rise + 0.03);
                }
            }
            StairShape::Switchback => {
                let f1 = STAIR_RUN * (self.nh - 1) as f64;
                for i in 1..self.nh {
                    let s0 = self.end + STAIR_RUN * (i - 1) as f64;
                    let h = z + self.rise_h * i as f64;
                    tread(b, m.first_lane, s0, s0 + STAIR_RUN, h, self.rise_h + 0.03);
                }
                let (ya, yb) = (y_of(self.end + f1), y_of(self.end + f1 + HALF_LANDING));
                let hz = z + 0.5 * self.level_h;
                b.aabb_box(
                    Point3::new(0.5 * t, ya.min(yb), hz - slab),
                    Point3::new(self.cw - 0.5 * t, ya.max(yb), hz),
                    inst,
                );
                for j in 1..self.nh {
                    let s1 = self.end + f1 - STAIR_RUN * (j - 1) as f64;
                    let h = hz + self.rise_h * j as f64;
                    tread(b, m.last_lane(), s1 - STAIR_RUN, s1, h, self.rise_h + 0.03);
                }
            }
        }
    }

    /// The landing slab of the core at one end (south or north).
    fn end_rect(&self, south: bool) -> Rect {
        if south {
            Rect {
                x0: 0.0,
                y0: 0.0,
                x1: self.cw,
                y1: self.end,
            }
        } else {
            Rect {
                x0: 0.0,
                y0: self.sd - self.end,
                x1: self.cw,
                y1: self.sd,
            }
        }
    }
}

/// Draws the stairs of a house of `floors` floors, bottom up: each storey
/// gets a straight or a switchback stair with probability 1/2; the first
/// flight of a stair takes the lane beside the last flight of the stair
/// below (a flight never runs right above the top of the one below, which
/// keeps more than a storey height minus a riser of head room over every
/// flight and landing).
fn draw_stairs(rng: &mut ChaCha8Rng, floors: usize) -> Vec<StairModule> {
    let mut out: Vec<StairModule> = Vec::new();
    for _ in 1..floors {
        let shape = if rng.random::<bool>() {
            StairShape::Straight
        } else {
            StairShape::Switchback
        };
        let (south, first_lane) = match out.last() {
            None => (true, rng.random_range(0..2usize)),
            Some(p) => (p.arrives_south(), 1 - p.last_lane()),
        };
        out.push(StairModule {
            shape,
            south,
            first_lane,
        });
    }
    out
}

/// Floor class (1-4) of an HM3D house (four or more floors: 4).
fn floor_class(floors: u32) -> u32 {
    floors.clamp(1, MAX_FLOORS)
}

/// The generator's first draws: a floor class from [`HM3D_FLOOR_COUNTS`]
/// (or `floors` when given), then an HM3D validation house of that class,
/// uniformly (all houses when the statistics hold none of that class).
fn draw_house<'a>(
    rng: &mut ChaCha8Rng,
    stats: &'a HouseStats,
    floors: Option<u32>,
) -> Option<&'a HouseSize> {
    if stats.houses.is_empty() {
        return None;
    }
    let classes: Vec<(u32, f64)> = HM3D_FLOOR_COUNTS
        .iter()
        .enumerate()
        .map(|(i, &c)| (i as u32 + 1, f64::from(c)))
        .collect();
    let drawn = weighted_pick(rng, &classes).unwrap_or(1);
    let class = floors.map_or(drawn, floor_class);
    let of_class: Vec<&HouseSize> = stats
        .houses
        .iter()
        .filter(|h| floor_class(h.floors) == class)
        .collect();
    if of_class.is_empty() {
        stats.houses.get(rng.random_range(0..stats.houses.len()))
    } else {
        of_class.get(rng.random_range(0..of_class.len())).copied()
    }
}

/// The HM3D house (floors, rooms, navigable area) that the house of `seed`
/// imitates with the default configuration (`floors: None`): the
/// generator's first draws, a floor class from HM3D's floor counts
/// ([`HM3D_FLOOR_COUNTS`]) and a validation house of that class
/// (`None` without houses). The house gets `min(floors, 4)` floors.
pub fn house_record(seed: u64, stats: &HouseStats) -> Option<&HouseSize> {
    house_record_for(seed, stats, None)
}

/// [`house_record`] for a configuration's `floors` (a given number of floors
/// imitates a validation house of that floor class).
pub fn house_record_for(seed: u64, stats: &HouseStats, floors: Option<u32>) -> Option<&HouseSize> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    draw_house(&mut rng, stats, floors)
}

/// Generates a procedural house as a [`Scene`] (see the module docs).
///
/// # Errors
/// [`SceneError::Config`] for an invalid configuration; [`SceneError::Invalid`]
/// if the embedded statistics are unusable.
///
/// # Complexity
/// O(R^2 + F + S) for R rooms, F furniture pieces (placement by rejection
/// sampling with a bounded number of attempts) and S stair treads.
pub fn generate(seed: u64, config: &ProceduralConfig) -> Result<Scene, SceneError> {
    generate_with_stats(seed, config, HouseStats::embedded()?)
}

/// Rooms per floor: `n` rooms dealt as evenly as possible, lower floors
/// first, the ground floor at least two when the house has stairs.
fn rooms_per_floor(n: usize, floors: usize) -> Vec<usize> {
    let mut counts: Vec<usize> = (0..floors)
        .map(|f| n / floors + usize::from(f < n % floors))
        .collect();
    if floors > 1 {
        while counts[0] < 2 {
            match (1..floors).rev().find(|&f| counts[f] > 1) {
                Some(f) => {
                    counts[f] -= 1;
                    counts[0] += 1;
                }
                None => break,
            }
        }
    }
    counts
}

/// The mesh of floor `f`: a floor slab per room (upstairs the stairwell
/// core has a slab only at its landing end, `south_end` or north), ceilings
/// on the top floor (`top`), and the walls with their door openings.
/// Returns the floor's [`Level`] and its named [`Room`]s.
fn floor_geometry(
    b: &mut MeshBuilder,
    f: usize,
    rooms: &[FloorRoom],
    openings: &[Opening],
    (top, south_end): (bool, bool),
    g: &StairGeom,
    config: &ProceduralConfig,
) -> (Level, Vec<Room>) {
    let mut rooms_out = Vec::with_capacity(rooms.len());
    let z = f as f64 * g.level_h;
    let level = Level {
        name: if f == 0 {
            "Ground floor".into()
        } else {
            format!("Floor {f}")
        },
        elevation: z,
        height: config.wall_height,
        floor_thickness: config.floor_thickness,
    };
    for (ri, r) in rooms.iter().enumerate() {
        let name = if r.stair && f == 0 {
            STAIRWELL.to_string()
        } else if r.stair || r.landing {
            STAIRWELL_LANDING.to_string()
        } else {
            format!("{} {}", r.room_type.label(), ri)
        };
        rooms_out.push(Room {
            name: name.clone(),
            room_type: r.room_type,
            level: f,
            polygon: r.rect.polygon(),
            floor_z: z,
        });
        // upstairs the core has a floor only at its landing end (the
        // rest is the stairwell's void)
        let slab = if r.stair && f > 0 {
            g.end_rect(south_end)
        } else {
            r.rect
        };
        let fl = b.add_instance(InstanceKind::Floor, "floor", &name, f);
        b.aabb_box(
            Point3::new(slab.x0, slab.y0, z - config.floor_thickness),
            Point3::new(slab.x1, slab.y1, z),
            fl,
        );
        if top {
            let c = b.add_instance(InstanceKind::Ceiling, "ceiling", &name, f);
            b.horizontal_polygon(&r.rect.polygon(), z + config.wall_height, false, c);
        }
    }
    build_walls(b, rooms, openings, f, z, config);
    (level, rooms_out)
}

/// Where one floor's rooms go: the house outline and, with stairs, the
/// stairwell core.
#[derive(Debug, Clone, Copy)]
struct FloorOutline {
    /// Floor index (0: ground floor).
    floor: usize,
    /// Whether the house has stairs (a core on every floor).
    stairwell: bool,
    /// The stairwell core.
    core: Rect,
    /// House width (x), metres.
    width: f64,
    /// House depth (y), metres.
    depth: f64,
}

/// The rooms of one floor: the stairwell core and, upstairs, its landing
/// strip; the rest of the outline split into areas, the floor's room types
/// dealt to the areas in proportion to their area, and each area split
/// recursively into rooms ([`split_rooms`]).
fn floor_rooms(
    rng: &mut ChaCha8Rng,
    outline: &FloorOutline,
    floor_types: &[RoomType],
    g: &StairGeom,
    config: &ProceduralConfig,
) -> Vec<FloorRoom> {
    let FloorOutline {
        floor: f,
        stairwell,
        core,
        width: w,
        depth: d,
    } = *outline;
    let mut rooms = Vec::new();
    let areas: Vec<Rect> = if stairwell {
        rooms.push(FloorRoom {
            rect: core,
            room_type: if f == 0 {
                RoomType::Stairs
            } else {
                RoomType::Hallway
            },
            stair: true,
            landing: false,
        });
        if f == 0 {
            // ground floor: a strip across the whole house above the
            // core and the area beside it
            vec![
                Rect {
                    x0: 0.0,
                    y0: g.sd,
                    x1: w,
                    y1: d,
                },
                Rect {
                    x0: g.cw,
                    y0: 0.0,
                    x1: w,
                    y1: g.sd,
                },
            ]
        } else {
            // upper floors: a landing strip beyond the core's north end
            rooms.push(FloorRoom {
                rect: Rect {
                    x0: 0.0,
                    y0: g.sd,
                    x1: g.cw,
                    y1: d,
                },
                room_type: RoomType::Hallway,
                stair: false,
                landing: true,
            });
            vec![Rect {
                x0: g.cw,
                y0: 0.0,
                x1: w,
                y1: d,
            }]
        }
    } else {
        vec![Rect {
            x0: 0.0,
            y0: 0.0,
            x1: w,
            y1: d,
        }]
    };
    // deal the floor's types to its areas in proportion to their area
    // (each type to the area furthest below its share; every area gets one)
    let total_area: f64 = areas.iter().map(Rect::area).sum();
    let w_total: f64 = floor_types.iter().map(|&t| area_weight(t)).sum();
    let want: Vec<f64> = areas
        .iter()
        .map(|a| w_total * a.area() / total_area)
        .collect();
    let mut groups: Vec<Vec<RoomType>> = vec![Vec::new(); areas.len()];
    let mut got = vec![0.0; areas.len()];
    for (i, &t) in floor_types.iter().enumerate() {
        let empty: Vec<usize> = (0..areas.len()).filter(|&k| groups[k].is_empty()).collect();
        let k = if floor_types.len() - i <= empty.len() {
            empty[0]
        } else {
            (0..areas.len())
                .max_by(|&a, &b| (want[a] - got[a]).total_cmp(&(want[b] - got[b])))
                .unwrap_or(0)
        };
        groups[k].push(t);
        got[k] += area_weight(t);
    }
    for (a, group) in areas.iter().zip(&groups) {
        let mut leaves = Vec::new();
        split_rooms(rng, *a, group, config.min_room_side, &mut leaves);
        for (rect, room_type) in leaves {
            rooms.push(FloorRoom {
                rect,
                room_type,
                stair: false,
                landing: false,
            });
        }
    }
    rooms
}

/// The doors of one floor: a candidate opening (random position) on every
/// wall two rooms share (the stairwell core only beside its landing, `south`
/// or north), then a random spanning tree over them plus extras with
/// probability [`EXTRA_DOOR_PROBABILITY`], then narrower doors on the
/// longest shared wall between rooms still cut off, until every room is
/// connected or no wall is left.
fn floor_openings(
    rng: &mut ChaCha8Rng,
    rooms: &[FloorRoom],
    south: bool,
    g: &StairGeom,
    config: &ProceduralConfig,
) -> Vec<Opening> {
    let t = config.wall_thickness;
    let mut cands: Vec<Opening> = Vec::new();
    let mut forced: Vec<Opening> = Vec::new();
    for i in 0..rooms.len() {
        for j in i + 1..rooms.len() {
            let Some(mut s) = shared(&rooms[i].rect, &rooms[j].rect) else {
                continue;
            };
            let (a, b) = (&rooms[i], &rooms[j]);
            if (a.stair && b.landing) || (a.landing && b.stair) {
                // the landing strip opens onto a north landing
                if !south {
                    forced.push(Opening {
                        seg: s,
                        open: true,
                        rooms: (i, j),
                    });
                }
                continue;
            }
            if a.stair || b.stair {
                // the core opens only beside its landing on this floor
                // (the rest of its side is a void or a flight)
                if s.axis != 1 {
                    continue;
                }
                if south {
                    s.hi = s.hi.min(g.end);
                } else {
                    s.lo = s.lo.max(g.sd - g.end);
                }
            }
            let margin = 0.05 + t * 0.5;
            if s.hi - s.lo < config.door_width + 2.0 * margin {
                continue;
            }
            let free = s.hi - s.lo - config.door_width - 2.0 * margin;
            let lo = s.lo + margin + rng.random::<f64>() * free;
            cands.push(Opening {
                seg: Shared {
                    lo,
                    hi: lo + config.door_width,
                    ..s
                },
                open: false,
                rooms: (i, j),
            });
        }
    }
    // random spanning tree + extras
    let mut sets = UnionFind::<usize>::new(rooms.len());
    let mut chosen = forced.clone();
    for o in &forced {
        sets.union(o.rooms.0, o.rooms.1);
    }
    let mut order: Vec<usize> = (0..cands.len()).collect();
    shuffle(rng, &mut order);
    for &k in &order {
        let o = cands[k];
        // a tree edge, or (drawn only then) an extra door
        if sets.union(o.rooms.0, o.rooms.1) || rng.random::<f64>() < EXTRA_DOOR_PROBABILITY {
            chosen.push(o);
        }
    }
    // rooms still cut off (only short shared walls): narrower doors on
    // the longest shared wall between components
    loop {
        let mut best: Option<(f64, Opening)> = None;
        for i in 0..rooms.len() {
            for j in i + 1..rooms.len() {
                if sets.equiv(i, j) {
                    continue;
                }
                let (a, b) = (&rooms[i], &rooms[j]);
                if a.stair || b.stair || (a.landing && b.landing) {
                    continue;
                }
                let Some(s) = shared(&a.rect, &b.rect) else {
                    continue;
                };
                let len = s.hi - s.lo - t - 0.04;
                if len >= 0.75 && best.is_none_or(|(l, _)| len > l) {
                    let w = len.min(config.door_width);
                    let lo = 0.5 * (s.lo + s.hi) - 0.5 * w;
                    best = Some((
                        len,
                        Opening {
                            seg: Shared {
                                lo,
                                hi: lo + w,
                                ..s
                            },
                            open: false,
                            rooms: (i, j),
                        },
                    ));
                }
            }
        }
        let Some((_, o)) = best else { break };
        sets.union(o.rooms.0, o.rooms.1);
        chosen.push(o);
    }
    chosen
}

/// [`generate`] with explicit statistics.
///
/// # Errors
/// As [`generate`], plus [`SceneError::Invalid`] for invalid statistics.
pub fn generate_with_stats(
    seed: u64,
    config: &ProceduralConfig,
    stats: &HouseStats,
) -> Result<Scene, SceneError> {
    config.validate()?;
    stats.validate()?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let house = draw_house(&mut rng, stats, config.floors)
        .ok_or_else(|| SceneError::Invalid("statistics without houses".into()))?;
    let floors = config.floors.unwrap_or(floor_class(house.floors)) as usize;
    let t = config.wall_thickness;
    let g = StairGeom::new(config);
    let level_h = g.level_h;
    let stairs = draw_stairs(&mut rng, floors);
    // end of the core where each floor's landing lies (south?)
    let ends: Vec<bool> = (0..floors)
        .map(|f| {
            if f == 0 {
                true
            } else {
                stairs[f - 1].arrives_south()
            }
        })
        .collect();

    // room budget: the stairwell (core on every floor, strip beside it
    // upstairs) counts as one Hall/stairwell room
    let stairwell = floors > 1;
    let structural = usize::from(stairwell);
    let min_sampled = if stairwell { floors + 1 } else { 1 };
    let cap = config.max_rooms_per_floor as usize * floors;
    let n_sampled = (house.rooms as usize)
        .saturating_sub(structural)
        .max(min_sampled)
        .min(cap.max(min_sampled));
    let types = sample_room_types(&mut rng, stats, n_sampled, stairwell);
    let counts = rooms_per_floor(n_sampled, floors);

    // footprint: navigable area times FOOTPRINT_PER_NAVIGABLE shared by the
    // floors, at least MIN_ROOM_AREA per room plus the stairwell core
    // half the stairwell's void is added to each floor (calibrated: the
    // walkable area follows HM3D's and few rooms are lost, see the
    // `procedural_stats` test)
    let (core_area, hole_area) = if stairwell {
        (g.cw * g.sd, 0.5 * g.cw * (g.sd - g.end))
    } else {
        (0.0, 0.0)
    };
    let most = counts.iter().copied().max().unwrap_or(1);
    let per_floor = (house.navigable_area * FOOTPRINT_PER_NAVIGABLE / floors as f64 + hole_area)
        .max(most as f64 * MIN_ROOM_AREA + core_area)
        .clamp(30.0, 500.0);
    let aspect = rng.random_range(1.0..1.6);
    let mut w = (per_floor * aspect).sqrt();
    let mut d = per_floor / w;
    if rng.random::<bool>() {
        std::mem::swap(&mut w, &mut d);
    }
    // a given footprint replaces the drawn one (the draws above still
    // happen, so that the rest of the house follows the same seed)
    if let Some([fw, fd]) = config.footprint {
        (w, d) = (fw, fd);
    }
    let (w, d) = (
        w.max(if stairwell {
            g.cw + 2.0 * config.min_room_side
        } else {
            6.0
        }),
        d.max(if stairwell { g.sd + 2.6 } else { 6.0 }),
    );

    // types per floor: ground-floor types first (bedrooms end up on the
    // upper floors); within a floor the sampling order (anchors first) is
    // kept, so that a layout with fewer leaves than types drops extra rooms
    // first
    let mut order: Vec<usize> = (0..types.len()).collect();
    order.sort_by_key(|&i| (ground_rank(types[i]), i));
    let mut idx_floor: Vec<Vec<usize>> = vec![Vec::new(); floors];
    let mut k = 0;
    for (f, &c) in counts.iter().enumerate() {
        idx_floor[f].extend_from_slice(&order[k..k + c]);
        k += c;
    }
    let by_floor: Vec<Vec<RoomType>> = idx_floor
        .into_iter()
        .map(|mut idx| {
            idx.sort_unstable();
            idx.into_iter().map(|i| types[i]).collect()
        })
        .collect();

    let core = Rect {
        x0: 0.0,
        y0: 0.0,
        x1: g.cw,
        y1: g.sd,
    };
    let plan: Vec<Vec<FloorRoom>> = by_floor
        .into_iter()
        .enumerate()
        .map(|(f, floor_types)| {
            let outline = FloorOutline {
                floor: f,
                stairwell,
                core,
                width: w,
                depth: d,
            };
            floor_rooms(&mut rng, &outline, &floor_types, &g, config)
        })
        .collect();

    // doors
    let openings: Vec<Vec<Opening>> = plan
        .iter()
        .enumerate()
        .map(|(f, rooms)| floor_openings(&mut rng, rooms, ends[f], &g, config))
        .collect();

    // geometry
    let mut b = MeshBuilder::new();
    let mut levels = Vec::new();
    let mut rooms_out = Vec::new();
    for (f, rooms) in plan.iter().enumerate() {
        let top = f + 1 == floors;
        let (level, floor_rooms_out) =
            floor_geometry(&mut b, f, rooms, &openings[f], (top, ends[f]), &g, config);
        levels.push(level);
        rooms_out.extend(floor_rooms_out);
    }
    for (f, m) in stairs.iter().enumerate() {
        let name = if f == 0 {
            "Staircase".to_string()
        } else {
            format!("Staircase {f}")
        };
        let st = b.add_instance(InstanceKind::Stairs, "stairs", &name, f);
        g.build(&mut b, st, m, f as f64 * level_h, t, config.floor_thickness);
    }
    // furniture: object lists drawn per room from its own type's statistics
    // (the stairwell and its landing stay empty); with shuffled semantics the
    // lists are then dealt to the rooms in random order, which keeps the
    // house's objects and breaks the room-object association
    let mut furnished: Vec<(usize, usize, Rect)> = Vec::new();
    let mut lists: Vec<Vec<Drawn>> = Vec::new();
    for (f, rooms) in plan.iter().enumerate() {
        for (ri, r) in rooms.iter().enumerate() {
            if r.stair || r.landing {
                continue;
            }
            furnished.push((f, ri, r.rect));
            lists.push(
                stats
                    .room_type(r.room_type)
                    .map(|rs| draw_objects(&mut rng, rs))
                    .unwrap_or_default(),
            );
        }
    }
    if config.shuffled_semantics {
        shuffle(&mut rng, &mut lists);
    }
    for ((f, ri, rect), list) in furnished.into_iter().zip(lists) {
        let room = PlacedRoom {
            floor: f,
            index: ri,
            rect,
            z: f as f64 * level_h,
        };
        furnish_room(&mut rng, &mut b, &room, &list, &openings[f], t);
    }
    let desc = b.finish(&format!("procedural-{seed}"), levels, rooms_out);
    Scene::from_description(desc)
}

/// Room `index` of floor `floor` as placed in the house: its outline and
/// floor height.
#[derive(Debug, Clone, Copy)]
struct PlacedRoom {
    /// Floor index.
    floor: usize,
    /// Index of the room on its floor (as in the floor's openings).
    index: usize,
    /// Outline (wall centre lines).
    rect: Rect,
    /// Floor height, metres.
    z: f64,
}

/// Places one room's drawn objects (`list`): keep-out zones in front of its
/// doors (`openings` of its floor), then every instance in placement order
/// (first instances of every category before second ones; floor pieces
/// before wall-mounted ones, large before small, by decreasing HM3D
/// presence), each at a sampled position that keeps the room open
/// ([`room_stays_open`]) or, mounted, viewable, within the floor-space
/// budget [`MAX_FURNISHED_SHARE`] for extra instances. `t` is the wall
/// thickness.
fn furnish_room(
    rng: &mut ChaCha8Rng,
    b: &mut MeshBuilder,
    placed: &PlacedRoom,
    list: &[Drawn],
    openings: &[Opening],
    t: f64,
) {
    let PlacedRoom {
        floor: f,
        index: ri,
        rect,
        z,
    } = *placed;
    let mut room = RoomFurniture::default();
    for o in openings {
        if o.rooms.0 != ri && o.rooms.1 != ri {
            continue;
        }
        let s = o.seg;
        let depth = DOOR_CLEARANCE;
        room.keep_out.push(if s.axis == 0 {
            Rect {
                x0: s.lo - 0.2,
                x1: s.hi + 0.2,
                y0: s.c - depth,
                y1: s.c + depth,
            }
        } else {
            Rect {
                y0: s.lo - 0.2,
                y1: s.hi + 0.2,
                x0: s.c - depth,
                x1: s.c + depth,
            }
        });
    }
    let inner = rect.inflate(-(t * 0.5 + 0.01));
    // points just inside each doorway of this room
    let door_points: Vec<Point2<f64>> = openings
        .iter()
        .filter(|o| o.rooms.0 == ri || o.rooms.1 == ri)
        .map(|o| {
            let (s, mid) = (o.seg, 0.5 * (o.seg.lo + o.seg.hi));
            if s.axis == 0 {
                let dy = if (rect.y0 - s.c).abs() < 1e-6 {
                    0.4
                } else {
                    -0.4
                };
                Point2::new(mid, s.c + dy)
            } else {
                let dx = if (rect.x0 - s.c).abs() < 1e-6 {
                    0.4
                } else {
                    -0.4
                };
                Point2::new(s.c + dx, mid)
            }
        })
        .collect();
    let mut used_area = 0.0;
    // placement order: first instances of every category before second
    // ones; within a round floor pieces before wall-mounted ones, large
    // pieces (over 0.8 m^2) before small ones, each by decreasing HM3D
    // presence. A later floor piece may not cut a mounted one off the
    // free floor (`room_stays_open`) nor stand tall in front of it.
    let mut items: Vec<(Drawn, u32)> = list
        .iter()
        .flat_map(|&d| (0..d.count).map(move |k| (d, k)))
        .collect();
    items.sort_by(|(a, ka), (b, kb)| {
        let mounted_a = a.shape.placement == Placement::Mounted;
        let mounted_b = b.shape.placement == Placement::Mounted;
        let area = |d: &Drawn| d.shape.width.1 * d.shape.depth.1;
        ka.cmp(kb)
            .then(mounted_a.cmp(&mounted_b))
            .then((area(b) > 0.8).cmp(&(area(a) > 0.8)))
            .then(b.presence.total_cmp(&a.presence))
            .then(area(b).total_cmp(&area(a)))
    });
    for (drawn, k) in items {
        let sh = drawn.shape;
        let size = (
            rng.random_range(sh.width.0..=sh.width.1),
            rng.random_range(sh.depth.0..=sh.depth.1),
            rng.random_range(sh.height.0..=sh.height.1),
        );
        let mounted = sh.placement == Placement::Mounted;
        // the floor-space budget limits extra instances only, so that
        // presence follows the statistics even in small rooms
        if !mounted && k > 0 && used_area + size.0 * size.1 > MAX_FURNISHED_SHARE * rect.area() {
            continue;
        }
        // `room.placed` does not change while this piece is placed
        let viewable = mounted.then(|| viewable(&inner, &room.placed, &door_points));
        let accept = |c: &Candidate| {
            if let Some(viewable) = &viewable {
                viewable(&c.foot)
            } else {
                let mut trial = room.placed.clone();
                trial.push(c.foot);
                room_stays_open(&inner, &trial, &door_points, &room.mounted)
            }
        };
        let Some(Candidate {
            centre: at,
            yaw,
            foot,
            clear,
            ..
        }) = place(
            rng,
            sh.category,
            sh.placement,
            (size.0, size.1),
            size.2 > MOUNT_HEIGHT - 0.1,
            &inner,
            &room,
            accept,
        )
        else {
            continue;
        };
        let inst = b.add_instance(
            InstanceKind::Object,
            sh.category,
            &format!("{} {}", sh.category, k + 1),
            f,
        );
        let at = Point3::new(at.x, at.y, z + if mounted { MOUNT_HEIGHT } else { 0.0 });
        furniture::build(b, inst, sh.category, size, at, yaw);
        if mounted {
            room.mounted.push(foot);
            room.mounted_clears.push(clear);
        } else {
            used_area += size.0 * size.1;
            room.placed.push(foot);
            room.tall.push(size.2 > MOUNT_HEIGHT - 0.1);
            room.clears.push(clear);
            room.categories.push(sh.category);
            room.against_wall.push(sh.placement == Placement::Wall);
        }
    }
}

/// Cell size (m) of the free-floor grid of a room ([`free_components`]).
const CELL: f64 = 0.1;

/// Centre of cell `k` of a room's free-floor grid `nx` cells wide.
fn cell_centre(inner: &Rect, nx: usize, k: usize) -> Point2<f64> {
    Point2::new(
        inner.x0 + ((k % nx) as f64 + 0.5) * CELL,
        inner.y0 + ((k / nx) as f64 + 0.5) * CELL,
    )
}

/// Free cells ([`CELL`]) of a room where an agent fits between the placed
/// footprints, labelled by connected component (`u32::MAX` = blocked).
fn free_components(inner: &Rect, placed: &[Rect]) -> (Vec<u32>, usize, usize) {
    const CLEAR: f64 = 0.3;
    // walls: the navmesh erodes by the agent radius (0.18 m) plus up to one
    // 0.05 m cell of rasterisation, so a cell must keep 0.25 m to the wall
    const WALL_CLEAR: f64 = 0.25;
    let nx = (inner.w() / CELL).floor().max(1.0) as usize;
    let ny = (inner.d() / CELL).floor().max(1.0) as usize;
    let mut label = vec![u32::MAX; nx * ny];
    let free: Vec<bool> = (0..nx * ny)
        .map(|k| {
            let c = cell_centre(inner, nx, k);
            c.x - inner.x0 >= WALL_CLEAR
                && inner.x1 - c.x >= WALL_CLEAR
                && c.y - inner.y0 >= WALL_CLEAR
                && inner.y1 - c.y >= WALL_CLEAR
                && !placed.iter().any(|p| {
                    let q = p.inflate(CLEAR);
                    c.x > q.x0 && c.x < q.x1 && c.y > q.y0 && c.y < q.y1
                })
        })
        .collect();
    let mut n = 0u32;
    for k in 0..nx * ny {
        if !free[k] || label[k] != u32::MAX {
            continue;
        }
        let mut stack = vec![k];
        label[k] = n;
        while let Some(c) = stack.pop() {
            let (i, j) = (c % nx, c / nx);
            let mut push = |m: usize| {
                if free[m] && label[m] == u32::MAX {
                    label[m] = n;
                    stack.push(m);
                }
            };
            if i > 0 {
                push(c - 1);
            }
            if i + 1 < nx {
                push(c + 1);
            }
            if j > 0 {
                push(c - nx);
            }
            if j + 1 < ny {
                push(c + nx);
            }
        }
        n += 1;
    }
    (label, nx, ny)
}

fn cell_of(inner: &Rect, nx: usize, ny: usize, p: &Point2<f64>) -> usize {
    let i = (((p.x - inner.x0) / CELL).floor().max(0.0) as usize).min(nx - 1);
    let j = (((p.y - inner.y0) / CELL).floor().max(0.0) as usize).min(ny - 1);
    j * nx + i
}

/// True when every doorway of the room is free and all doorways (and, for a
/// room without doors, some free cell) lie in one free component.
fn room_stays_open(inner: &Rect, placed: &[Rect], doors: &[Point2<f64>], mounted: &[Rect]) -> bool {
    let (label, nx, ny) = free_components(inner, placed);
    let mut comp = None;
    for d in doors {
        let l = label[cell_of(inner, nx, ny, d)];
        if l == u32::MAX || comp.is_some_and(|c| c != l) {
            return false;
        }
        comp = Some(l);
    }
    // every piece, floor-standing or wall-mounted, keeps a free cell of that
    // component within 0.8 m
    placed
        .iter()
        .chain(mounted)
        .all(|p| near_component(inner, &label, nx, ny, comp, p))
}

/// True when a free cell of component `comp` (any component when `None`)
/// lies within 0.8 m (Euclidean) of the footprint: an agent standing there
/// is within the 1 m view point radius even after the height field's
/// rasterisation.
fn near_component(
    inner: &Rect,
    label: &[u32],
    nx: usize,
    ny: usize,
    comp: Option<u32>,
    foot: &Rect,
) -> bool {
    const REACH: f64 = 0.8;
    (0..nx * ny).any(|k| {
        let c = cell_centre(inner, nx, k);
        let l = label[k];
        let dx = (foot.x0 - c.x).max(c.x - foot.x1).max(0.0);
        let dy = (foot.y0 - c.y).max(c.y - foot.y1).max(0.0);
        l != u32::MAX && comp.is_none_or(|cc| cc == l) && dx.hypot(dy) <= REACH
    }) || ny == 0
}

/// Test whether a wall-mounted piece with footprint `foot` can be seen from
/// the doorways' free component, with the free floor of `placed` computed
/// once.
fn viewable(
    inner: &Rect,
    placed: &[Rect],
    doors: &[Point2<f64>],
) -> impl Fn(&Rect) -> bool + use<> {
    let (label, nx, ny) = free_components(inner, placed);
    let comp = doors.first().map(|d| label[cell_of(inner, nx, ny, d)]);
    let inner = *inner;
    move |foot| near_component(&inner, &label, nx, ny, comp, foot)
}

/// Furniture placed in one room so far.
#[derive(Default)]
struct RoomFurniture {
    /// Footprints of floor-standing pieces.
    placed: Vec<Rect>,
    /// Whether each floor-standing piece reaches above a wall-mounted one (1.1 m).
    tall: Vec<bool>,
    /// Floor kept clear in front of (or around) each floor-standing piece.
    clears: Vec<Rect>,
    /// Footprints of wall-mounted pieces.
    mounted: Vec<Rect>,
    /// Floor in front of each wall-mounted piece, kept free of tall pieces.
    mounted_clears: Vec<Rect>,
    /// Floor kept clear at the doorways.
    keep_out: Vec<Rect>,
    /// Category of each floor-standing piece.
    categories: Vec<&'static str>,
    /// Whether each floor-standing piece stands against a wall.
    against_wall: Vec<bool>,
}

/// A candidate pose of a piece.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    centre: Point2<f64>,
    yaw: f64,
    foot: Rect,
    /// Floor the piece keeps clear.
    clear: Rect,
    /// The placed piece (a table) this one is drawn up to: its clearance
    /// zone does not block this piece.
    beside: Option<usize>,
}

impl Candidate {
    fn new(centre: Point2<f64>, yaw: f64, foot: Rect, clear: Rect) -> Candidate {
        Candidate {
            centre,
            yaw,
            foot,
            clear,
            beside: None,
        }
    }
}

/// Candidate poses of a piece of size (w, d): free-standing pieces on a 0.1 m
/// grid of centres keeping `margin` to the walls, in both orientations;
/// wall pieces every 0.1 m along each wall, back against it, with a
/// clearance zone of [`WALL_FRONT_CLEARANCE`] in front.
fn candidates(placement: Placement, (w, d): (f64, f64), inner: &Rect) -> Vec<Candidate> {
    const STEP: f64 = 0.1;
    let range = |lo: f64, hi: f64| -> Vec<f64> {
        if lo > hi {
            return Vec::new();
        }
        let n = ((hi - lo) / STEP).floor() as usize;
        let mut v: Vec<f64> = (0..=n).map(|i| lo + i as f64 * STEP).collect();
        if hi - v[v.len() - 1] > 1e-9 {
            v.push(hi);
        }
        v
    };
    let mut out = Vec::new();
    match placement {
        Placement::Free => {
            let margin = free_margin(w, d);
            for quarter in 0..2u32 {
                let (fw, fd) = if quarter == 1 { (d, w) } else { (w, d) };
                let yaw = f64::from(quarter) * std::f64::consts::FRAC_PI_2;
                let xs = range(inner.x0 + fw * 0.5 + margin, inner.x1 - fw * 0.5 - margin);
                let ys = range(inner.y0 + fd * 0.5 + margin, inner.y1 - fd * 0.5 - margin);
                for &x in &xs {
                    for &y in &ys {
                        let foot = Rect::centred(Point2::new(x, y), fw, fd);
                        out.push(Candidate::new(
                            Point2::new(x, y),
                            yaw,
                            foot,
                            foot.inflate(margin),
                        ));
                    }
                }
            }
        }
        Placement::Wall | Placement::Mounted => {
            // side 0: wall at y0 (piece faces +y), 1: x1 (faces -x), 2: y1
            // (faces -y), 3: x0 (faces +x)
            for side in 0..4 {
                let (along_lo, along_hi) = if side % 2 == 0 {
                    (inner.x0, inner.x1)
                } else {
                    (inner.y0, inner.y1)
                };
                for a in range(along_lo + w * 0.5 + 0.05, along_hi - w * 0.5 - 0.05) {
                    let (c, yaw) = match side {
                        0 => (Point2::new(a, inner.y0 + d * 0.5), std::f64::consts::PI),
                        1 => (
                            Point2::new(inner.x1 - d * 0.5, a),
                            -std::f64::consts::FRAC_PI_2,
                        ),
                        2 => (Point2::new(a, inner.y1 - d * 0.5), 0.0),
                        _ => (
                            Point2::new(inner.x0 + d * 0.5, a),
                            std::f64::consts::FRAC_PI_2,
                        ),
                    };
                    let (fw, fd) = if side % 2 == 0 { (w, d) } else { (d, w) };
                    let foot = Rect::centred(c, fw, fd);
                    let front = WALL_FRONT_CLEARANCE;
                    let clear = match side {
                        0 => Rect {
                            y1: foot.y1 + front,
                            ..foot.inflate(0.05)
                        },
                        1 => Rect {
                            x0: foot.x0 - front,
                            ..foot.inflate(0.05)
                        },
                        2 => Rect {
                            y0: foot.y0 - front,
                            ..foot.inflate(0.05)
                        },
                        _ => Rect {
                            x1: foot.x1 + front,
                            ..foot.inflate(0.05)
                        },
                    };
                    out.push(Candidate::new(c, yaw, foot, clear));
                }
            }
        }
    }
    out
}

/// Poses of a seat (chair, stool) of size (w, d) drawn up to a placed table
/// or counter: every 0.1 m along each of its sides, 0.05 m away, facing it,
/// keeping 0.45 m of the room's floor clear behind.
fn seat_candidates((w, d): (f64, f64), inner: &Rect, room: &RoomFurniture) -> Vec<Candidate> {
    let mut out = Vec::new();
    for (i, (t, &cat)) in room.placed.iter().zip(&room.categories).enumerate() {
        if cat != "table" && cat != "counter" {
            continue;
        }
        // side 0: south of the table, facing +y; 1: east, facing -x;
        // 2: north, facing -y; 3: west, facing +x
        for side in 0..4 {
            let (lo, hi) = if side % 2 == 0 {
                (t.x0, t.x1)
            } else {
                (t.y0, t.y1)
            };
            let mut a = lo + w * 0.5;
            while a <= hi - w * 0.5 + 1e-9 {
                let (c, yaw) = match side {
                    0 => (Point2::new(a, t.y0 - 0.05 - d * 0.5), std::f64::consts::PI),
                    1 => (
                        Point2::new(t.x1 + 0.05 + d * 0.5, a),
                        -std::f64::consts::FRAC_PI_2,
                    ),
                    2 => (Point2::new(a, t.y1 + 0.05 + d * 0.5), 0.0),
                    _ => (
                        Point2::new(t.x0 - 0.05 - d * 0.5, a),
                        std::f64::consts::FRAC_PI_2,
                    ),
                };
                a += 0.1;
                let (fw, fd) = if side % 2 == 0 { (w, d) } else { (d, w) };
                let foot = Rect::centred(c, fw, fd);
                if foot.sticks_out_of(inner) {
                    continue;
                }
                let back = 0.45;
                let clear = match side {
                    0 => Rect {
                        y0: foot.y0 - back,
                        ..foot.inflate(0.03)
                    },
                    1 => Rect {
                        x1: foot.x1 + back,
                        ..foot.inflate(0.03)
                    },
                    2 => Rect {
                        y1: foot.y1 + back,
                        ..foot.inflate(0.03)
                    },
                    _ => Rect {
                        x0: foot.x0 - back,
                        ..foot.inflate(0.03)
                    },
                };
                // the floor behind the seat lies inside the room
                if clear.sticks_out_of(inner) {
                    continue;
                }
                out.push(Candidate {
                    beside: Some(i),
                    ..Candidate::new(c, yaw, foot, clear)
                });
            }
        }
    }
    out
}

/// Share of a wall piece's clearance zone that another wall piece may cover.
const CLEARANCE_SHARE: f64 = 0.4;

/// Area of the intersection of two rectangles.
fn overlap_area(a: &Rect, b: &Rect) -> f64 {
    (a.x1.min(b.x1) - a.x0.max(b.x0)).max(0.0) * (a.y1.min(b.y1) - a.y0.max(b.y0)).max(0.0)
}

/// Floor a free-standing piece keeps around it (small pieces less).
fn free_margin(w: f64, d: f64) -> f64 {
    if w * d < 0.35 { 0.45 } else { 0.65 }
}

/// Whether a candidate pose collides with what the room holds: wall pieces
/// may stand side by side, but nothing stands in another piece's clearance
/// zone, and wall-mounted pieces hang only above (and in front of) pieces
/// lower than 1.1 m (`tall`: the candidate is a floor piece reaching higher).
fn blocked(placement: Placement, tall: bool, cand: &Candidate, room: &RoomFurniture) -> bool {
    let (foot, clear) = (&cand.foot, &cand.clear);
    if placement == Placement::Mounted {
        room.mounted.iter().any(|m| m.inflate(0.1).overlaps(foot))
            || room
                .placed
                .iter()
                .zip(&room.tall)
                .any(|(p, &tall)| tall && (p.overlaps(clear) || p.inflate(0.05).overlaps(foot)))
    } else {
        // two wall pieces may share part of their clearance zones (pieces
        // meeting at a corner); otherwise clearance zones stay free
        let wall = placement == Placement::Wall;
        let cuts = |zone: &Rect, r: &Rect, shareable: bool| {
            if shareable {
                overlap_area(zone, r) > CLEARANCE_SHARE * zone.area()
            } else {
                zone.overlaps(r)
            }
        };
        room.placed
            .iter()
            .zip(&room.against_wall)
            .any(|(p, &pw)| cuts(clear, p, wall && pw) || p.inflate(0.02).overlaps(foot))
            || room
                .clears
                .iter()
                .zip(&room.against_wall)
                .enumerate()
                .any(|(i, (c, &pw))| cand.beside != Some(i) && cuts(c, foot, wall && pw))
            || room.keep_out.iter().any(|k| k.overlaps(foot))
            || (tall
                && room
                    .mounted
                    .iter()
                    .zip(&room.mounted_clears)
                    .any(|(m, c)| m.inflate(0.05).overlaps(foot) || c.overlaps(foot)))
    }
}

/// Finds a pose for a piece: seats first try the places at tables
/// ([`seat_candidates`]), then every piece its candidate poses
/// ([`candidates`]), each group in random order; the first pose that is not
/// [`blocked`] and passes `accept` wins. At most 16 unblocked poses per group
/// are offered to `accept` (it runs a flood fill).
#[allow(clippy::too_many_arguments)]
fn place(
    rng: &mut ChaCha8Rng,
    category: &str,
    placement: Placement,
    size: (f64, f64),
    tall: bool,
    inner: &Rect,
    room: &RoomFurniture,
    mut accept: impl FnMut(&Candidate) -> bool,
) -> Option<Candidate> {
    let mut groups = Vec::new();
    if matches!(category, "chair" | "stool") {
        groups.push(seat_candidates(size, inner, room));
    }
    groups.push(candidates(placement, size, inner));
    for mut cands in groups {
        let n = cands.len();
        let mut tried = 0;
        for i in 0..n {
            let j = rng.random_range(i..n);
            cands.swap(i, j);
            let c = &cands[i];
            if blocked(placement, tall, c, room) {
                continue;
            }
            tried += 1;
            if accept(c) {
                return Some(*c);
            }
            if tried >= 16 {
                break;
            }
        }
    }
    None
}

/// Extrudes the walls of one floor: every room edge, deduplicated per line,
/// minus openings, with lintels above doors.
fn build_walls(
    b: &mut MeshBuilder,
    rooms: &[FloorRoom],
    openings: &[Opening],
    level: usize,
    z: f64,
    cfg: &ProceduralConfig,
) {
    use std::collections::BTreeMap;
    let t = cfg.wall_thickness;
    // (axis, coordinate in mm) -> intervals
    let mut lines: BTreeMap<(usize, i64), Vec<(f64, f64)>> = BTreeMap::new();
    for r in rooms {
        let q = r.rect;
        for (axis, c, lo, hi) in [
            (0, q.y0, q.x0, q.x1),
            (0, q.y1, q.x0, q.x1),
            (1, q.x0, q.y0, q.y1),
            (1, q.x1, q.y0, q.y1),
        ] {
            lines
                .entry((axis, (c * 1000.0).round() as i64))
                .or_default()
                .push((lo, hi));
        }
    }
    for ((axis, cm), mut iv) in lines {
        let c = cm as f64 / 1000.0;
        iv.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut merged: Vec<(f64, f64)> = Vec::new();
        for (lo, hi) in iv {
            match merged.last_mut() {
                Some(l) if lo <= l.1 + 1e-6 => l.1 = l.1.max(hi),
                _ => merged.push((lo, hi)),
            }
        }
        let holes: Vec<&Opening> = openings
            .iter()
            .filter(|o| o.seg.axis == axis && (o.seg.c - c).abs() < 1e-3)
            .collect();
        for (lo, hi) in merged {
            let mut pieces = vec![(lo - t * 0.5, hi + t * 0.5)];
            for h in &holes {
                let (hlo, hhi) = if h.open {
                    (h.seg.lo + t * 0.5, h.seg.hi - t * 0.5)
                } else {
                    (h.seg.lo, h.seg.hi)
                };
                pieces = pieces
                    .into_iter()
                    .flat_map(|(a, bb)| {
                        if hhi <= a || hlo >= bb {
                            vec![(a, bb)]
                        } else {
                            [(a, hlo), (hhi, bb)]
                                .into_iter()
                                .filter(|p| p.1 - p.0 > 1e-4)
                                .collect()
                        }
                    })
                    .collect();
            }
            // min and max corners of the wall box over [a, e] x [z0, z1]
            let corners = |a: f64, e: f64, z0: f64, z1: f64| {
                if axis == 0 {
                    (
                        Point3::new(a, c - t * 0.5, z0),
                        Point3::new(e, c + t * 0.5, z1),
                    )
                } else {
                    (
                        Point3::new(c - t * 0.5, a, z0),
                        Point3::new(c + t * 0.5, e, z1),
                    )
                }
            };
            let seg_box = |b: &mut MeshBuilder, a: f64, e: f64, z0: f64, z1: f64, inst| {
                let (min, max) = corners(a, e, z0, z1);
                b.aabb_box(min, max, inst);
            };
            for (a, e) in pieces {
                let wi = b.add_instance(InstanceKind::Wall, "wall", "wall", level);
                seg_box(b, a, e, z, z + cfg.wall_height, wi);
            }
            for h in &holes {
                if h.open || h.seg.hi <= lo || h.seg.lo >= hi {
                    continue;
                }
                let di = b.add_instance(InstanceKind::Door, "door", "door", level);
                seg_box(
                    b,
                    h.seg.lo,
                    h.seg.hi,
                    z + cfg.door_height,
                    z + cfg.wall_height,
                    di,
                );
                let (p0, p1) = corners(h.seg.lo, h.seg.hi, z, z + cfg.door_height);
                b.include_in_bounds(di, p0);
                b.include_in_bounds(di, p1);
            }
        }
    }
}

impl Scene {
    /// A procedural house (see [`crate::procedural`]); same seed, same house.
    ///
    /// # Errors
    /// [`SceneError::Config`] for an invalid configuration.
    pub fn procedural(seed: u64, config: &ProceduralConfig) -> Result<Scene, SceneError> {
        generate(seed, config)
    }
}

//! Procedural houses: the embedded default scene source, no data files needed.
//!
//! [`generate`] builds a seeded multi-room house with one or two floors:
//!
//! 1. **Size** — a house size (floors, rooms, navigable area) is drawn from the
//!    HM3D validation scenes ([`HouseStats`]); the footprint area per floor is
//!    the navigable area per floor scaled by 1.6 (furniture and walls take the
//!    rest), clamped to 40-150 m^2.
//! 2. **Layout** — two-floor houses reserve a stair block at one corner and a
//!    landing strip beside it; the rest of each floor is split by binary space
//!    partition into rooms no narrower than `min_room_side`.
//! 3. **Room types** — essentials (living room, kitchen, bedroom, bathroom)
//!    first, then types drawn in proportion to their HM3D frequency; larger
//!    types take larger rooms.
//! 4. **Doors** — a random spanning tree of the room adjacency graph (plus
//!    extra doors with probability 0.3) gets door openings, so every room is
//!    reachable; walls are extruded with thickness and lintels over doors.
//! 5. **Furniture** — for each room, each category is present with its HM3D
//!    probability for that room type and count; pieces are composite boxes
//!    ([`furniture`]) placed against walls or in the free area, keeping door
//!    zones and a walking margin clear. A piece is kept only if, on a 0.1 m
//!    grid inflated by 0.3 m, all doorways of the room stay in one free
//!    component and every piece keeps a free cell of it within 0.9 m (so every
//!    room is reachable and every object has a view point). With
//!    `shuffled_semantics` the object list of each room comes from a random
//!    room type instead.
//!
//! Same seed and configuration, same house.

pub mod furniture;
pub mod stats;

use nalgebra::{Point2, Point3};
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
    /// Number of floors (1 or 2); `None` draws it from the HM3D statistics.
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
    /// Most rooms per floor (the stair block and landing not counted).
    pub max_rooms_per_floor: u32,
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
            max_rooms_per_floor: 7,
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
        if self.floors.is_some_and(|f| !(1..=2).contains(&f)) {
            return bad("floors", "must be 1 or 2");
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
        if !(1..=20).contains(&self.max_rooms_per_floor) {
            return bad("max_rooms_per_floor", "must be in [1, 20]");
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

fn size_rank(t: RoomType) -> u32 {
    match t {
        RoomType::LivingRoom => 0,
        RoomType::Garage => 1,
        RoomType::Bedroom => 2,
        RoomType::Kitchen => 3,
        RoomType::DiningRoom => 4,
        RoomType::Office => 5,
        RoomType::Other | RoomType::Storage | RoomType::Outdoor => 6,
        RoomType::Laundry => 7,
        RoomType::Hallway | RoomType::Stairs => 8,
        RoomType::Bathroom => 9,
        RoomType::Toilet | RoomType::Closet => 10,
    }
}

fn split_bsp(rng: &mut ChaCha8Rng, area: Rect, n: usize, min_side: f64) -> Vec<Rect> {
    let mut rects = vec![area];
    while rects.len() < n {
        // largest splittable rectangle
        let mut order: Vec<usize> = (0..rects.len()).collect();
        order.sort_by(|&a, &b| rects[b].area().total_cmp(&rects[a].area()));
        let Some(&i) = order
            .iter()
            .find(|&&i| rects[i].w().max(rects[i].d()) >= 2.0 * min_side)
        else {
            break;
        };
        let r = rects[i];
        let along_x = r.w() >= r.d();
        let len = if along_x { r.w() } else { r.d() };
        let lo = min_side / len;
        let t = rng.random_range(lo.clamp(0.35, 0.5)..=(1.0 - lo).clamp(0.5, 0.65));
        let (a, b) = if along_x {
            let x = r.x0 + t * r.w();
            (Rect { x1: x, ..r }, Rect { x0: x, ..r })
        } else {
            let y = r.y0 + t * r.d();
            (Rect { y1: y, ..r }, Rect { y0: y, ..r })
        };
        rects[i] = a;
        rects.push(b);
    }
    rects
}

fn find(p: &mut [usize], mut i: usize) -> usize {
    while p[i] != i {
        p[i] = p[p[i]];
        i = p[i];
    }
    i
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

/// Generates a procedural house as a [`Scene`] (see the module docs).
///
/// # Errors
/// [`SceneError::Config`] for an invalid configuration; [`SceneError::Invalid`]
/// if the embedded statistics are unusable.
///
/// # Complexity
/// O(R^2 + F) for R rooms and F furniture pieces (placement by rejection
/// sampling with a bounded number of attempts).
pub fn generate(seed: u64, config: &ProceduralConfig) -> Result<Scene, SceneError> {
    generate_with_stats(seed, config, HouseStats::embedded()?)
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
    let house = &stats.houses[rng.random_range(0..stats.houses.len())];
    let floors = config.floors.unwrap_or(house.floors.clamp(1, 2)) as usize;
    let t = config.wall_thickness;
    let level_h = config.wall_height + config.floor_thickness;
    // stairs geometry (two floors)
    let n_steps = (level_h / 0.18).ceil() as usize;
    let rise = level_h / n_steps as f64;
    let run = 0.26;
    let landing_len = 1.5;
    let sw = 1.3;
    let sd = landing_len + run * n_steps as f64;

    let per_floor = (house.navigable_area / floors as f64 * 1.6).clamp(40.0, 150.0);
    let aspect = rng.random_range(1.0..1.6);
    let mut w = (per_floor * aspect).sqrt();
    let mut d = per_floor / w;
    if rng.random::<bool>() {
        std::mem::swap(&mut w, &mut d);
    }
    let (w, d) = (w.max(6.0), d.max(if floors == 2 { sd + 2.6 } else { 6.0 }));

    let rooms_total = house.rooms.max(3) as usize;
    let mut plan: Vec<Vec<FloorRoom>> = Vec::new();
    for f in 0..floors {
        let mut rooms = Vec::new();
        let main = if floors == 2 {
            rooms.push(FloorRoom {
                rect: Rect {
                    x0: 0.0,
                    y0: 0.0,
                    x1: sw,
                    y1: sd,
                },
                room_type: RoomType::Stairs,
                stair: true,
                landing: false,
            });
            rooms.push(FloorRoom {
                rect: Rect {
                    x0: 0.0,
                    y0: sd,
                    x1: sw,
                    y1: d,
                },
                room_type: RoomType::Hallway,
                stair: false,
                landing: true,
            });
            Rect {
                x0: sw,
                y0: 0.0,
                x1: w,
                y1: d,
            }
        } else {
            Rect {
                x0: 0.0,
                y0: 0.0,
                x1: w,
                y1: d,
            }
        };
        let by_area = (main.area() / 12.0).floor() as usize;
        let n = (rooms_total / floors)
            .clamp(3, config.max_rooms_per_floor as usize)
            .min(by_area.max(2));
        let mut leaves = split_bsp(&mut rng, main, n, config.min_room_side);
        // room types: essentials then sampled
        let mut types: Vec<RoomType> = match (floors, f) {
            (1, _) => vec![
                RoomType::LivingRoom,
                RoomType::Kitchen,
                RoomType::Bedroom,
                RoomType::Bathroom,
            ],
            (_, 0) => vec![RoomType::LivingRoom, RoomType::Kitchen, RoomType::Bathroom],
            _ => vec![RoomType::Bedroom, RoomType::Bathroom, RoomType::Bedroom],
        };
        let weights: Vec<(RoomType, f64)> = stats
            .room_types
            .iter()
            .filter(|r| {
                !matches!(
                    r.room_type,
                    RoomType::Hallway | RoomType::Stairs | RoomType::Other
                )
            })
            .map(|r| (r.room_type, r.mean_per_scene))
            .collect();
        while types.len() < leaves.len() {
            types.push(weighted_pick(&mut rng, &weights).unwrap_or(RoomType::Bedroom));
        }
        types.truncate(leaves.len());
        types.sort_by_key(|&t| size_rank(t));
        leaves.sort_by(|a, b| b.area().total_cmp(&a.area()));
        for (rect, room_type) in leaves.into_iter().zip(types) {
            rooms.push(FloorRoom {
                rect,
                room_type,
                stair: false,
                landing: false,
            });
        }
        plan.push(rooms);
    }

    // doors
    let mut openings: Vec<Vec<Opening>> = Vec::new();
    for (f, rooms) in plan.iter().enumerate() {
        let mut cands: Vec<Opening> = Vec::new();
        let mut forced: Vec<Opening> = Vec::new();
        for i in 0..rooms.len() {
            for j in i + 1..rooms.len() {
                let Some(mut s) = shared(&rooms[i].rect, &rooms[j].rect) else {
                    continue;
                };
                let (a, b) = (&rooms[i], &rooms[j]);
                if (a.stair && b.landing) || (a.landing && b.stair) {
                    if f == 1 {
                        forced.push(Opening {
                            seg: s,
                            open: true,
                            rooms: (i, j),
                        });
                    }
                    continue;
                }
                if a.stair || b.stair {
                    if f == 1 {
                        continue; // railing around the stairwell
                    }
                    // ground floor: only from the landing at the foot of the stairs
                    s.hi = s.hi.min(landing_len);
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
        let mut parent: Vec<usize> = (0..rooms.len()).collect();
        let mut chosen = forced.clone();
        for o in &forced {
            let (a, b) = (find(&mut parent, o.rooms.0), find(&mut parent, o.rooms.1));
            parent[a] = b;
        }
        let mut order: Vec<usize> = (0..cands.len()).collect();
        for i in (1..order.len()).rev() {
            order.swap(i, rng.random_range(0..=i));
        }
        for &k in &order {
            let o = cands[k];
            let (a, b) = (find(&mut parent, o.rooms.0), find(&mut parent, o.rooms.1));
            if a != b {
                parent[a] = b;
                chosen.push(o);
            } else if rng.random::<f64>() < 0.3 {
                chosen.push(o);
            }
        }
        // rooms still cut off (only short shared walls): narrower doors on
        // the longest shared wall between components
        loop {
            let mut best: Option<(f64, Opening)> = None;
            for i in 0..rooms.len() {
                for j in i + 1..rooms.len() {
                    if find(&mut parent, i) == find(&mut parent, j) {
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
            let (a, b) = (find(&mut parent, o.rooms.0), find(&mut parent, o.rooms.1));
            parent[a] = b;
            chosen.push(o);
        }
        openings.push(chosen);
    }

    // geometry
    let mut b = MeshBuilder::new();
    let mut levels = Vec::new();
    let mut rooms_out = Vec::new();
    for (f, rooms) in plan.iter().enumerate() {
        let z = f as f64 * level_h;
        levels.push(Level {
            name: if f == 0 {
                "Ground floor".into()
            } else {
                format!("Floor {f}")
            },
            elevation: z,
            height: config.wall_height,
            floor_thickness: config.floor_thickness,
        });
        let top = f + 1 == floors;
        for (ri, r) in rooms.iter().enumerate() {
            let name = format!("{} {}", r.room_type.label(), ri);
            rooms_out.push(Room {
                name: name.clone(),
                room_type: r.room_type,
                level: f,
                polygon: r.rect.polygon(),
                floor_z: z,
            });
            if !(r.stair && f > 0) {
                let fl = b.add_instance(InstanceKind::Floor, "floor", &name, f);
                b.aabb_box(
                    Point3::new(r.rect.x0, r.rect.y0, z - config.floor_thickness),
                    Point3::new(r.rect.x1, r.rect.y1, z),
                    fl,
                );
            }
            if top {
                let c = b.add_instance(InstanceKind::Ceiling, "ceiling", &name, f);
                b.horizontal_polygon(&r.rect.polygon(), z + config.wall_height, false, c);
            }
        }
        build_walls(&mut b, rooms, &openings[f], f, z, config);
    }
    if floors == 2 {
        let st = b.add_instance(InstanceKind::Stairs, "stairs", "Staircase", 0);
        let y0 = sd - run * n_steps as f64;
        for i in 0..n_steps {
            let ya = y0 + run * i as f64;
            let yb = if i + 1 == n_steps { sd } else { ya + run };
            b.aabb_box(
                Point3::new(t * 0.5, ya, 0.0),
                Point3::new(sw - t * 0.5, yb, rise * (i + 1) as f64),
                st,
            );
        }
    }

    // furniture
    let mut level_of_room = Vec::new();
    for (f, rooms) in plan.iter().enumerate() {
        for (ri, r) in rooms.iter().enumerate() {
            level_of_room.push((f, ri, r.rect, r.room_type, r.stair));
        }
    }
    let types_with_stats: Vec<RoomType> = stats.room_types.iter().map(|r| r.room_type).collect();
    for (f, ri, rect, room_type, stair) in level_of_room {
        if stair {
            continue;
        }
        let z = f as f64 * level_h;
        let source_type = if config.shuffled_semantics {
            types_with_stats[rng.random_range(0..types_with_stats.len())]
        } else {
            room_type
        };
        let Some(rs) = stats.room_type(source_type) else {
            continue;
        };
        let mut keep_out: Vec<Rect> = Vec::new();
        for o in &openings[f] {
            if o.rooms.0 != ri && o.rooms.1 != ri {
                continue;
            }
            let s = o.seg;
            let depth = 1.1;
            keep_out.push(if s.axis == 0 {
                Rect {
                    x0: s.lo - 0.3,
                    x1: s.hi + 0.3,
                    y0: s.c - depth,
                    y1: s.c + depth,
                }
            } else {
                Rect {
                    y0: s.lo - 0.3,
                    y1: s.hi + 0.3,
                    x0: s.c - depth,
                    x1: s.c + depth,
                }
            });
        }
        let inner = rect.inflate(-(t * 0.5 + 0.01));
        // points just inside each doorway of this room
        let door_points: Vec<Point2<f64>> = openings[f]
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
        let mut placed: Vec<Rect> = Vec::new();
        let mut mounted: Vec<Rect> = Vec::new();
        let mut used_area = 0.0;
        // floor pieces first, then wall-mounted ones, which must stay reachable
        let mut order: Vec<&CategoryStats> = rs.objects.iter().collect();
        order
            .sort_by_key(|c| shape(&c.category).is_some_and(|s| s.placement == Placement::Mounted));
        for cs in order {
            let Some(sh) = shape(&cs.category) else {
                continue;
            };
            if rng.random::<f64>() >= cs.presence {
                continue;
            }
            // count: 1 + geometric with mean (mean_count - 1)
            let mut count = 1u32;
            let p_more = ((cs.mean_count - 1.0) / cs.mean_count).clamp(0.0, 0.9);
            while count < sh.max_per_room && rng.random::<f64>() < p_more {
                count += 1;
            }
            for k in 0..count {
                let size = (
                    rng.random_range(sh.width.0..=sh.width.1),
                    rng.random_range(sh.depth.0..=sh.depth.1),
                    rng.random_range(sh.height.0..=sh.height.1),
                );
                if sh.placement != Placement::Mounted
                    && used_area + size.0 * size.1 > 0.3 * rect.area()
                {
                    break;
                }
                let Some((at, yaw, foot)) = place(
                    &mut rng,
                    sh.placement,
                    size,
                    &inner,
                    &placed,
                    &mounted,
                    &keep_out,
                ) else {
                    break;
                };
                if sh.placement != Placement::Mounted {
                    let mut trial = placed.clone();
                    trial.push(foot);
                    if !room_stays_open(&inner, &trial, &door_points) {
                        continue;
                    }
                } else if !viewable(&inner, &placed, &door_points, &foot) {
                    continue;
                }
                let inst = b.add_instance(
                    InstanceKind::Object,
                    sh.category,
                    &format!("{} {}", sh.category, k + 1),
                    f,
                );
                let at = Point3::new(
                    at.x,
                    at.y,
                    z + if sh.placement == Placement::Mounted {
                        1.2
                    } else {
                        0.0
                    },
                );
                furniture::build(&mut b, inst, sh.category, size, at, yaw);
                if sh.placement == Placement::Mounted {
                    mounted.push(foot);
                } else {
                    used_area += size.0 * size.1;
                    placed.push(foot);
                }
            }
        }
    }
    let desc = b.finish(&format!("procedural-{seed}"), levels, rooms_out);
    Scene::from_description(desc)
}

/// Free cells (0.1 m) of a room where an agent fits between the placed
/// footprints, labelled by connected component (`u32::MAX` = blocked).
fn free_components(inner: &Rect, placed: &[Rect]) -> (Vec<u32>, usize, usize) {
    const CELL: f64 = 0.1;
    const CLEAR: f64 = 0.3;
    // walls: the navmesh erodes by the agent radius (0.18 m) plus up to one
    // 0.05 m cell of rasterisation, so a cell must keep 0.25 m to the wall
    const WALL_CLEAR: f64 = 0.25;
    let nx = (inner.w() / CELL).floor().max(1.0) as usize;
    let ny = (inner.d() / CELL).floor().max(1.0) as usize;
    let centre = |i: usize, j: usize| {
        Point2::new(
            inner.x0 + (i as f64 + 0.5) * CELL,
            inner.y0 + (j as f64 + 0.5) * CELL,
        )
    };
    let mut label = vec![u32::MAX; nx * ny];
    let free: Vec<bool> = (0..nx * ny)
        .map(|k| {
            let c = centre(k % nx, k / nx);
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
    let i = (((p.x - inner.x0) / 0.1).floor().max(0.0) as usize).min(nx - 1);
    let j = (((p.y - inner.y0) / 0.1).floor().max(0.0) as usize).min(ny - 1);
    j * nx + i
}

/// True when every doorway of the room is free and all doorways (and, for a
/// room without doors, some free cell) lie in one free component.
fn room_stays_open(inner: &Rect, placed: &[Rect], doors: &[Point2<f64>]) -> bool {
    let (label, nx, ny) = free_components(inner, placed);
    let mut comp = None;
    for d in doors {
        let l = label[cell_of(inner, nx, ny, d)];
        if l == u32::MAX || comp.is_some_and(|c| c != l) {
            return false;
        }
        comp = Some(l);
    }
    // every placed piece keeps a free cell of that component within 0.9 m
    placed
        .iter()
        .all(|p| near_component(inner, &label, nx, ny, comp, p))
}

fn near_component(
    inner: &Rect,
    label: &[u32],
    nx: usize,
    ny: usize,
    comp: Option<u32>,
    foot: &Rect,
) -> bool {
    let reach = foot.inflate(0.9);
    (0..nx * ny).any(|k| {
        let c = Point2::new(
            inner.x0 + ((k % nx) as f64 + 0.5) * 0.1,
            inner.y0 + ((k / nx) as f64 + 0.5) * 0.1,
        );
        let l = label[k];
        l != u32::MAX
            && comp.is_none_or(|cc| cc == l)
            && c.x > reach.x0
            && c.x < reach.x1
            && c.y > reach.y0
            && c.y < reach.y1
    }) || ny == 0
}

/// True when a wall-mounted piece with footprint `foot` can be seen from the
/// doorways' free component.
fn viewable(inner: &Rect, placed: &[Rect], doors: &[Point2<f64>], foot: &Rect) -> bool {
    let (label, nx, ny) = free_components(inner, placed);
    let comp = doors.first().map(|d| label[cell_of(inner, nx, ny, d)]);
    near_component(inner, &label, nx, ny, comp, foot)
}

/// Finds a position for a piece. Returns (centre, yaw, footprint).
fn place(
    rng: &mut ChaCha8Rng,
    placement: Placement,
    (w, d, _h): (f64, f64, f64),
    inner: &Rect,
    placed: &[Rect],
    mounted: &[Rect],
    keep_out: &[Rect],
) -> Option<(Point2<f64>, f64, Rect)> {
    const MARGIN: f64 = 0.65;
    for _ in 0..40 {
        let (c, yaw, foot, clear) = match placement {
            Placement::Free => {
                let quarter = rng.random_range(0..4);
                let yaw = f64::from(quarter) * std::f64::consts::FRAC_PI_2;
                let (fw, fd) = if quarter % 2 == 1 { (d, w) } else { (w, d) };
                let lo = (inner.x0 + fw * 0.5 + MARGIN, inner.y0 + fd * 0.5 + MARGIN);
                let hi = (inner.x1 - fw * 0.5 - MARGIN, inner.y1 - fd * 0.5 - MARGIN);
                if lo.0 > hi.0 || lo.1 > hi.1 {
                    return None;
                }
                let c = Point2::new(rng.random_range(lo.0..=hi.0), rng.random_range(lo.1..=hi.1));
                let foot = Rect {
                    x0: c.x - fw * 0.5,
                    x1: c.x + fw * 0.5,
                    y0: c.y - fd * 0.5,
                    y1: c.y + fd * 0.5,
                };
                (c, yaw, foot, foot.inflate(MARGIN))
            }
            Placement::Wall | Placement::Mounted => {
                // side 0: wall at y0 (piece faces +y), 1: x1 (faces -x), 2: y1 (faces -y), 3: x0 (faces +x)
                let side = rng.random_range(0..4);
                let (along_lo, along_hi) = if side % 2 == 0 {
                    (inner.x0, inner.x1)
                } else {
                    (inner.y0, inner.y1)
                };
                if along_hi - along_lo < w + 0.1 {
                    continue;
                }
                let a = rng.random_range(along_lo + w * 0.5 + 0.05..=along_hi - w * 0.5 - 0.05);
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
                let foot = Rect {
                    x0: c.x - fw * 0.5,
                    x1: c.x + fw * 0.5,
                    y0: c.y - fd * 0.5,
                    y1: c.y + fd * 0.5,
                };
                // clearance in front of the piece
                let front = MARGIN + 0.1;
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
                (c, yaw, foot, clear)
            }
        };
        let blocked = if placement == Placement::Mounted {
            mounted.iter().any(|m| m.inflate(0.1).overlaps(&foot))
                || placed.iter().any(|p| p.overlaps(&clear))
        } else {
            placed
                .iter()
                .any(|p| p.overlaps(&clear) || p.inflate(MARGIN).overlaps(&foot))
                || keep_out.iter().any(|k| k.overlaps(&foot))
        };
        if !blocked {
            return Some((c, yaw, foot));
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
            let seg_box = |b: &mut MeshBuilder, a: f64, e: f64, z0: f64, z1: f64, inst| {
                let (min, max) = if axis == 0 {
                    (
                        Point3::new(a, c - t * 0.5, z0),
                        Point3::new(e, c + t * 0.5, z1),
                    )
                } else {
                    (
                        Point3::new(c - t * 0.5, a, z0),
                        Point3::new(c + t * 0.5, e, z1),
                    )
                };
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
                let (p0, p1) = if axis == 0 {
                    (
                        Point3::new(h.seg.lo, c - t * 0.5, z),
                        Point3::new(h.seg.hi, c + t * 0.5, z + cfg.door_height),
                    )
                } else {
                    (
                        Point3::new(c - t * 0.5, h.seg.lo, z),
                        Point3::new(c + t * 0.5, h.seg.hi, z + cfg.door_height),
                    )
                };
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

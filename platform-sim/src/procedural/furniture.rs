//! Composite-box furniture with category-typical shapes.
//!
//! Each piece is built in a local frame: x along the piece's width, y along
//! its depth with the back at `+depth / 2` (against the wall), z up from the
//! floor. A chair has a seat, a back and four legs; a table a top and four
//! legs; a bed a frame, a mattress and a headboard; and so on.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use crate::geometry::MeshBuilder;
use crate::scene::InstanceId;

/// How a category is placed in a room.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// Back against a wall.
    Wall,
    /// In the free area of the room.
    Free,
    /// Hung on a wall above the floor (does not occupy floor space).
    Mounted,
}

/// Shape parameters of one category: (width, depth, height) ranges and placement.
#[derive(Debug, Clone, Copy)]
pub struct Shape {
    /// ObjectNav category.
    pub category: &'static str,
    /// Width range (m).
    pub width: (f64, f64),
    /// Depth range (m).
    pub depth: (f64, f64),
    /// Height range (m).
    pub height: (f64, f64),
    /// Placement rule.
    pub placement: Placement,
    /// Most instances per room.
    pub max_per_room: u32,
}

/// The categories the generator can build.
pub const SHAPES: &[Shape] = &[
    Shape {
        category: "bed",
        width: (0.9, 1.8),
        depth: (1.95, 2.1),
        height: (0.9, 1.1),
        placement: Placement::Wall,
        max_per_room: 2,
    },
    Shape {
        category: "sofa",
        width: (1.6, 2.3),
        depth: (0.85, 0.95),
        height: (0.8, 0.9),
        placement: Placement::Wall,
        max_per_room: 2,
    },
    Shape {
        category: "chair",
        width: (0.42, 0.5),
        depth: (0.45, 0.52),
        height: (0.85, 0.95),
        placement: Placement::Free,
        max_per_room: 6,
    },
    Shape {
        category: "stool",
        width: (0.32, 0.4),
        depth: (0.32, 0.4),
        height: (0.45, 0.7),
        placement: Placement::Free,
        max_per_room: 3,
    },
    Shape {
        category: "table",
        width: (0.8, 1.6),
        depth: (0.6, 0.9),
        height: (0.45, 0.76),
        placement: Placement::Free,
        max_per_room: 2,
    },
    Shape {
        category: "toilet",
        width: (0.38, 0.42),
        depth: (0.6, 0.7),
        height: (0.75, 0.82),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "sink",
        width: (0.5, 0.8),
        depth: (0.42, 0.5),
        height: (0.82, 0.9),
        placement: Placement::Wall,
        max_per_room: 2,
    },
    Shape {
        category: "bathtub",
        width: (1.5, 1.75),
        depth: (0.7, 0.8),
        height: (0.5, 0.6),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "shower",
        width: (0.8, 1.0),
        depth: (0.8, 1.0),
        height: (1.9, 2.1),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "tv_monitor",
        width: (0.8, 1.4),
        depth: (0.35, 0.45),
        height: (1.0, 1.4),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "plant",
        width: (0.35, 0.55),
        depth: (0.35, 0.55),
        height: (0.6, 1.5),
        placement: Placement::Free,
        max_per_room: 3,
    },
    Shape {
        category: "cabinet",
        width: (0.6, 1.2),
        depth: (0.4, 0.6),
        height: (0.8, 2.0),
        placement: Placement::Wall,
        max_per_room: 3,
    },
    Shape {
        category: "chest_of_drawers",
        width: (0.7, 1.2),
        depth: (0.45, 0.55),
        height: (0.8, 1.1),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "counter",
        width: (1.2, 2.4),
        depth: (0.6, 0.65),
        height: (0.88, 0.92),
        placement: Placement::Wall,
        max_per_room: 2,
    },
    Shape {
        category: "fireplace",
        width: (1.2, 1.6),
        depth: (0.4, 0.55),
        height: (1.0, 1.2),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "refrigerator",
        width: (0.6, 0.7),
        depth: (0.6, 0.7),
        height: (1.7, 1.9),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "stove",
        width: (0.6, 0.6),
        depth: (0.6, 0.6),
        height: (0.88, 0.92),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "shelving",
        width: (0.6, 1.2),
        depth: (0.3, 0.4),
        height: (1.2, 2.0),
        placement: Placement::Wall,
        max_per_room: 2,
    },
    Shape {
        category: "washing_machine",
        width: (0.6, 0.6),
        depth: (0.6, 0.6),
        height: (0.85, 0.85),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "seating",
        width: (1.0, 1.5),
        depth: (0.4, 0.5),
        height: (0.45, 0.5),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "picture",
        width: (0.4, 1.0),
        depth: (0.03, 0.05),
        height: (0.4, 0.8),
        placement: Placement::Mounted,
        max_per_room: 3,
    },
    Shape {
        category: "towel",
        width: (0.3, 0.6),
        depth: (0.05, 0.08),
        height: (0.5, 0.7),
        placement: Placement::Mounted,
        max_per_room: 2,
    },
    Shape {
        category: "cushion",
        width: (0.45, 0.6),
        depth: (0.45, 0.6),
        height: (0.25, 0.4),
        placement: Placement::Wall,
        max_per_room: 3,
    },
    Shape {
        category: "lamp",
        width: (0.3, 0.4),
        depth: (0.3, 0.4),
        height: (1.4, 1.7),
        placement: Placement::Wall,
        max_per_room: 3,
    },
    Shape {
        category: "mirror",
        width: (0.4, 0.8),
        depth: (0.03, 0.05),
        height: (0.6, 0.9),
        placement: Placement::Mounted,
        max_per_room: 2,
    },
    Shape {
        category: "radiator",
        width: (0.6, 1.2),
        depth: (0.08, 0.12),
        height: (0.5, 0.7),
        placement: Placement::Wall,
        max_per_room: 2,
    },
    Shape {
        category: "toilet_paper",
        width: (0.12, 0.15),
        depth: (0.1, 0.12),
        height: (0.12, 0.15),
        placement: Placement::Mounted,
        max_per_room: 2,
    },
    Shape {
        category: "dishwasher",
        width: (0.6, 0.6),
        depth: (0.6, 0.6),
        height: (0.85, 0.85),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "piano",
        width: (1.4, 1.55),
        depth: (0.55, 0.65),
        height: (1.1, 1.3),
        placement: Placement::Wall,
        max_per_room: 1,
    },
    Shape {
        category: "gym_equipment",
        width: (0.6, 0.8),
        depth: (1.2, 1.8),
        height: (0.5, 1.3),
        placement: Placement::Free,
        max_per_room: 2,
    },
    Shape {
        category: "clothes",
        width: (0.6, 1.0),
        depth: (0.4, 0.5),
        height: (1.3, 1.7),
        placement: Placement::Wall,
        max_per_room: 2,
    },
];

/// The shape of a category, if the generator can build it.
pub fn shape(category: &str) -> Option<&'static Shape> {
    SHAPES.iter().find(|s| s.category == category)
}

/// Places boxes in the piece's local frame.
struct Piece<'a> {
    b: &'a mut MeshBuilder,
    pose: Isometry3<f64>,
    inst: InstanceId,
}

impl Piece<'_> {
    /// Box from local min to max corner.
    fn boxed(&mut self, x0: f64, y0: f64, z0: f64, x1: f64, y1: f64, z1: f64) {
        let c = Vector3::new((x0 + x1) * 0.5, (y0 + y1) * 0.5, (z0 + z1) * 0.5);
        let half = Vector3::new(
            (x1 - x0).abs() * 0.5,
            (y1 - y0).abs() * 0.5,
            (z1 - z0).abs() * 0.5,
        );
        let pose = self.pose * Translation3::from(c);
        self.b.oriented_box(&pose, half, self.inst);
    }
    fn legs(&mut self, w: f64, d: f64, h: f64, s: f64) {
        let (x, y) = (w * 0.5 - s, d * 0.5 - s);
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            self.boxed(sx * x - s, sy * y - s, 0.0, sx * x + s, sy * y + s, h);
        }
    }
}

/// Builds one piece of `category` with size (w, d, h), its local frame placed
/// at floor point `at` rotated by `yaw` about z. Mounted pieces are built from
/// `at.z` upwards. Unknown categories become a plain box.
pub fn build(
    b: &mut MeshBuilder,
    inst: InstanceId,
    category: &str,
    size: (f64, f64, f64),
    at: Point3<f64>,
    yaw: f64,
) {
    let (w, d, h) = size;
    let pose = Isometry3::from_parts(
        Translation3::new(at.x, at.y, at.z),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
    );
    let mut p = Piece { b, pose, inst };
    let (hw, hd) = (w * 0.5, d * 0.5);
    match category {
        "chair" => {
            let seat = 0.45;
            p.legs(w, d, seat - 0.04, 0.02);
            p.boxed(-hw, -hd, seat - 0.04, hw, hd, seat);
            p.boxed(-hw, hd - 0.05, seat, hw, hd, h);
        }
        "stool" => {
            p.legs(w, d, h - 0.04, 0.02);
            p.boxed(-hw, -hd, h - 0.04, hw, hd, h);
        }
        "table" => {
            p.legs(w, d, h - 0.04, 0.03);
            p.boxed(-hw, -hd, h - 0.04, hw, hd, h);
        }
        "sofa" => {
            p.boxed(-hw, -hd, 0.08, hw, hd, 0.42);
            p.legs(w, d, 0.08, 0.03);
            p.boxed(-hw, hd - 0.2, 0.42, hw, hd, h);
            p.boxed(-hw, -hd, 0.42, -hw + 0.18, hd - 0.2, 0.62);
            p.boxed(hw - 0.18, -hd, 0.42, hw, hd - 0.2, 0.62);
        }
        "bed" => {
            p.legs(w, d, 0.15, 0.04);
            p.boxed(-hw, -hd, 0.15, hw, hd - 0.06, 0.3);
            p.boxed(-hw + 0.02, -hd + 0.02, 0.3, hw - 0.02, hd - 0.08, 0.52);
            p.boxed(-hw, hd - 0.06, 0.0, hw, hd, h);
        }
        "toilet" => {
            p.boxed(-0.15, -hd, 0.0, 0.15, hd - 0.18, 0.2);
            p.boxed(-hw, -hd, 0.2, hw, hd - 0.18, 0.42);
            p.boxed(-hw, hd - 0.18, 0.0, hw, hd, h);
        }
        "sink" => {
            p.boxed(-hw, -hd + 0.02, 0.0, hw, hd, h - 0.05);
            p.boxed(-hw, -hd, h - 0.05, hw, hd, h);
        }
        "bathtub" => {
            p.boxed(-hw, -hd, 0.0, hw, hd, 0.1);
            p.boxed(-hw, -hd, 0.1, hw, -hd + 0.06, h);
            p.boxed(-hw, hd - 0.06, 0.1, hw, hd, h);
            p.boxed(-hw, -hd + 0.06, 0.1, -hw + 0.06, hd - 0.06, h);
            p.boxed(hw - 0.06, -hd + 0.06, 0.1, hw, hd - 0.06, h);
        }
        "shower" => {
            p.boxed(-hw, -hd, 0.0, hw, hd, 0.08);
            p.boxed(-hw, -hd, 0.08, -hw + 0.02, hd, h);
            p.boxed(-hw, -hd, 0.08, 0.0, -hd + 0.02, h);
            p.boxed(-0.02, hd - 0.05, h - 0.3, 0.02, hd, h - 0.26);
        }
        "tv_monitor" => {
            // screen on a low stand; the stand is part of the instance
            let stand = 0.45;
            p.boxed(-hw, -hd, 0.0, hw, hd, stand);
            p.boxed(-0.05, -0.04, stand, 0.05, 0.04, stand + 0.1);
            p.boxed(-hw + 0.05, -0.03, stand + 0.1, hw - 0.05, 0.03, h);
        }
        "plant" => {
            let pot = (h * 0.3).min(0.35);
            p.boxed(-hw * 0.6, -hd * 0.6, 0.0, hw * 0.6, hd * 0.6, pot);
            p.boxed(-0.02, -0.02, pot, 0.02, 0.02, pot + 0.1);
            p.boxed(-hw, -hd, pot + 0.1, hw, hd, h);
            p.boxed(-hw * 0.6, -hd * 0.6, h, hw * 0.6, hd * 0.6, h + 0.1);
        }
        "chest_of_drawers" => {
            p.boxed(-hw, -hd + 0.02, 0.05, hw, hd, h);
            p.boxed(-hw + 0.03, -hd + 0.03, 0.0, hw - 0.03, hd, 0.05);
            let n = 3;
            for i in 0..n {
                let z0 = 0.08 + (h - 0.1) * i as f64 / n as f64;
                let z1 = 0.05 + (h - 0.1) * (i + 1) as f64 / n as f64;
                p.boxed(-hw + 0.02, -hd, z0, hw - 0.02, -hd + 0.02, z1);
            }
        }
        "counter" | "stove" | "washing_machine" | "dishwasher" => {
            p.boxed(-hw, -hd + 0.05, 0.0, hw, hd, 0.1);
            p.boxed(-hw, -hd + 0.02, 0.1, hw, hd, h - 0.04);
            p.boxed(-hw, -hd, h - 0.04, hw, hd, h);
        }
        "fireplace" => {
            p.boxed(-hw, -hd, 0.0, hw, hd, 0.1);
            p.boxed(-hw, -hd, 0.1, -hw + 0.3, hd, h - 0.12);
            p.boxed(hw - 0.3, -hd, 0.1, hw, hd, h - 0.12);
            p.boxed(-hw + 0.3, hd - 0.1, 0.1, hw - 0.3, hd, h - 0.12);
            p.boxed(-hw - 0.05, -hd - 0.05, h - 0.12, hw + 0.05, hd, h);
        }
        "shelving" => {
            p.boxed(-hw, -hd, 0.0, -hw + 0.02, hd, h);
            p.boxed(hw - 0.02, -hd, 0.0, hw, hd, h);
            p.boxed(-hw, hd - 0.01, 0.0, hw, hd, h);
            for i in 0..5 {
                let z = (h - 0.02) * i as f64 / 4.0;
                p.boxed(-hw + 0.02, -hd, z, hw - 0.02, hd - 0.01, z + 0.02);
            }
        }
        "seating" => {
            p.legs(w, d, h - 0.05, 0.03);
            p.boxed(-hw, -hd, h - 0.05, hw, hd, h);
        }
        "cabinet" => {
            p.boxed(-hw + 0.03, -hd + 0.04, 0.0, hw - 0.03, hd, 0.08);
            p.boxed(-hw, -hd + 0.02, 0.08, hw, hd, h);
            p.boxed(-hw + 0.01, -hd, 0.1, -0.005, -hd + 0.02, h - 0.02);
            p.boxed(0.005, -hd, 0.1, hw - 0.01, -hd + 0.02, h - 0.02);
        }
        "lamp" => {
            p.boxed(-hw, -hd, 0.0, hw, hd, 0.04);
            p.boxed(-0.015, -0.015, 0.04, 0.015, 0.015, h - 0.3);
            p.boxed(-hw, -hd, h - 0.3, hw, hd, h);
        }
        "radiator" => {
            p.boxed(-hw, -hd, 0.1, hw, hd, h);
            p.boxed(-hw + 0.03, -0.02, 0.0, -hw + 0.06, 0.02, 0.1);
            p.boxed(hw - 0.06, -0.02, 0.0, hw - 0.03, 0.02, 0.1);
        }
        "piano" => {
            p.boxed(-hw, hd - 0.3, 0.0, hw, hd, h);
            p.boxed(-hw, -hd, 0.65, hw, hd - 0.3, 0.75);
            p.boxed(-hw, -hd, 0.0, -hw + 0.05, hd - 0.3, 0.65);
            p.boxed(hw - 0.05, -hd, 0.0, hw, hd - 0.3, 0.65);
        }
        "gym_equipment" => {
            // a weight bench with an upright rack at one end
            p.legs(w, d, 0.42, 0.03);
            p.boxed(-hw, -hd, 0.42, hw, hd, 0.48);
            p.boxed(-hw, hd - 0.08, 0.48, hw, hd, h.max(0.6));
        }
        "clothes" => {
            // clothes hanging from a rail on two uprights
            p.boxed(-hw, -0.02, 0.0, -hw + 0.03, 0.02, h);
            p.boxed(hw - 0.03, -0.02, 0.0, hw, 0.02, h);
            p.boxed(-hw, -0.015, h - 0.03, hw, 0.015, h);
            p.boxed(-hw + 0.05, -hd, h * 0.35, hw - 0.05, hd, h - 0.05);
        }
        _ => p.boxed(-hw, -hd, 0.0, hw, hd, h),
    }
}

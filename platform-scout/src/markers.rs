//! RViz markers of the agent's state (`/sornav/markers`): frontiers,
//! frontier clusters, relocation candidates, object clusters, the
//! exploration route, the active mission, confirmed targets and the robot's
//! footprint.
//!
//! Each call returns a complete [`MarkerArray`] that starts with a
//! `DELETEALL` marker, so stale markers disappear.

use std::collections::BTreeMap;

use sornav::AgentSnapshot;

use crate::bridge::ConfirmedTarget;
use crate::config::ScoutConfig;
use crate::msg::{ColorRGBA, Header, Marker, MarkerArray, Point, Pose, Quaternion, Vector3};

/// Namespaces of the markers, in publication order.
pub const NAMESPACES: [&str; 9] = [
    FRONTIERS.ns,
    CLUSTERS.ns,
    RELOCATION.ns,
    OBJECTS.ns,
    OBJECT_LABELS.ns,
    ROUTE.ns,
    MISSION.ns,
    CONFIRMED.ns,
    FOOTPRINT.ns,
];

/// How the markers of one namespace look.
struct Style {
    ns: &'static str,
    /// Shape ([`Marker::SPHERE_LIST`], ...).
    kind: i32,
    /// Size along every axis (m).
    scale: f64,
    color: ColorRGBA,
}

impl Style {
    /// Opaque `[r, g, b]`.
    const fn new(ns: &'static str, kind: i32, scale: f64, [r, g, b]: [f32; 3]) -> Self {
        Self {
            ns,
            kind,
            scale,
            color: ColorRGBA::rgb(r, g, b),
        }
    }

    /// A marker `id` of this style, at the origin, with no points.
    fn marker(&self, header: &Header, id: i32) -> Marker {
        Marker {
            header: header.clone(),
            ns: self.ns.to_owned(),
            id,
            r#type: self.kind,
            action: Marker::ADD,
            pose: Pose {
                position: Point::default(),
                orientation: Quaternion::IDENTITY,
            },
            scale: Vector3::new(self.scale, self.scale, self.scale),
            color: self.color,
            ..Marker::default()
        }
    }
}

const FRONTIERS: Style = Style::new("frontiers", Marker::SPHERE_LIST, 0.15, [0.1, 0.5, 1.0]);
const CLUSTERS: Style = Style::new("clusters", Marker::SPHERE_LIST, 0.3, [1.0, 1.0, 1.0]);
const RELOCATION: Style = Style::new(
    "relocation_candidates",
    Marker::CUBE_LIST,
    0.35,
    [1.0, 0.6, 0.0],
);
const OBJECTS: Style = Style::new("objects", Marker::CUBE_LIST, 0.2, [0.7, 0.7, 0.7]);
const OBJECT_LABELS: Style = Style::new(
    "object_labels",
    Marker::TEXT_VIEW_FACING,
    0.25,
    [1.0, 1.0, 1.0],
);
const ROUTE: Style = Style::new("route", Marker::LINE_STRIP, 0.05, [0.2, 1.0, 0.2]);
const MISSION: Style = Style::new("mission", Marker::SPHERE, 0.4, [1.0, 0.0, 1.0]);
const MISSION_PATH: Style = Style::new("mission", Marker::LINE_STRIP, 0.04, [1.0, 0.0, 1.0]);
const CONFIRMED: Style = Style::new("confirmed", Marker::CYLINDER, 0.5, [0.0, 1.0, 0.0]);
const FOOTPRINT: Style = Style::new("footprint", Marker::LINE_STRIP, 0.03, [1.0, 1.0, 0.0]);

/// A distinct colour per key (golden-ratio hue walk).
fn palette(key: u64) -> ColorRGBA {
    let h = (key as f64 * 0.618_033_988_749_895).fract() * 6.0;
    let x = (1.0 - ((h % 2.0) - 1.0).abs()) as f32;
    let (r, g, b) = match h as u32 {
        0 => (1.0, x, 0.0),
        1 => (x, 1.0, 0.0),
        2 => (0.0, 1.0, x),
        3 => (0.0, x, 1.0),
        4 => (x, 0.0, 1.0),
        _ => (1.0, 0.0, x),
    };
    ColorRGBA::rgb(r, g, b)
}

/// The markers of one snapshot.
///
/// # Complexity
/// O(frontiers + clusters + objects + route).
pub fn markers_from_snapshot(
    s: &AgentSnapshot,
    confirmed: &[ConfirmedTarget],
    config: &ScoutConfig,
    header: &Header,
) -> MarkerArray {
    let z = s.pose.map_or(0.0, |p| p.position.z) + 0.05;
    let mut markers = vec![Marker {
        header: header.clone(),
        action: Marker::DELETEALL,
        ..Marker::default()
    }];
    let viewpoints: BTreeMap<u64, Point> = s
        .frontiers
        .iter()
        .map(|f| (f.id.0, Point::new(f.viewpoint.x, f.viewpoint.y, z)))
        .collect();

    let mut m = FRONTIERS.marker(header, 0);
    m.points = viewpoints.values().copied().collect();
    markers.push(m);

    if let Some(cg) = &s.clusters {
        let mut m = CLUSTERS.marker(header, 0);
        for c in cg.clusters() {
            m.points.push(Point::new(c.centre.x, c.centre.y, z + 0.2));
            m.colors.push(palette(c.id.0 as u64));
        }
        markers.push(m);
        let mut m = RELOCATION.marker(header, 0);
        for k in cg.top_k() {
            if let Some(p) = cg
                .cluster(*k)
                .and_then(|c| c.relocation.as_ref())
                .and_then(|r| viewpoints.get(&r.waypoint.0))
            {
                m.points.push(*p);
            }
        }
        markers.push(m);
    }

    let mut cubes = OBJECTS.marker(header, 0);
    let mut id = 0;
    for o in &s.objects {
        let Some(label) = &o.label else { continue };
        cubes.points.push(Point::from(o.centre));
        cubes.colors.push(palette(o.id));
        let mut t = OBJECT_LABELS.marker(header, id);
        t.pose.position = Point::new(o.centre.x, o.centre.y, o.max.z + 0.2);
        t.text = format!("{label} ({})", o.support);
        markers.push(t);
        id += 1;
    }
    markers.push(cubes);

    if let Some(route) = &s.route {
        let mut m = ROUTE.marker(header, 0);
        if let Some(p) = s.pose {
            m.points.push(Point::new(p.position.x, p.position.y, z));
        }
        m.points.extend(
            route
                .order
                .iter()
                .filter_map(|f| viewpoints.get(&f.0))
                .copied(),
        );
        markers.push(m);
    }

    if let Some((_, mission)) = &s.active_mission {
        let mut m = MISSION.marker(header, 0);
        m.pose.position = Point::from(mission.waypoint);
        markers.push(m);
        if let Some(path) = &mission.path {
            let mut m = MISSION_PATH.marker(header, 1);
            m.points = path.iter().map(|p| Point::from(*p)).collect();
            markers.push(m);
        }
    }

    for (i, c) in confirmed.iter().enumerate() {
        let mut m = CONFIRMED.marker(header, i as i32);
        m.pose.position = Point::new(c.centre[0], c.centre[1], c.centre[2]);
        m.scale.z = 1.5;
        markers.push(m);
    }
    if let Some(p) = s.pose {
        let (sin, cos) = p.yaw.sin_cos();
        let mut m = FOOTPRINT.marker(header, 0);
        let fp = &config.robot.footprint;
        m.points = fp
            .iter()
            .chain(fp.first())
            .map(|v| {
                Point::new(
                    p.position.x + cos * v[0] - sin * v[1],
                    p.position.y + sin * v[0] + cos * v[1],
                    z,
                )
            })
            .collect();
        markers.push(m);
    }
    MarkerArray { markers }
}

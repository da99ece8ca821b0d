//! Places where exploration missions arrived, counted: the bound on
//! re-dispatching the same goal.
//!
//! A frontier that standing at its viewpoint does not observe away (floor
//! below the camera's view, a shadow behind furniture) changes a little
//! with every frame and comes back under a new id, so a per-id arrival
//! count never reaches its limit and the robot is sent to the same spot
//! again and again — a thrash of missions that arrive at once and show
//! nothing. [`Visits`] counts arrivals by place instead: an arrival within
//! the radius of a recorded place adds to it (the first such place, in
//! recording order), otherwise it opens a new place; a place reached
//! `limit` times is *spent*, and the agent excludes every frontier whose
//! viewpoint lies within the radius of a spent place.

use nalgebra::Point3;

/// Exploration arrivals counted by place (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Visits {
    places: Vec<(Point3<f64>, u32)>,
    limit: u32,
    radius: f64,
}

impl Visits {
    /// No arrivals yet; a place within `radius` (m, horizontally and
    /// vertically) is spent after `limit` arrivals.
    pub(crate) fn new(limit: u32, radius: f64) -> Self {
        Self {
            places: Vec::new(),
            limit,
            radius,
        }
    }

    fn near(&self, a: &Point3<f64>, b: &Point3<f64>) -> bool {
        (a.xy() - b.xy()).norm() <= self.radius && (a.z - b.z).abs() <= self.radius
    }

    /// Counts an arrival at `at`; non-finite positions are ignored.
    ///
    /// # Complexity
    /// O(p) for p places.
    pub(crate) fn record(&mut self, at: Point3<f64>) {
        if !at.coords.iter().all(|c| c.is_finite()) {
            return;
        }
        match self.places.iter().position(|(p, _)| self.near(p, &at)) {
            Some(i) => self.places[i].1 += 1,
            None => self.places.push((at, 1)),
        }
    }

    /// Whether any place is spent (a cheap test before scanning frontiers).
    pub(crate) fn any_spent(&self) -> bool {
        self.places.iter().any(|(_, n)| *n >= self.limit)
    }

    /// Whether `viewpoint` lies within the radius of a spent place.
    ///
    /// # Complexity
    /// O(p) for p places.
    pub(crate) fn is_spent(&self, viewpoint: &Point3<f64>) -> bool {
        self.places
            .iter()
            .any(|(p, n)| *n >= self.limit && self.near(p, viewpoint))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn a_place_is_spent_after_the_limit() {
        let mut v = Visits::new(3, 0.4);
        let at = Point3::new(1.0, 2.0, 0.0);
        v.record(at);
        v.record(Point3::new(1.2, 2.1, 0.0));
        assert!(!v.any_spent() && !v.is_spent(&at));
        v.record(Point3::new(0.9, 1.8, 0.05));
        assert!(v.any_spent());
        assert!(v.is_spent(&Point3::new(1.3, 2.0, 0.0)));
        // another floor, or another room, is not the same place
        assert!(!v.is_spent(&Point3::new(1.0, 2.0, 2.6)));
        assert!(!v.is_spent(&Point3::new(2.0, 2.0, 0.0)));
        // non-finite arrivals are ignored
        v.record(Point3::new(f64::NAN, 0.0, 0.0));
        assert_eq!(v.places.len(), 1);
    }

    proptest! {
        /// Soundness against a brute-force count: a spent viewpoint has at
        /// least `limit` arrivals within twice the radius (each counted
        /// arrival lies within the radius of its place, the place within
        /// the radius of the viewpoint); and `limit` arrivals at one point
        /// always spend it.
        #[test]
        fn spent_places_have_enough_arrivals(
            arrivals in proptest::collection::vec((0u8..12, 0u8..12, 0u8..2), 0..40),
            probe in (0u8..12, 0u8..12, 0u8..2),
            limit in 1u32..5,
        ) {
            let point = |(x, y, z): (u8, u8, u8)| {
                Point3::new(f64::from(x) * 0.25, f64::from(y) * 0.25, f64::from(z) * 2.5)
            };
            let radius = 0.4;
            let mut v = Visits::new(limit, radius);
            for &a in &arrivals {
                v.record(point(a));
            }
            let p = point(probe);
            let within = arrivals
                .iter()
                .map(|&a| point(a))
                .filter(|a| (a.xy() - p.xy()).norm() <= 2.0 * radius + 1e-9 && (a.z - p.z).abs() <= 2.0 * radius)
                .count();
            if v.is_spent(&p) {
                prop_assert!(within >= limit as usize);
            }
            for _ in 0..limit {
                v.record(p);
            }
            prop_assert!(v.is_spent(&p));
        }
    }
}

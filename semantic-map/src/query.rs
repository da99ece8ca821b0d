//! Read-only queries over the object clusters (as of the last
//! [`SemanticMap::update_clusters`]). These are what the semantic contexts
//! S_r (around the robot) and S_k (around a candidate region) are built from.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::cluster::{ClusterId, ObjectCluster};
use crate::key::VoxelKey;
use crate::label::LabelId;
use crate::map::SemanticMap;

/// A combined cluster filter: every set criterion must hold.
///
/// # Examples
/// ```
/// use nalgebra::Point3;
/// use sornav_semantic_map::{ClusterQuery, LabelId};
/// // S_r: clusters with at least N_min = 10 voxels within 10 m of the robot.
/// let q = ClusterQuery::default()
///     .min_support(10)
///     .within(Point3::new(1.0, 2.0, 0.0), 10.0);
/// let toilets = q.clone().label(LabelId(14));
/// assert_eq!(toilets.label, Some(LabelId(14)));
/// // The same on one floor of a building: the level with its floor at
/// // 2.8 m and the next floor at 5.6 m owns the band [2.8, 5.6).
/// let upstairs = toilets.heights(2.8, 5.6);
/// assert_eq!(upstairs.heights, Some((2.8, 5.6)));
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ClusterQuery {
    /// Only clusters with this label.
    pub label: Option<LabelId>,
    /// Only clusters with `support >= min_support`.
    pub min_support: usize,
    /// Only clusters whose centre lies within this horizontal (x, y)
    /// distance of the point (z is ignored).
    pub within: Option<(Point3<f64>, f64)>,
    /// Only clusters whose centre height `z` lies in `[lo, hi)` (one
    /// floor's height band; see [`heights`](Self::heights)).
    #[serde(default)]
    pub heights: Option<(f64, f64)>,
}

impl ClusterQuery {
    /// Restricts to `label`.
    pub fn label(mut self, label: LabelId) -> Self {
        self.label = Some(label);
        self
    }

    /// Restricts to `support >= n`.
    pub fn min_support(mut self, n: usize) -> Self {
        self.min_support = n;
        self
    }

    /// Restricts to centres within horizontal distance `radius` of `point`.
    pub fn within(mut self, point: Point3<f64>, radius: f64) -> Self {
        self.within = Some((point, radius));
        self
    }

    /// Restricts to centres whose height `z` lies in `[lo, hi)`: the
    /// objects of one floor, whose band is `[floor_z, next floor_z)` (the
    /// top floor's is `[floor_z, f64::INFINITY)`), so that a table top or
    /// a ceiling lamp belongs to the floor below it and every object to
    /// exactly one floor. A NaN bound matches nothing; infinite bounds are
    /// open ends.
    ///
    /// # Examples
    /// ```
    /// use sornav_semantic_map::ClusterQuery;
    /// // Floors at 0 m and 2.8 m: the ground floor's objects, then the
    /// // first floor's (up to the roof).
    /// let ground = ClusterQuery::default().heights(0.0, 2.8);
    /// let first = ClusterQuery::default().heights(2.8, f64::INFINITY);
    /// assert_ne!(ground, first);
    /// ```
    pub fn heights(mut self, lo: f64, hi: f64) -> Self {
        self.heights = Some((lo, hi));
        self
    }

    /// Whether `c` satisfies every criterion. The radius test is
    /// `horizontal_distance(point, centre) <= radius`, so a NaN point
    /// coordinate or radius matches nothing and an infinite radius (with a
    /// finite point) matches every centre. The height test is `lo <=
    /// centre.z < hi`, so a NaN bound matches nothing.
    pub fn matches(&self, c: &ObjectCluster) -> bool {
        if self.label.is_some_and(|l| l != c.label) || c.support < self.min_support {
            return false;
        }
        if let Some((lo, hi)) = self.heights
            && !(lo <= c.centre.z && c.centre.z < hi)
        {
            return false;
        }
        match &self.within {
            None => true,
            Some((p, r)) => horizontal_distance(p, &c.centre) <= *r,
        }
    }
}

/// Distance between the (x, y) projections of two points.
pub fn horizontal_distance(a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    (a.x - b.x).hypot(a.y - b.y)
}

impl SemanticMap {
    /// All clusters in id order.
    pub fn clusters(&self) -> impl Iterator<Item = &ObjectCluster> + '_ {
        self.clusters.entries.values().map(|e| &e.cluster)
    }

    /// Number of clusters.
    pub fn cluster_count(&self) -> usize {
        self.clusters.entries.len()
    }

    /// The cluster with id `id`.
    ///
    /// # Complexity
    /// O(log C) for C clusters.
    pub fn cluster(&self, id: ClusterId) -> Option<&ObjectCluster> {
        self.clusters.entries.get(&id).map(|e| &e.cluster)
    }

    /// The member voxels of cluster `id`, in no particular order.
    pub fn cluster_voxels(&self, id: ClusterId) -> Option<&[VoxelKey]> {
        self.clusters.entries.get(&id).map(|e| e.voxels.as_slice())
    }

    /// The cluster voxel `key` belongs to.
    ///
    /// # Complexity
    /// O(1) expected.
    pub fn cluster_at(&self, key: &VoxelKey) -> Option<ClusterId> {
        self.clusters.assignment.get(key).copied()
    }

    /// Clusters with label `label`, id order. O(C).
    pub fn clusters_with_label(&self, label: LabelId) -> impl Iterator<Item = &ObjectCluster> + '_ {
        self.clusters().filter(move |c| c.label == label)
    }

    /// Clusters with `support >= n`, id order. O(C).
    pub fn clusters_with_support(&self, n: usize) -> impl Iterator<Item = &ObjectCluster> + '_ {
        self.clusters().filter(move |c| c.support >= n)
    }

    /// Clusters whose centre lies within horizontal distance `radius` of
    /// `point` (z ignored), id order. O(C).
    pub fn clusters_within(
        &self,
        point: Point3<f64>,
        radius: f64,
    ) -> impl Iterator<Item = &ObjectCluster> + '_ {
        self.clusters()
            .filter(move |c| horizontal_distance(&point, &c.centre) <= radius)
    }

    /// Clusters matching every criterion of `query`, id order.
    ///
    /// # Complexity
    /// O(C) for C clusters (object clusters number in the hundreds at
    /// most, so a linear scan beats maintaining a spatial index).
    pub fn query(&self, query: &ClusterQuery) -> Vec<&ObjectCluster> {
        self.clusters().filter(|c| query.matches(c)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LabelSet, LabeledPoint, MapConfig};

    /// A map with one cluster of three points near (1.075, 1.025, 0.525).
    fn one_cluster_map() -> SemanticMap {
        let mut map = SemanticMap::new(MapConfig::default(), LabelSet::household()).unwrap();
        let pts: Vec<_> = (0..3)
            .map(|i| LabeledPoint::new(1.025 + 0.05 * i as f32, 1.025, 0.525, LabelId(10)))
            .collect();
        map.integrate_points(&Point3::origin(), &pts).unwrap();
        map.update_clusters();
        map
    }

    #[test]
    fn non_finite_radius_and_point_follow_the_documented_rule() {
        let map = one_cluster_map();
        assert_eq!(map.cluster_count(), 1);
        let o = Point3::origin();
        assert_eq!(map.clusters_within(o, f64::NAN).count(), 0);
        assert_eq!(map.clusters_within(o, f64::INFINITY).count(), 1);
        let nan = Point3::new(f64::NAN, 0.0, 0.0);
        assert_eq!(map.clusters_within(nan, f64::INFINITY).count(), 0);
        let q = ClusterQuery::default().within(o, f64::NAN);
        assert!(map.query(&q).is_empty());
        assert_eq!(map.query(&ClusterQuery::default().within(o, 2.0)).len(), 1);
    }

    #[test]
    fn height_bands_are_half_open_and_nan_matches_nothing() {
        let map = one_cluster_map();
        let z = map.clusters().next().unwrap().centre.z;
        let count = |lo: f64, hi: f64| map.query(&ClusterQuery::default().heights(lo, hi)).len();
        assert_eq!(count(z, z + 1.0), 1); // lower bound included
        assert_eq!(count(z - 1.0, z), 0); // upper bound excluded
        assert_eq!(count(f64::NEG_INFINITY, f64::INFINITY), 1);
        assert_eq!(count(f64::NAN, f64::INFINITY), 0);
        assert_eq!(count(f64::NEG_INFINITY, f64::NAN), 0);
        assert_eq!(count(z + 1.0, z - 1.0), 0); // empty band
        // A query without the field (older JSON) has no height band.
        let q: ClusterQuery =
            serde_json::from_str(r#"{"label":null,"min_support":2,"within":null}"#).unwrap();
        assert_eq!(q, ClusterQuery::default().min_support(2));
    }
}

//! Semantic contexts: the objects around a candidate cluster (`S_k`) and
//! around the robot (`S_r`), as shown to the supervisor.

use std::fmt::Debug;

use nalgebra::{Point2, Point3};
use serde::{Deserialize, Serialize};

use crate::{ClusterError, ClusterGraph, ClusterId};

/// What the semantic contexts need to know about an object `o_j`: its label
/// `l_j`, its support `N_j` (voxels) and its centre `p_j`.
///
/// Implement it for your map's object type (or wrap it in a newtype); it is
/// implemented for [`ObjectSummary`] and for references to any implementor.
pub trait LabelledObject {
    /// Category label `l_j`.
    fn label(&self) -> &str;
    /// Support `N_j`: the number of voxels (observations) backing the object.
    fn support(&self) -> usize;
    /// Centre `p_j` (m, world frame, z up). Only x and y enter distances.
    fn centre(&self) -> Point3<f64>;
    /// The level (floor) the object is on, when known: the contexts of a
    /// cluster graph count only objects of the robot's or the cluster's
    /// level (a bed upstairs, seen through a stairwell, is not part of the
    /// kitchen's context). `None` (the default): the object counts on every
    /// level.
    fn level(&self) -> Option<u16> {
        None
    }
}

impl<T: LabelledObject + ?Sized> LabelledObject for &T {
    fn label(&self) -> &str {
        (**self).label()
    }
    fn support(&self) -> usize {
        (**self).support()
    }
    fn centre(&self) -> Point3<f64> {
        (**self).centre()
    }
    fn level(&self) -> Option<u16> {
        (**self).level()
    }
}

/// A plain object record implementing [`LabelledObject`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectSummary {
    /// Category label `l_j`.
    pub label: String,
    /// Support `N_j` (voxels).
    pub support: usize,
    /// Centre `p_j` (m).
    pub centre: Point3<f64>,
    /// The level the object is on (`None`: unknown, counts everywhere).
    #[serde(default)]
    pub level: Option<u16>,
}

impl LabelledObject for ObjectSummary {
    fn label(&self) -> &str {
        &self.label
    }
    fn support(&self) -> usize {
        self.support
    }
    fn centre(&self) -> Point3<f64> {
        self.centre
    }
    fn level(&self) -> Option<u16> {
        self.level
    }
}

/// An element `(l_j, N_j, d(o_j, C_k))` of a cluster's context `S_k`.
///
/// (Named apart from `sornav-supervisor`'s `CandidateObject`, the policy's
/// input that `sornav` builds from it: both crates are re-exported by the
/// facade.)
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClusterObject {
    /// Label `l_j`.
    pub label: String,
    /// Support `N_j`.
    pub support: usize,
    /// `d(o_j, C_k)`: minimum horizontal distance (m) from the object centre
    /// to a member frontier of the cluster.
    pub distance: f64,
}

/// An element `(l_j, N_j)` of the robot's context `S_r`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NearbyObject {
    /// Label `l_j`.
    pub label: String,
    /// Support `N_j`.
    pub support: usize,
}

/// `S_k = {(l_j, N_j, d(o_j, C_k)) : N_j >= N_min, d(o_j, C_k) <= R_s}`,
/// nearest objects first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ClusterContext {
    /// The cluster `C_k`.
    pub cluster: ClusterId,
    /// The qualifying objects by increasing distance (ties: label, then input
    /// order).
    pub objects: Vec<ClusterObject>,
    /// Objects skipped because their centre had a NaN or infinite coordinate.
    pub rejected_non_finite: usize,
}

/// `S_r = {(l_j, N_j) : N_j >= N_min, ||p_j - p_r||_xy <= R_r}`, nearest
/// objects first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotContext {
    /// The qualifying objects by increasing horizontal distance to the robot
    /// (ties: label, then input order).
    pub objects: Vec<NearbyObject>,
    /// Objects skipped because their centre had a NaN or infinite coordinate.
    pub rejected_non_finite: usize,
}

fn finite_xy<O: LabelledObject>(o: &O) -> Option<Point2<f64>> {
    let c = o.centre();
    c.iter().all(|v| v.is_finite()).then(|| c.xy())
}

/// Splits `objects` into the qualifying `(index, distance)` pairs and the
/// number of non-finite rejections; `distance` returns the horizontal
/// distance of an object's xy centre to the context's anchor.
fn qualifying<O: LabelledObject>(
    objects: &[O],
    n_min: usize,
    radius: f64,
    level: Option<u16>,
    distance: impl Fn(Point2<f64>) -> f64,
) -> (Vec<(usize, f64)>, usize) {
    let mut rejected = 0;
    let mut kept = Vec::new();
    for (i, o) in objects.iter().enumerate() {
        let Some(xy) = finite_xy(o) else {
            rejected += 1;
            continue;
        };
        if o.support() < n_min {
            continue;
        }
        if let (Some(want), Some(have)) = (level, o.level())
            && want != have
        {
            continue;
        }
        let d = distance(xy);
        if d <= radius {
            kept.push((i, d));
        }
    }
    kept.sort_by(|a, b| {
        a.1.total_cmp(&b.1)
            .then_with(|| objects[a.0].label().cmp(objects[b.0].label()))
            .then(a.0.cmp(&b.0))
    });
    (kept, rejected)
}

/// The robot's semantic context `S_r` at `robot` (m) for `config`'s `N_min`
/// and `R_r`.
///
/// `N_min` applies here as well as in `S_k`: objects below it do not count
/// anywhere in SOR-Nav (the design guide's parameter table), and a handful of
/// mislabelled voxels must not trigger a context conflict.
///
/// # Complexity
/// O(M log M) for M objects.
///
/// # Example
/// ```
/// use nalgebra::{Point2, Point3};
/// use sornav_cluster_graph::{ClusterConfig, ObjectSummary, robot_context};
///
/// let bed = ObjectSummary { level: None, label: "bed".into(), support: 400, centre: Point3::new(3.0, 0.0, 0.5) };
/// let far = ObjectSummary { level: None, label: "sofa".into(), support: 900, centre: Point3::new(30.0, 0.0, 0.4) };
/// let s_r = robot_context(Point2::origin(), &[bed, far], &ClusterConfig::default());
/// assert_eq!(s_r.objects.len(), 1);
/// assert_eq!(s_r.objects[0].label, "bed");
/// ```
pub fn robot_context<O: LabelledObject>(
    robot: Point2<f64>,
    objects: &[O],
    config: &crate::ClusterConfig,
) -> RobotContext {
    robot_context_on_level(robot, None, objects, config)
}

/// [`robot_context`] counting only objects on `level` (and objects of
/// unknown level); `None`: every object.
///
/// # Complexity
/// O(M log M) for M objects.
pub fn robot_context_on_level<O: LabelledObject>(
    robot: Point2<f64>,
    level: Option<u16>,
    objects: &[O],
    config: &crate::ClusterConfig,
) -> RobotContext {
    let (kept, rejected_non_finite) = qualifying(objects, config.n_min, config.r_r, level, |xy| {
        (xy - robot).norm()
    });
    RobotContext {
        objects: kept
            .into_iter()
            .map(|(i, _)| NearbyObject {
                label: objects[i].label().to_owned(),
                support: objects[i].support(),
            })
            .collect(),
        rejected_non_finite,
    }
}

impl<Id: Copy + Ord + Debug> ClusterGraph<Id> {
    /// The semantic context `S_k` of cluster `k`: every object with
    /// `N_j >= N_min` on the cluster's level (or of unknown level) whose
    /// centre lies within `R_s` (horizontally) of a member frontier, with
    /// that minimum distance.
    ///
    /// # Errors
    /// [`ClusterError::UnknownCluster`] when `k` is not a cluster of this
    /// graph.
    ///
    /// # Complexity
    /// O(M n_k + M log M) for M objects and n_k members.
    pub fn cluster_context<O: LabelledObject>(
        &self,
        k: ClusterId,
        objects: &[O],
    ) -> Result<ClusterContext, ClusterError> {
        let cluster = self
            .cluster(k)
            .ok_or(ClusterError::UnknownCluster(k.0, self.len()))?;
        let members = &cluster.member_positions;
        let (kept, rejected_non_finite) = qualifying(
            objects,
            self.config().n_min,
            self.config().r_s,
            Some(cluster.level),
            |xy| {
                members
                    .iter()
                    .map(|m| (xy - m).norm())
                    .fold(f64::INFINITY, f64::min)
            },
        );
        Ok(ClusterContext {
            cluster: k,
            objects: kept
                .into_iter()
                .map(|(i, distance)| ClusterObject {
                    label: objects[i].label().to_owned(),
                    support: objects[i].support(),
                    distance,
                })
                .collect(),
            rejected_non_finite,
        })
    }

    /// The contexts `S_k` of the top-K clusters, in ranking order: what the
    /// supervisor compares against the robot's context.
    ///
    /// # Complexity
    /// O(M n + K M log M) for M objects and n frontiers.
    pub fn candidate_contexts<O: LabelledObject>(&self, objects: &[O]) -> Vec<ClusterContext> {
        self.top_k()
            .iter()
            .filter_map(|&k| self.cluster_context(k, objects).ok())
            .collect()
    }

    /// The robot's context `S_r` at the robot position the graph was built
    /// with, counting objects of the robot's level only; see
    /// [`robot_context`].
    pub fn robot_context<O: LabelledObject>(&self, objects: &[O]) -> RobotContext {
        robot_context_on_level(
            self.robot_position(),
            Some(self.robot_level()),
            objects,
            self.config(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ClusterConfig, GraphNode, SparseDecisionGraph};

    fn obj(label: &str, support: usize, x: f64, y: f64) -> ObjectSummary {
        ObjectSummary {
            level: None,
            label: label.into(),
            support,
            centre: Point3::new(x, y, 1.5),
        }
    }

    #[test]
    fn robot_context_filters_sorts_and_counts_rejections() {
        let objects = [
            obj("sofa", 50, 6.0, 8.0), // exactly 10 m: kept
            obj("bed", 50, 1.0, 0.0),
            obj("lamp", 9, 1.0, 0.0), // below N_min
            obj("tv", 50, f64::NAN, 0.0),
            obj("sink", 50, 10.0, 0.1), // beyond R_r
        ];
        let s = robot_context(Point2::origin(), &objects, &ClusterConfig::default());
        let labels: Vec<&str> = s.objects.iter().map(|o| o.label.as_str()).collect();
        assert_eq!(labels, ["bed", "sofa"]);
        assert_eq!(s.rejected_non_finite, 1);
    }

    #[test]
    fn cluster_context_uses_the_nearest_member_horizontally() {
        let mut g = SparseDecisionGraph::new(Point2::origin());
        g.add_frontier(1_u32, Point2::new(0.0, 0.0));
        g.add_frontier(2, Point2::new(20.0, 0.0));
        g.set_edge(GraphNode::Frontier(1), GraphNode::Frontier(2), 20.0, vec![]);
        g.set_edge(GraphNode::Robot, GraphNode::Frontier(1), 0.0, vec![]);
        let cg = ClusterGraph::build(&g, &ClusterConfig::default()).unwrap();
        assert_eq!(cg.len(), 1);
        // The centre (10, 0) is 9 m from this object, but the nearest
        // member is 11 m away: excluded. Height is ignored.
        let objects = [
            ObjectSummary {
                level: None,
                label: "toilet".into(),
                support: 30,
                centre: Point3::new(10.0, 9.0, 40.0),
            },
            obj("bed", 30, 23.0, 4.0),
        ];
        let s = cg.cluster_context(ClusterId(0), &objects).unwrap();
        assert_eq!(s.objects.len(), 1);
        assert_eq!(s.objects[0].label, "bed");
        approx::assert_relative_eq!(s.objects[0].distance, 5.0);
        assert_eq!(
            cg.cluster_context(ClusterId(3), &objects),
            Err(ClusterError::UnknownCluster(3, 1))
        );
        assert_eq!(cg.candidate_contexts(&objects), vec![s.clone()]);
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(serde_json::from_str::<ClusterContext>(&json).unwrap(), s);
    }
}

//! An agent and episodes looking for a target that no scene carries (the
//! exploration tests).

/// A target category that no instance of any scene carries: an agent
/// looking for it explores until it declares the search exhausted.
pub const ABSENT: &str = "no_such_object";

/// Builds the simulator agent with one more category, [`ABSENT`], that no
/// pixel is ever labelled with.
pub struct AbsentTargetFactory(pub sornav_examples::adapter::ConfigFactory);

impl sornav_examples::adapter::AgentFactory for AbsentTargetFactory {
    fn build(&self, labels: &[sornav::LabelEntry]) -> Result<sornav::Agent, sornav::AgentError> {
        let mut labels = labels.to_vec();
        let id = labels.iter().map(|l| l.id).max().unwrap_or(0) + 1;
        labels.push(sornav::LabelEntry {
            id,
            name: ABSENT.to_owned(),
            ignored: false,
        });
        self.0.build(&labels)
    }
}

/// An episode looking for [`ABSENT`] from `start` heading `yaw`, with a
/// placeholder goal at the start (`run_episode` needs a view point; the
/// agent never finds it).
pub fn absent_target_episode(
    id: String,
    scene: &str,
    start: nalgebra::Point3<f64>,
    yaw: f64,
) -> sornav_platform_sim::Episode {
    sornav_platform_sim::Episode {
        episode_id: id,
        scene_id: scene.to_owned(),
        start_position: start,
        start_yaw: yaw,
        object_category: ABSENT.to_owned(),
        goals: vec![sornav_platform_sim::ObjectGoal {
            object_id: u64::MAX,
            object_name: None,
            category: ABSENT.to_owned(),
            position: start,
            view_points: vec![sornav_platform_sim::ViewPoint {
                position: start,
                yaw: 0.0,
                iou: None,
            }],
        }],
        geodesic_distance: None,
        euclidean_distance: None,
        closest_goal_object_id: None,
        cross_floor: None,
    }
}

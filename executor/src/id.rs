//! Identifiers used by missions.

use serde::{Deserialize, Serialize};

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident, $label:literal) => {
        $(#[$doc])*
        #[derive(
            Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize,
        )]
        #[serde(transparent)]
        pub struct $name(pub u64);

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, concat!($label, "#{}"), self.0)
            }
        }
    };
}

id_type!(
    /// A frontier of the global frontier decision graph (target of
    /// [`MissionKind::Explore`](crate::MissionKind::Explore)).
    FrontierId,
    "frontier"
);
id_type!(
    /// A frontier cluster (region) of the cluster graph (target of
    /// [`MissionKind::Relocate`](crate::MissionKind::Relocate)).
    ClusterId,
    "cluster"
);
id_type!(
    /// An object cluster of the semantic map (target of
    /// [`MissionKind::NavToObject`](crate::MissionKind::NavToObject)).
    ObjectId,
    "object"
);
id_type!(
    /// A mission admitted by the [`Executor`](crate::Executor); unique per
    /// executor, increasing.
    MissionId,
    "mission"
);

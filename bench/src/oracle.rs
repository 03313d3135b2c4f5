//! The penetration oracle of B5 and B8: parry3d's mesh-mesh intersection test of a part's
//! visible pose against its static surroundings, independent of our own collision detection.

use vas_server::collision::parry_mesh::ORACLE_SCALE;
use vas_server::collision::{MeshCollider, ParryMesh, QueryStats};
use vas_server::geometry::TriMesh;
use vas_server::sliding::Pose;

/// parry3d's mesh-mesh intersection test of one part against fixed obstacles.
///
/// The test runs in millimetres: parry's GJK reports "intersecting" for any distance below
/// 1.2e-6 of its length unit, which in metres would flag the micrometre gaps a contact tolerance
/// of a hundredth of a millimetre leaves. Intersection does not change under uniform scaling,
/// and in millimetres that threshold (1.2 nm) is below the f32 resolution of the coordinates.
pub struct PenetrationOracle {
    part: ParryMesh,
    obstacles: Vec<(ParryMesh, Pose)>,
}

impl PenetrationOracle {
    /// The oracle of `part` (in its own frame) against `obstacles`, each a mesh in its own frame
    /// and its pose in the world.
    pub fn new<'a>(
        part: &TriMesh,
        obstacles: impl IntoIterator<Item = (&'a TriMesh, Pose)>,
    ) -> Self {
        PenetrationOracle {
            part: ParryMesh::in_millimetres(part),
            obstacles: obstacles
                .into_iter()
                .map(|(mesh, pose)| (ParryMesh::in_millimetres(mesh), pose))
                .collect(),
        }
    }

    /// Whether the part at `part_pose` (in the world) intersects an obstacle.
    pub fn penetrates(&self, part_pose: &Pose) -> bool {
        let inverse = part_pose.inverse();
        self.obstacles.iter().any(|(mesh, pose)| {
            let mut relative = inverse * pose;
            relative.translation.vector *= ORACLE_SCALE;
            self.part
                .intersects(mesh, &relative, &mut QueryStats::default())
        })
    }
}

//! The pairs of parts that collide where the scene places them. The simulation cannot blame such
//! a pair on a move, so it leaves it unchecked until the parts part; a person fixing the scene
//! needs to know which pairs those are, by name.

use std::sync::Arc;

use super::Scene;
use crate::collision::pipeline::{
    CollisionModel, CollisionPipeline, Detail, ObjectDesc, PipelineConfig,
};

impl Scene {
    /// The pairs of parts (ids, the smaller first, in order) whose meshes intersect at their
    /// configured poses, among the pairs the scene's collision rules check (two static parts
    /// are never checked). Builds the parts' trees and hulls where they are not built yet.
    pub fn colliding_as_placed(&self) -> Vec<[usize; 2]> {
        let mut pipeline = CollisionPipeline::new(PipelineConfig::default());
        let objects: Vec<_> = (self.parts.iter().enumerate())
            .map(|(id, part)| {
                pipeline
                    .add(ObjectDesc {
                        model: Arc::new(CollisionModel::new(
                            part.tree().clone(),
                            part.hull().clone(),
                        )),
                        pose: part.pose,
                        group: self.group_id(id),
                        is_static: !part.movable,
                    })
                    .expect("a validated scene's poses are valid and its parts fit")
            })
            .collect();
        pipeline.set_interest(self.interest_matrix(&objects));
        let id_of = |object| (objects.iter()).position(|&placed| placed == object);
        let mut pairs: Vec<[usize; 2]> = (pipeline.run_frame(Detail::Pairs).colliding.iter())
            .filter_map(|pair| {
                let (a, b) = (id_of(pair.a)?, id_of(pair.b)?);
                Some([a.min(b), a.max(b)])
            })
            .collect();
        pairs.sort_unstable();
        pairs
    }

    /// `pairs` of part ids in words, for a person: "peg – block, bolt – plate".
    pub fn pair_names(&self, pairs: &[[usize; 2]]) -> String {
        let name = |id: usize| self.parts.get(id).map_or("?", |part| part.name.as_str());
        (pairs.iter())
            .map(|&[a, b]| format!("{} – {}", name(a), name(b)))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

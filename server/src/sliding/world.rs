//! The collision copy of the grasped part tested pairwise against the obstacles around it: the
//! [`SlideWorld`] the state machine runs on when it queries collision structures directly.
//!
//! The part and every obstacle carry a [`MeshCollider`] (the DOP-tree in the server) and an edge
//! adjacency for classification. A query skips obstacles whose world box the part's bounding
//! sphere misses, then asks the collider. Obstacles that form a slide-in unit with the part have
//! an allowance: their intersecting pairs count only when deeper than it.
//!
//! The distance query (for conservative advancement) asks each obstacle pair for its distance
//! below the least found so far, starting from the bound the caller gives, so that an obstacle
//! farther than that costs one sphere-box test; each pair keeps its own [`DistanceCollider`]
//! memory from query to query.
//!
//! The world keeps the time spent in collision detection apart from the rest, so that benchmarks
//! can report the sliding algorithm's own cost per contact point.

use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::Point3;

use super::allowance::triangle_pair_depth;
use super::contact::{Contact, ContactSide, TouchingPair, classify_pairs};
use super::machine::SlideWorld;
use super::motion::{Motion, Pose};
use crate::collision::distance::DistanceMemory;
use crate::collision::pipeline::ExactTest;
use crate::collision::{DopTree, MeshCollider, QueryStats};
use crate::geometry::{EdgeAdjacency, Point, TriMesh};

/// A mesh with what sliding needs of it: edge adjacency and a collision structure.
#[derive(Debug)]
pub struct SlideBody<C> {
    mesh: Arc<TriMesh>,
    adjacency: Arc<EdgeAdjacency>,
    collider: C,
}

impl<C: MeshCollider> SlideBody<C> {
    /// Builds adjacency and collider for `mesh` (weld a soup first, so that neighbours share
    /// vertices; classification copes without, by its rim rule).
    pub fn new(mesh: Arc<TriMesh>) -> Self {
        let adjacency = Arc::new(EdgeAdjacency::new(&mesh));
        let collider = C::build(&mesh);
        SlideBody::with_parts(mesh, adjacency, collider)
    }

    /// A body of `mesh` whose `adjacency` and `collider` are already built (a scene's parts
    /// share their DOP-trees with the other loops, and build their adjacency while the scene is
    /// prepared).
    pub fn with_parts(mesh: Arc<TriMesh>, adjacency: Arc<EdgeAdjacency>, collider: C) -> Self {
        SlideBody {
            adjacency,
            collider,
            mesh,
        }
    }

    /// The mesh.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// The centre of the mesh's bounding box and the radius of the sphere around it that holds
    /// every vertex: the pivot and radius of a grasped part.
    pub fn pivot_and_radius(&self) -> (Point, f64) {
        self.mesh.bounding_sphere()
    }

    fn side<'a>(&'a self, pose: &'a Pose) -> ContactSide<'a> {
        ContactSide {
            mesh: &self.mesh,
            adjacency: &self.adjacency,
            pose,
        }
    }
}

/// A collider that also measures distances between meshes.
pub trait DistanceCollider: ExactTest {
    /// What a pair of meshes keeps from one query to the next.
    type Memory: Default + Clone + Send + std::fmt::Debug;

    /// The least distance between the two meshes (B posed in A's frame by `b_to_a`), 0 when
    /// they touch or intersect; `None` when it is at least `d_max`.
    fn distance_below(
        &self,
        other: &Self,
        b_to_a: &Pose,
        d_max: f64,
        memory: &mut Self::Memory,
        stats: &mut QueryStats,
    ) -> Option<f64>;
}

impl DistanceCollider for DopTree {
    type Memory = DistanceMemory;

    fn distance_below(
        &self,
        other: &Self,
        b_to_a: &Pose,
        d_max: f64,
        memory: &mut DistanceMemory,
        stats: &mut QueryStats,
    ) -> Option<f64> {
        DopTree::distance_below(self, other, b_to_a, d_max, memory, stats)
            .map(|closest| closest.distance)
    }
}

/// A static obstacle: a body at a pose, with an optional slide-in allowance against the part.
#[derive(Debug)]
pub struct Obstacle<C> {
    body: Arc<SlideBody<C>>,
    pose: Pose,
    allowance: Option<f64>,
    /// The world-frame bounding box of the posed mesh.
    world_box: (Point, Point),
}

impl<C: MeshCollider> Obstacle<C> {
    /// An obstacle at `pose`; `allowance` (metres) when it and the part form a slide-in unit.
    pub fn new(body: Arc<SlideBody<C>>, pose: Pose, allowance: Option<f64>) -> Self {
        let mut lo = Point3::from([f64::MAX; 3]);
        let mut hi = Point3::from([f64::MIN; 3]);
        for v in body.mesh.vertices() {
            let w = pose * v;
            lo = lo.inf(&w);
            hi = hi.sup(&w);
        }
        Obstacle {
            body,
            pose,
            allowance,
            world_box: (lo, hi),
        }
    }

    /// Whether a sphere may touch the obstacle's world box.
    fn near(&self, centre: &Point, radius: f64) -> bool {
        let (lo, hi) = &self.world_box;
        let nearest = centre.coords.sup(&lo.coords).inf(&hi.coords);
        (nearest - centre.coords).norm_squared() <= radius * radius
    }
}

/// Work and time spent by a [`PairwiseWorld`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WorldStats {
    /// Collision queries (first hit) answered.
    pub collision_queries: u64,
    /// Contact queries (all pairs, then classification) answered.
    pub contact_queries: u64,
    /// Distance queries answered.
    pub distance_queries: u64,
    /// Obstacle tests skipped by the bounding-sphere check.
    pub obstacles_skipped: u64,
    /// Work inside the colliders.
    pub query_stats: QueryStats,
    /// Time spent in collision detection (collider queries, allowance depths and distances).
    pub collision_time: Duration,
    /// Time spent classifying contacts.
    pub classification_time: Duration,
}

/// The grasped part's collision copy against a set of static obstacles, queried pair by pair.
#[derive(Debug)]
pub struct PairwiseWorld<C: DistanceCollider> {
    part: Arc<SlideBody<C>>,
    /// Pivot of the part in its mesh frame, and the radius around it.
    pivot: Point,
    radius: f64,
    obstacles: Vec<Obstacle<C>>,
    /// Per obstacle, its distance memory with the part.
    memories: Vec<C::Memory>,
    pairs: Vec<TouchingPair>,
    stats: WorldStats,
    /// The part pose of the last collision query that found the part free.
    last_free: Option<Pose>,
    /// Whether a first-hit query may split a long traversal across the current rayon pool
    /// ([`ExactTest::intersects_split`]).
    split_long_queries: bool,
}

impl<C: DistanceCollider> PairwiseWorld<C> {
    /// The part's collision copy against `obstacles`.
    pub fn new(part: Arc<SlideBody<C>>, obstacles: Vec<Obstacle<C>>) -> Self {
        let (pivot, radius) = part.pivot_and_radius();
        PairwiseWorld {
            part,
            pivot,
            radius,
            memories: vec![C::Memory::default(); obstacles.len()],
            obstacles,
            pairs: Vec::new(),
            stats: WorldStats::default(),
            last_free: None,
            split_long_queries: false,
        }
    }

    /// Lets first-hit queries split a long traversal across the current rayon pool: a part of
    /// tens of thousands of triangles sliding along a close fit spends most of its frame in one
    /// such query. Off by default: the runtime's loops already share the cores.
    pub fn split_long_queries(mut self, split: bool) -> Self {
        self.split_long_queries = split;
        self
    }

    /// The obstacles, in the order contacts name them.
    pub fn obstacles(&self) -> &[Obstacle<C>] {
        &self.obstacles
    }

    /// The obstacles (by index, with their poses) that the last collision query to find the part
    /// free proved apart from it, if that query was at `part_pose`; otherwise none. A query tests
    /// every obstacle near the part, so a free answer proves each of them apart, except those
    /// with an allowance, which may overlap the part by design and are left out. The collision
    /// loop then need not test those pairs again at the same poses.
    pub fn proved_apart(&self, part_pose: &Pose) -> Vec<(usize, Pose)> {
        if self.last_free != Some(*part_pose) {
            return Vec::new();
        }
        let centre = part_pose * self.pivot;
        (self.obstacles.iter().enumerate())
            .filter(|(_, obstacle)| obstacle.allowance.is_none())
            .filter(|(_, obstacle)| obstacle.near(&centre, self.radius))
            .map(|(index, obstacle)| (index, obstacle.pose))
            .collect()
    }

    /// Counters and times so far.
    pub fn stats(&self) -> &WorldStats {
        &self.stats
    }

    /// The pairs of obstacle `index` touching the part at `part_pose`, deeper than the
    /// obstacle's allowance if it has one, into `self.pairs` (sorted).
    fn collect_pairs(&mut self, index: usize, part_pose: &Pose) {
        let obstacle = &self.obstacles[index];
        self.pairs.clear();
        let b_to_a = part_pose.inverse() * obstacle.pose;
        self.part.collider.intersecting_pairs(
            &obstacle.body.collider,
            &b_to_a,
            &mut self.pairs,
            &mut self.stats.query_stats,
        );
        if let Some(allowance) = obstacle.allowance {
            let (part, other) = (&self.part.mesh, &obstacle.body.mesh);
            self.pairs.retain(|&[p, q]| {
                let tp = part.triangle(p as usize);
                let tq = other.triangle(q as usize).map(|v| b_to_a * v);
                triangle_pair_depth(&tp, &tq) > allowance
            });
        }
        self.pairs.sort_unstable();
    }
}

impl<C: DistanceCollider> SlideWorld for PairwiseWorld<C> {
    fn collides(&mut self, part_pose: &Pose) -> bool {
        let start = Instant::now();
        self.stats.collision_queries += 1;
        let centre = part_pose * self.pivot;
        let mut hit = false;
        for index in 0..self.obstacles.len() {
            let obstacle = &self.obstacles[index];
            if !obstacle.near(&centre, self.radius) {
                self.stats.obstacles_skipped += 1;
                continue;
            }
            hit = if obstacle.allowance.is_some() {
                self.collect_pairs(index, part_pose);
                !self.pairs.is_empty()
            } else {
                let b_to_a = part_pose.inverse() * obstacle.pose;
                let (other, stats) = (&obstacle.body.collider, &mut self.stats.query_stats);
                if self.split_long_queries {
                    self.part.collider.intersects_split(other, &b_to_a, stats)
                } else {
                    self.part.collider.intersects(other, &b_to_a, stats)
                }
            };
            if hit {
                break;
            }
        }
        self.stats.collision_time += start.elapsed();
        if !hit {
            self.last_free = Some(*part_pose);
        }
        hit
    }

    fn clearance(&mut self, part_pose: &Pose, d_max: f64) -> Option<f64> {
        let start = Instant::now();
        self.stats.distance_queries += 1;
        let centre = part_pose * self.pivot;
        let mut least = None;
        let mut bound = d_max;
        for (obstacle, memory) in self.obstacles.iter().zip(&mut self.memories) {
            if !obstacle.near(&centre, self.radius + bound) {
                self.stats.obstacles_skipped += 1;
                continue;
            }
            let distance = if obstacle.allowance.is_some() {
                // The pair may overlap by design: no distance to go by.
                Some(0.0)
            } else {
                let b_to_a = part_pose.inverse() * obstacle.pose;
                let (other, stats) = (&obstacle.body.collider, &mut self.stats.query_stats);
                self.part
                    .collider
                    .distance_below(other, &b_to_a, bound, memory, stats)
            };
            if let Some(distance) = distance {
                least = Some(distance);
                bound = distance;
                if distance <= 0.0 {
                    break;
                }
            }
        }
        self.stats.collision_time += start.elapsed();
        least
    }

    fn contacts(
        &mut self,
        part_pose: &Pose,
        approach: &Motion,
        pivot: &Point,
        out: &mut Vec<Contact>,
    ) {
        self.stats.contact_queries += 1;
        let centre = part_pose * self.pivot;
        for index in 0..self.obstacles.len() {
            if !self.obstacles[index].near(&centre, self.radius) {
                self.stats.obstacles_skipped += 1;
                continue;
            }
            let start = Instant::now();
            self.collect_pairs(index, part_pose);
            let classifying = Instant::now();
            self.stats.collision_time += classifying - start;
            let obstacle = &self.obstacles[index];
            classify_pairs(
                index,
                &self.part.side(part_pose),
                &obstacle.body.side(&obstacle.pose),
                &self.pairs,
                approach,
                pivot,
                out,
            );
            self.stats.classification_time += classifying.elapsed();
        }
    }
}

//! The hand against the parts near it: each segment's DOP-tree tested against each part's, and
//! the contacts of touching segments, found with a slightly inflated copy of the segment.

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Unit, Vector3};

use super::analysis::{Contact, ContactSide};
use super::clasp::{ObjectSet, SegmentPlacement};
use super::model::{HandModel, JointLevel, SegmentId};
use super::segment_mesh::{SegmentMeshError, swept_hull_mesh};
use crate::collision::{DopTree, MeshCollider, OrientationSet, QueryStats};
use crate::geometry::TriMesh;

/// The caller's name for a part (its index in the scene).
pub type PartId = u32;

/// Most contact points kept per segment and part: enough to outline a contact region.
const MAX_CONTACT_POINTS: usize = 48;

/// Most triangle pairs of a contact whose edge crossings are computed (four times the points
/// kept, so that thinning still picks from an even spread).
const CROSSING_PAIRS: usize = 4 * MAX_CONTACT_POINTS;

/// The most objects a collider handles at once (bits of an [`ObjectSet`]).
pub const MAX_OBJECTS: usize = 64;

/// Collision geometry of one segment, in its own frame.
#[derive(Debug, Clone)]
struct SegmentGeometry {
    mesh: TriMesh,
    tree: DopTree,
    probe: TriMesh,
    probe_tree: DopTree,
    /// Outward unit normal of each probe triangle.
    probe_normals: Vec<Vector3<f64>>,
    /// Bounding sphere of the probe mesh.
    bound: (Point3<f64>, f64),
}

/// The collision geometry of a whole hand, built once per hand model.
#[derive(Debug, Clone)]
pub struct HandGeometry {
    segments: Vec<SegmentGeometry>,
    probe_margin: f64,
}

impl HandGeometry {
    /// Builds every segment's mesh and DOP-tree (of `k` orientations, the parts' k), and those
    /// of its contact probe: the segment grown by `probe_margin` metres, which must exceed the
    /// gap the clasp may leave at a contact.
    pub fn new(
        model: &HandModel,
        probe_margin: f64,
        k: usize,
    ) -> Result<HandGeometry, SegmentMeshError> {
        let orientations = OrientationSet::new(k)?;
        let segments = model
            .segments()
            .iter()
            .map(|segment| {
                let mesh = swept_hull_mesh(&segment.shape, 0.0)?;
                let probe = swept_hull_mesh(&segment.shape, probe_margin)?;
                let centre = mean_vertex(&probe);
                let probe_normals = probe
                    .triangles()
                    .iter()
                    .enumerate()
                    .map(|(i, _)| {
                        let [a, b, c] = probe.triangle(i);
                        let n = (b - a).cross(&(c - a)).normalize();
                        // The hull is convex: outward is away from its centre.
                        if n.dot(&(a - centre)) < 0.0 { -n } else { n }
                    })
                    .collect();
                let radius = probe
                    .vertices()
                    .iter()
                    .map(|v| (v - centre).norm())
                    .fold(0.0, f64::max);
                Ok(SegmentGeometry {
                    tree: DopTree::with_orientations(&mesh, &orientations),
                    probe_tree: DopTree::with_orientations(&probe, &orientations),
                    mesh,
                    probe,
                    probe_normals,
                    bound: (centre, radius),
                })
            })
            .collect::<Result<Vec<_>, SegmentMeshError>>()?;
        Ok(HandGeometry {
            segments,
            probe_margin,
        })
    }

    /// The collision mesh of a segment, in its frame.
    pub fn mesh(&self, segment: SegmentId) -> &TriMesh {
        &self.segments[segment].mesh
    }

    /// The DOP-tree of a segment's collision mesh (a clone shares it).
    pub fn tree(&self, segment: SegmentId) -> &DopTree {
        &self.segments[segment].tree
    }

    /// How much the contact probe is grown beyond the segment (metres).
    pub fn probe_margin(&self) -> f64 {
        self.probe_margin
    }
}

/// A part as the hand needs it, built once per part: its mesh, DOP-tree, bounding sphere and
/// centre of mass.
#[derive(Debug, Clone)]
pub struct PartGeometry {
    /// Shared with the scene's part, which has it already.
    mesh: Arc<TriMesh>,
    tree: DopTree,
    bound: (Point3<f64>, f64),
    centre_of_mass: Point3<f64>,
}

impl PartGeometry {
    /// A sphere around the part, in its own frame: its centre and radius.
    pub fn bound(&self) -> (Point3<f64>, f64) {
        self.bound
    }

    /// Builds the part's DOP-tree (default orientations); see [`PartGeometry::with_tree`].
    pub fn new(mesh: impl Into<Arc<TriMesh>>) -> PartGeometry {
        let mesh = mesh.into();
        let tree = DopTree::build(&mesh);
        PartGeometry::with_tree(mesh, tree)
    }

    /// The part with `tree`, already built over `mesh` (a scene's parts share theirs with the
    /// other loops). The centre of mass is the area-weighted centroid of the surface: right for
    /// hollow parts and for symmetric solids, and defined for open meshes with inconsistent
    /// winding, where a volume centroid is not.
    pub fn with_tree(mesh: Arc<TriMesh>, tree: DopTree) -> PartGeometry {
        let (centre, radius) = mesh.bounding_sphere();
        let mut area = 0.0;
        let mut weighted = Vector3::zeros();
        for i in 0..mesh.triangles().len() {
            let [a, b, c] = mesh.triangle(i);
            let w = (b - a).cross(&(c - a)).norm();
            area += w;
            weighted += (a.coords + b.coords + c.coords) * (w / 3.0);
        }
        PartGeometry {
            tree,
            bound: (centre, radius),
            centre_of_mass: Point3::from(weighted / area),
            mesh,
        }
    }

    /// The part's mesh, in its frame.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// The part's DOP-tree.
    pub fn tree(&self) -> &DopTree {
        &self.tree
    }

    /// The centre of mass, in the part's frame.
    pub fn centre_of_mass(&self) -> Point3<f64> {
        self.centre_of_mass
    }
}

/// A part near the hand: what the caller passes every frame.
#[derive(Debug, Clone, Copy)]
pub struct Obstacle<'a> {
    /// The caller's id of the part.
    pub part: PartId,
    /// Its geometry.
    pub geometry: &'a PartGeometry,
    /// Its pose in the world (ignored for the part the hand holds, which follows the hand).
    pub pose: Isometry3<f64>,
}

/// The collision test the clasp uses: segments against the obstacles of one frame; the held part
/// (if any) is placed in the hand root's frame.
pub struct SceneCollider<'a> {
    hand: &'a HandGeometry,
    obstacles: &'a [Obstacle<'a>],
    /// Index into `obstacles` of the held part, and the part's pose in the root's frame.
    held: Option<(usize, Isometry3<f64>)>,
    /// Work done by the queries so far.
    pub stats: QueryStats,
    pairs: Vec<[u32; 2]>,
}

impl<'a> SceneCollider<'a> {
    /// A collider over at most [`MAX_OBJECTS`] obstacles (the rest are ignored); `held` names
    /// the held part and its pose relative to the hand root.
    pub fn new(
        hand: &'a HandGeometry,
        obstacles: &'a [Obstacle<'a>],
        held: Option<(PartId, Isometry3<f64>)>,
    ) -> Self {
        let obstacles = &obstacles[..obstacles.len().min(MAX_OBJECTS)];
        let held = held.and_then(|(part, offset)| {
            obstacles
                .iter()
                .position(|o| o.part == part)
                .map(|k| (k, offset))
        });
        SceneCollider {
            hand,
            obstacles,
            held,
            stats: QueryStats::default(),
            pairs: Vec::new(),
        }
    }

    /// The obstacles, in object order (bit `k` of an [`ObjectSet`] is `obstacles()[k]`).
    pub fn obstacles(&self) -> &[Obstacle<'a>] {
        self.obstacles
    }

    /// The pose of object `k` in the world when the hand root is at `root`.
    pub fn object_pose(&self, k: usize, root: &Isometry3<f64>) -> Isometry3<f64> {
        match self.held {
            Some((held, offset)) if held == k => root * offset,
            _ => self.obstacles[k].pose,
        }
    }

    /// The segment's pose in object `k`'s frame. The held part's relation to the segment does
    /// not depend on the root, so it is computed without it.
    pub fn segment_in_object(&self, k: usize, placement: &SegmentPlacement) -> Isometry3<f64> {
        match self.held {
            Some((held, offset)) if held == k => offset.inv_mul(&placement.local),
            _ => self.obstacles[k].pose.inv_mul(&placement.world()),
        }
    }

    /// The objects the segment intersects at `placement` (the held part is skipped when the
    /// flex values are valid: it moves with the root).
    pub fn collisions(&mut self, segment: SegmentId, placement: &SegmentPlacement) -> ObjectSet {
        let geometry = &self.hand.segments[segment];
        let mut hit = ObjectSet::EMPTY;
        for k in 0..self.obstacles.len() {
            if placement.flex_valid && self.held.is_some_and(|(held, _)| held == k) {
                continue;
            }
            let to_object = self.segment_in_object(k, placement);
            let part = self.obstacles[k].geometry;
            if !spheres_overlap(&to_object, geometry.bound, part.bound) {
                continue;
            }
            if part
                .tree
                .intersects(&geometry.tree, &to_object, &mut self.stats)
            {
                hit = hit.union(ObjectSet::single(k));
            }
        }
        hit
    }

    /// How a segment at `to_object` (its pose in object `k`'s frame, see
    /// [`SceneCollider::segment_in_object`]) touches the object: where its probe (the segment
    /// grown by the probe margin) cuts the part and which side of the segment that is, with the
    /// points and normal in the object's frame. `None` when the probe does not reach the part.
    pub fn contact(
        &mut self,
        segment: SegmentId,
        level: JointLevel,
        k: usize,
        to_object: &Isometry3<f64>,
    ) -> Option<Contact> {
        let geometry = &self.hand.segments[segment];
        let part = self.obstacles[k].geometry;
        self.pairs.clear();
        part.tree.intersecting_pairs(
            &geometry.probe_tree,
            to_object,
            &mut self.pairs,
            &mut self.stats,
        );
        if self.pairs.is_empty() {
            return None;
        }
        // The points come from at most CROSSING_PAIRS pairs spread evenly over the list (a
        // probe pressed onto a fine mesh cuts hundreds of triangles, and only MAX_CONTACT_POINTS
        // points are kept); the normal from every probe triangle that touches.
        let mut points = Vec::new();
        let stride = self.pairs.len().div_ceil(CROSSING_PAIRS);
        for &pair in self.pairs.iter().step_by(stride) {
            pair_crossings(&geometry.probe, &part.mesh, to_object, pair, &mut points);
        }
        let mut seen: Vec<u32> = self.pairs.iter().map(|&[_, probe]| probe).collect();
        seen.sort_unstable();
        seen.dedup();
        let normal: Vector3<f64> = seen
            .iter()
            .map(|&t| geometry.probe_normals[t as usize])
            .sum();
        if points.is_empty() {
            // Only coplanar pairs: fall back to the touching probe triangles' centroids.
            points = seen
                .iter()
                .map(|&t| {
                    let [a, b, c] = geometry.probe.triangle(t as usize);
                    to_object * Point3::from((a.coords + b.coords + c.coords) / 3.0)
                })
                .collect();
        }
        thin_out(&mut points, MAX_CONTACT_POINTS);
        let local = Unit::try_new(normal, 1e-12)?;
        Some(Contact {
            points,
            normal: to_object.rotation * local,
            side: side_of(&local, level),
        })
    }

    /// True when no segment of the hand at `root`, with the segment poses `local` (root frame)
    /// of its valid flex values, intersects any obstacle (the held part, moving with the root,
    /// cannot).
    pub fn hand_is_free(&mut self, root: &Isometry3<f64>, local: &[Isometry3<f64>]) -> bool {
        local.iter().enumerate().all(|(s, pose)| {
            self.collisions(
                s,
                &SegmentPlacement {
                    root: *root,
                    local: *pose,
                    flex_valid: true,
                },
            )
            .is_empty()
        })
    }
}

/// True when the segment's bounding sphere (segment frame, placed by `to_object`) and the part's
/// (object frame) overlap.
fn spheres_overlap(
    to_object: &Isometry3<f64>,
    segment: (Point3<f64>, f64),
    part: (Point3<f64>, f64),
) -> bool {
    (to_object * segment.0 - part.0).norm() <= segment.1 + part.1
}

/// Which side of a segment an outward normal (segment frame) points to.
fn side_of(normal: &Vector3<f64>, level: JointLevel) -> ContactSide {
    if normal.z > 0.5 {
        ContactSide::Dorsal
    } else if level == JointLevel::Outer && normal.y > 0.5 {
        ContactSide::Tip
    } else if -normal.z >= normal.x.abs() {
        ContactSide::Palmar
    } else {
        ContactSide::Lateral
    }
}

/// Appends the points where the edges of a cut pair of triangles, `[part, probe]`, cross the
/// other triangle, in the object's frame (the probe placed there by `to_object`).
fn pair_crossings(
    probe: &TriMesh,
    part: &TriMesh,
    to_object: &Isometry3<f64>,
    [part_triangle, probe_triangle]: [u32; 2],
    out: &mut Vec<Point3<f64>>,
) {
    let probe_corners = probe
        .triangle(probe_triangle as usize)
        .map(|p| to_object * p);
    let part_corners = part.triangle(part_triangle as usize);
    triangle_crossings(&probe_corners, &part_corners, out);
    triangle_crossings(&part_corners, &probe_corners, out);
}

/// Appends the points where the edges of triangle `a` cross triangle `b`.
fn triangle_crossings(a: &[Point3<f64>; 3], b: &[Point3<f64>; 3], out: &mut Vec<Point3<f64>>) {
    for i in 0..3 {
        if let Some(p) = segment_triangle(&a[i], &a[(i + 1) % 3], b) {
            out.push(p);
        }
    }
}

/// Where the segment `p`–`q` crosses triangle `t` (Möller–Trumbore), if it does; segments in
/// the triangle's plane give none.
fn segment_triangle(p: &Point3<f64>, q: &Point3<f64>, t: &[Point3<f64>; 3]) -> Option<Point3<f64>> {
    let d = q - p;
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let h = d.cross(&e2);
    let det = e1.dot(&h);
    // |det| <= 1e-14 |e1| |e2| |d|, squared (no square roots).
    if det * det <= 1e-28 * e1.norm_squared() * e2.norm_squared() * d.norm_squared() {
        return None;
    }
    let s = p - t[0];
    let u = s.dot(&h) / det;
    let qv = s.cross(&e1);
    let v = d.dot(&qv) / det;
    let along = e2.dot(&qv) / det;
    ((0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&along))
        .then(|| p + d * along)
}

/// Keeps at most `max` points, evenly spread over the list.
fn thin_out(points: &mut Vec<Point3<f64>>, max: usize) {
    if points.len() > max {
        let step = points.len() as f64 / max as f64;
        *points = (0..max)
            .map(|i| points[(i as f64 * step) as usize])
            .collect();
    }
}

fn mean_vertex(mesh: &TriMesh) -> Point3<f64> {
    let sum = mesh
        .vertices()
        .iter()
        .fold(Vector3::zeros(), |acc, v| acc + v.coords);
    Point3::from(sum / mesh.vertices().len() as f64)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::FRAC_PI_2;

    use nalgebra::{Translation3, UnitQuaternion};

    use super::*;
    use crate::geometry::{bounding_box_of, shapes};
    use crate::grasping::model::tests::right_hand;

    #[test]
    fn a_probe_sunk_into_a_fine_mesh_keeps_an_even_spread_of_its_crossings() {
        // The palm's probe sunk 4 mm into the outer side of a finely tessellated torus (a tube
        // of 5 cm radius, 72,000 triangles) cuts hundreds of triangle pairs. The contact's points
        // must be crossings of those pairs (all of them computed here), spread over the whole
        // patch, and its normal must point from the palm towards the torus.
        let (margin, sink) = (0.008, 0.004);
        let model = right_hand();
        let hand =
            HandGeometry::new(&model, margin, crate::collision::orientation::DEFAULT_K).unwrap();
        let palm = 0;
        let geometry = &hand.segments[palm];
        let lowest = geometry
            .probe
            .vertices()
            .iter()
            .map(|v| v.z)
            .fold(f64::MAX, f64::min);
        let centre = geometry.bound.0;
        let (major, minor) = (0.3, 0.05);
        let part = PartGeometry::new(shapes::torus(major, minor, 600, 60));
        // The palm's -z faces the torus's axis (object -x); the probe's lowest point is `sink`
        // inside the tube's outermost circle.
        let to_object = Isometry3::from_parts(
            Translation3::new(major + minor - sink - lowest, -centre.y, centre.x),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2),
        );
        let obstacles = [Obstacle {
            part: 0,
            geometry: &part,
            pose: Isometry3::identity(),
        }];
        let mut collider = SceneCollider::new(&hand, &obstacles, None);
        let contact = collider
            .contact(palm, model.segments()[palm].level, 0, &to_object)
            .expect("the probe cuts the torus");

        let mut pairs = Vec::new();
        part.tree.intersecting_pairs(
            &geometry.probe_tree,
            &to_object,
            &mut pairs,
            &mut QueryStats::default(),
        );
        assert!(pairs.len() > CROSSING_PAIRS, "{} pairs", pairs.len());
        let mut every = Vec::new();
        for &pair in &pairs {
            pair_crossings(&geometry.probe, &part.mesh, &to_object, pair, &mut every);
        }
        assert_eq!(contact.points.len(), MAX_CONTACT_POINTS);
        assert!(contact.points.iter().all(|p| every.contains(p)));
        // Spread: the patch's extent across the tube's side (y and z; x is the depth) cut into
        // 6 x 6 cells; the kept points must reach nine in ten of the cells that any crossing reaches.
        let (lo, hi) = bounding_box_of(&every);
        let cell = |p: &Point3<f64>| {
            let at = |axis: usize| {
                let t = (p[axis] - lo[axis]) / (hi[axis] - lo[axis]).max(f64::MIN_POSITIVE);
                ((t * 6.0) as usize).min(5)
            };
            (at(1), at(2))
        };
        let cells = |points: &[Point3<f64>]| {
            let mut cells: Vec<_> = points.iter().map(cell).collect();
            cells.sort_unstable();
            cells.dedup();
            cells.len()
        };
        let (reached, all) = (cells(&contact.points), cells(&every));
        assert!(
            reached * 10 >= all * 9,
            "the points reach {reached} of the {all} cells the crossings reach"
        );
        assert!(contact.normal.x < -0.5, "normal {:?}", contact.normal);
    }
}

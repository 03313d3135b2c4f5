//! What B11 checks and reports of one method's run over one pose sequence: its time per query,
//! its distances against the reference peer's pose by pose, and whether its closest points lie
//! on the triangles it names and as far apart as the distance it answers.

use nalgebra::{Isometry3, Point3};
use serde::Serialize;
use vas_server::collision::QueryStats;
use vas_server::geometry::TriMesh;

/// One pose's answer of one method, both points in A's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Answer {
    /// The least distance (0 when the meshes touch or intersect).
    pub distance: f64,
    /// The closest point on A.
    pub on_a: Point3<f64>,
    /// The closest point on B.
    pub on_b: Point3<f64>,
    /// The triangles of A and B the points lie on, where the method names them.
    pub triangles: [Option<u32>; 2],
}

/// One method's run over one pose sequence: answers of its first round, each pose's fastest
/// time, and the DOP-tree's counters (none for the peers).
#[derive(Debug, Clone)]
pub struct Run {
    /// Method name ("doptree", "doptree-cold", "coal", "fcl").
    pub method: &'static str,
    /// One answer per pose.
    pub answers: Vec<Answer>,
    /// Each pose's fastest time over the rounds, nanoseconds.
    pub nanoseconds: Vec<f64>,
    /// Counters summed over the first round's poses.
    pub stats: Option<QueryStats>,
}

/// Mean DOP-tree counters per query.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct StatsMeans {
    /// Bounding-volume tests.
    pub bv_tests: f64,
    /// Node bounds of B re-aligned into A's frame.
    pub realignments: f64,
    /// Node pairs opened.
    pub nodes_visited: f64,
    /// Exact triangle-triangle distances.
    pub tri_tests: f64,
}

/// One row of B11: one method on one pose sequence of one pair.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// The pair's label.
    pub pair: String,
    /// "coherent" (B1's tumbling poses) or "random" (B2's).
    pub procedure: &'static str,
    /// The tumbling distance d (none for random poses).
    pub distance: Option<f64>,
    /// Method name.
    pub method: String,
    /// Poses measured.
    pub poses: usize,
    /// Fraction of poses at which the method found the meshes touching (distance 0).
    pub touching: f64,
    /// Mean time per query, microseconds.
    pub mean_us: f64,
    /// Median time per query, microseconds.
    pub median_us: f64,
    /// 99th percentile of the time per query, microseconds.
    pub p99_us: f64,
    /// Largest time of one query, microseconds.
    pub max_us: f64,
    /// Largest difference of the distance from the reference peer's at the same pose.
    pub max_difference: Option<f64>,
    /// The largest difference the bar allows: 1e-6 of the meshes' size (the larger diagonal of
    /// their bounding boxes).
    pub tolerance: f64,
    /// Largest error of the closest points where the meshes are apart: their distance from the
    /// triangles named, or the difference of their distance apart from the distance answered,
    /// whichever is larger (touching, the peers stop at the first contact, whose points are not
    /// closest points).
    pub point_error: f64,
    /// Mean counters per query (the DOP-tree's).
    pub stats: Option<StatsMeans>,
    /// Mean time over the reference peer's mean time at the same poses.
    pub reference_ratio: Option<f64>,
}

/// The row of `run` on `poses` of `a` and `b`, compared with `reference` (the reference peer's
/// run on the same poses) where there is one; `tolerance` is the bar's for these meshes.
pub fn summarise(
    run: &Run,
    reference: Option<&Run>,
    (a, b): (&TriMesh, &TriMesh),
    poses: &[Isometry3<f64>],
    (pair, procedure, distance): (&str, &'static str, Option<f64>),
    tolerance: f64,
) -> Row {
    let n = run.answers.len().max(1) as f64;
    let mut micros: Vec<f64> = run.nanoseconds.iter().map(|ns| ns * 1e-3).collect();
    micros.sort_by(f64::total_cmp);
    let at = |fraction: f64| micros[((micros.len() - 1) as f64 * fraction) as usize];
    let mean_us = micros.iter().sum::<f64>() / n;
    let reference_mean = reference.map(|r| r.nanoseconds.iter().sum::<f64>() * 1e-3 / n);
    let max_difference = reference.map(|r| {
        run.answers
            .iter()
            .zip(&r.answers)
            .map(|(own, theirs)| (own.distance - theirs.distance).abs())
            .fold(0.0, f64::max)
    });
    let point_error = run
        .answers
        .iter()
        .zip(poses)
        .filter(|(answer, _)| answer.distance > 0.0)
        .map(|(answer, pose)| point_error(answer, a, b, pose))
        .fold(0.0, f64::max);
    Row {
        pair: pair.to_owned(),
        procedure,
        distance,
        method: run.method.to_owned(),
        poses: run.answers.len(),
        touching: run.answers.iter().filter(|a| a.distance <= 0.0).count() as f64 / n,
        mean_us,
        median_us: at(0.5),
        p99_us: at(0.99),
        max_us: at(1.0),
        max_difference,
        tolerance,
        point_error,
        stats: run.stats.map(|s| StatsMeans {
            bv_tests: s.bv_tests as f64 / n,
            realignments: s.realignments as f64 / n,
            nodes_visited: s.nodes_visited as f64 / n,
            tri_tests: s.tri_tests as f64 / n,
        }),
        reference_ratio: reference_mean.map(|m| mean_us / m),
    }
}

/// How far `answer`'s points are from being right at B's `pose`: from the triangles they name
/// (infinite when one is not named), and apart by other than the distance answered.
fn point_error(answer: &Answer, a: &TriMesh, b: &TriMesh, pose: &Isometry3<f64>) -> f64 {
    let [Some(ta), Some(tb)] = answer.triangles else {
        return f64::INFINITY;
    };
    let (ta, tb) = (ta as usize, tb as usize);
    if ta >= a.triangles().len() || tb >= b.triangles().len() {
        return f64::INFINITY;
    }
    let on_a = point_triangle_distance(&answer.on_a, &a.triangle(ta));
    let on_b =
        point_triangle_distance(&pose.inverse_transform_point(&answer.on_b), &b.triangle(tb));
    let apart = ((answer.on_a - answer.on_b).norm() - answer.distance).abs();
    on_a.max(on_b).max(apart)
}

/// The distance of `p` from triangle `[a, b, c]` (Ericson's regions; a degenerate triangle is
/// measured by its edges).
pub fn point_triangle_distance(p: &Point3<f64>, [a, b, c]: &[Point3<f64>; 3]) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    let (va, vb, vc) = (d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2);
    let inside = va > 0.0 && vb > 0.0 && vc > 0.0;
    if inside {
        let sum = va + vb + vc;
        let closest = a + ab * (vb / sum) + ac * (vc / sum);
        return (p - closest).norm();
    }
    [(a, b), (b, c), (c, a)]
        .into_iter()
        .map(|(from, to)| point_segment_distance(p, from, to))
        .fold(f64::INFINITY, f64::min)
}

/// The distance of `p` from the segment `from`-`to`.
fn point_segment_distance(p: &Point3<f64>, from: &Point3<f64>, to: &Point3<f64>) -> f64 {
    let along = to - from;
    let length_squared = along.norm_squared();
    let t = if length_squared > 0.0 {
        ((p - from).dot(&along) / length_squared).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (from + along * t)).norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_are_measured_to_the_face_its_edges_and_its_corners() {
        let triangle = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(2.0, 0.0, 0.0),
            Point3::new(0.0, 2.0, 0.0),
        ];
        let distance = |x, y, z| point_triangle_distance(&Point3::new(x, y, z), &triangle);
        assert!((distance(0.5, 0.5, 3.0) - 3.0).abs() < 1e-12, "face");
        assert!((distance(1.0, -1.0, 0.0) - 1.0).abs() < 1e-12, "edge");
        assert!((distance(-3.0, -4.0, 0.0) - 5.0).abs() < 1e-12, "corner");
        assert!(
            (distance(2.0, 2.0, 0.0) - 2f64.sqrt()).abs() < 1e-12,
            "hypotenuse"
        );
        let flat = [triangle[0], triangle[1], Point3::new(1.0, 0.0, 0.0)];
        let on_flat = point_triangle_distance(&Point3::new(1.0, 1.0, 0.0), &flat);
        assert!((on_flat - 1.0).abs() < 1e-12, "a degenerate triangle");
    }
}

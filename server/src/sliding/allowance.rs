//! Slide-in units (the paper's future work): parts whose surfaces overlap by design in their final
//! position, like a car radio clipped into its slot, get a per-pair allowance. An intersecting
//! triangle pair of such a pair of parts counts as a collision only when it is deeper than the
//! allowance.
//!
//! The depth of a triangle pair is its separation distance by the separating-axis theorem: the
//! shortest translation, along any of the eleven candidate axes (both face normals and the nine
//! edge-edge cross products), that pulls the two triangles apart. For two faces that interfere by
//! a small offset it is that offset; for a part pushed through a wall it grows with the push.

use nalgebra::Vector3;

use crate::geometry::Point;

/// The separation depth of two triangles: zero when they are apart (or merely touch), else the
/// length of the shortest translation along a candidate axis that separates them.
pub fn triangle_pair_depth(a: &[Point; 3], b: &[Point; 3]) -> f64 {
    let edges = |t: &[Point; 3]| [t[1] - t[0], t[2] - t[1], t[0] - t[2]];
    let (ea, eb) = (edges(a), edges(b));
    let mut axes: [Vector3<f64>; 11] = [Vector3::zeros(); 11];
    axes[0] = ea[0].cross(&ea[1]);
    axes[1] = eb[0].cross(&eb[1]);
    for (i, u) in ea.iter().enumerate() {
        for (j, v) in eb.iter().enumerate() {
            axes[2 + 3 * i + j] = u.cross(v);
        }
    }
    let scale = ea
        .iter()
        .chain(eb.iter())
        .map(|e| e.norm_squared())
        .fold(0.0_f64, f64::max);
    let mut depth = f64::INFINITY;
    for axis in &axes {
        let length_squared = axis.norm_squared();
        // Axes from (nearly) parallel edges carry no information.
        if length_squared <= 1e-20 * scale * scale {
            continue;
        }
        let (a_lo, a_hi) = extent(a, axis);
        let (b_lo, b_hi) = extent(b, axis);
        let overlap = (a_hi - b_lo).min(b_hi - a_lo);
        if overlap <= 0.0 {
            return 0.0;
        }
        depth = depth.min(overlap / length_squared.sqrt());
    }
    if depth.is_finite() { depth } else { 0.0 }
}

/// The interval a triangle's projection onto `axis` covers.
fn extent(t: &[Point; 3], axis: &Vector3<f64>) -> (f64, f64) {
    let d = t.map(|p| p.coords.dot(axis));
    (d[0].min(d[1]).min(d[2]), d[0].max(d[1]).max(d[2]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64, z: f64) -> Point {
        Point::new(x, y, z)
    }

    #[test]
    fn separated_triangles_have_no_depth() {
        let a = [p(0., 0., 0.), p(1., 0., 0.), p(0., 1., 0.)];
        let b = [p(0., 0., 0.5), p(1., 0., 0.5), p(0., 1., 0.5)];
        assert_eq!(triangle_pair_depth(&a, &b), 0.0);
    }

    #[test]
    fn a_face_interfering_by_an_offset_has_that_depth() {
        // A wall in the plane x = 0 (material for x > 0 ... up to the wall's own extent) crossed
        // by a slab face standing 0.002 into it along x.
        let wall = [p(0., -1., -1.), p(0., 1., -1.), p(0., 0., 1.)];
        let face = [p(-1., 0., 0.), p(0.002, 0.3, 0.), p(0.002, -0.3, 0.)];
        let depth = triangle_pair_depth(&wall, &face);
        assert!((depth - 0.002).abs() < 1e-12, "{depth}");
    }

    #[test]
    fn depth_grows_with_the_push() {
        let wall = [p(0., -1., -1.), p(0., 1., -1.), p(0., 0., 1.)];
        let shallow = [p(-1., 0., 0.), p(0.01, 0.2, 0.), p(0.01, -0.2, 0.)];
        let deep = [p(-1., 0., 0.), p(0.3, 0.2, 0.), p(0.3, -0.2, 0.)];
        assert!(triangle_pair_depth(&wall, &deep) > 10.0 * triangle_pair_depth(&wall, &shallow));
    }
}

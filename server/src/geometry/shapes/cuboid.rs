//! A closed box of near-square triangles.

use nalgebra::Vector3;

use super::mesh_builder::MeshBuilder;
use super::resolution::closest_resolution;
use crate::geometry::mesh::{Point, TriMesh};

pub(super) fn build_cuboid(size: Vector3<f64>, target: usize) -> TriMesh {
    // Cells along the longest edge; the other edges get about as many per length, rounded down
    // or up (both are candidates, which lets the count come close to any target).
    let longest = size.imax();
    let cells = move |n: usize| {
        let spacing = size[longest] / n as f64;
        let per_axis = size.map(|s| {
            let exact = (s / spacing).clamp(1.0, target.max(1) as f64);
            [exact.floor() as usize, exact.ceil() as usize]
        });
        (0..4).map(move |choice| {
            let mut c = Vector3::new(per_axis.x[0], per_axis.y[0], per_axis.z[0]);
            let others = [(longest + 1) % 3, (longest + 2) % 3];
            c[others[0]] = per_axis[others[0]][choice & 1];
            c[others[1]] = per_axis[others[1]][choice >> 1];
            c[longest] = n;
            c
        })
    };
    let count = |c: Vector3<usize>| 4 * (c.x * c.y + c.y * c.z + c.z * c.x);
    let c = closest_resolution(
        target,
        (1usize..).flat_map(|n| cells(n).map(move |c| (c, count(c)))),
    );
    let h = size / 2.0;
    let (ex, ey, ez) = (
        Vector3::x() * size.x,
        Vector3::y() * size.y,
        Vector3::z() * size.z,
    );
    let corner = Point::from(-h);
    // Each face as (origin, u, v, cells along u, cells along v), with u x v pointing outwards.
    let faces = [
        (corner + ez, ex, ey, c.x, c.y),
        (corner, ey, ex, c.y, c.x),
        (corner + ex, ey, ez, c.y, c.z),
        (corner, ez, ey, c.z, c.y),
        (corner + ey, ez, ex, c.z, c.x),
        (corner, ex, ez, c.x, c.z),
    ];
    let mut builder = MeshBuilder::default();
    for (origin, u, v, nu, nv) in faces {
        let rows: Vec<Vec<u32>> = (0..=nv)
            .map(|j| {
                builder.row(
                    (0..=nu)
                        .map(|i| origin + u * (i as f64 / nu as f64) + v * (j as f64 / nv as f64)),
                )
            })
            .collect();
        for pair in rows.windows(2) {
            builder.strip(&pair[0], &pair[1], false);
        }
    }
    // The faces were built apart; welding joins them along the box's edges.
    builder.finish_welded(size.max() * 1e-9)
}

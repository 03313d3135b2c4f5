//! Plates with a round hole: the open sheet and the block with a through hole.

use std::f64::consts::{FRAC_PI_4, TAU};

use super::mesh_builder::MeshBuilder;
use super::resolution::{closest_resolution, steps};
use crate::geometry::mesh::{Point, TriMesh};

/// Resolution of a square plate with a round hole: `sides` segments per edge of the square
/// (4 * sides around the hole) and `rings` rings between the hole and the square.
#[derive(Debug, Clone, Copy)]
pub(super) struct PlateResolution {
    sides: usize,
    rings: usize,
}

impl PlateResolution {
    pub(super) fn new(width: f64, hole_radius: f64, sides: usize, cap: usize) -> Self {
        let spacing = width / sides as f64;
        // Mean distance from the hole to the square, between the edge midpoints and the corners.
        let gap = width / 2.0 * (1.0 + std::f64::consts::SQRT_2) / 2.0 - hole_radius;
        PlateResolution {
            sides,
            rings: steps(gap, spacing, cap),
        }
    }

    pub(super) fn segments(self) -> usize {
        4 * self.sides
    }

    /// The square's boundary, counter-clockwise from the corner (w/2, -w/2), `sides` points per
    /// edge, and the hole's boundary: a regular polygon at matching angles (vertex k at
    /// -45° + 360° k / segments, so one vertex lies at 0°).
    pub(super) fn outlines(self, width: f64, hole_radius: f64) -> (Vec<[f64; 2]>, Vec<[f64; 2]>) {
        let h = width / 2.0;
        let corners = [[h, -h], [h, h], [-h, h], [-h, -h], [h, -h]];
        let square = (0..self.segments())
            .map(|k| {
                let (edge, t) = (k / self.sides, (k % self.sides) as f64 / self.sides as f64);
                let [a, b] = [corners[edge], corners[edge + 1]];
                [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
            })
            .collect();
        let hole = (0..self.segments())
            .map(|k| {
                let angle = -FRAC_PI_4 + TAU * k as f64 / self.segments() as f64;
                [hole_radius * angle.cos(), hole_radius * angle.sin()]
            })
            .collect();
        (square, hole)
    }
}

/// Adds the flat ring between `square` and `hole` at height `z` to `builder`, reusing the given
/// boundary rows (so that the plate joins the walls built on them). Normals point up (+z) when
/// `up`, else down.
pub(super) fn plate(
    builder: &mut MeshBuilder,
    (square, hole): (&[[f64; 2]], &[[f64; 2]]),
    (square_row, hole_row): (&[u32], &[u32]),
    z: f64,
    rings: usize,
    up: bool,
) {
    let mut rows = vec![square_row.to_vec()];
    for k in 1..rings {
        let t = k as f64 / rings as f64;
        rows.push(
            builder.row(
                square.iter().zip(hole).map(|(s, c)| {
                    Point::new(s[0] + (c[0] - s[0]) * t, s[1] + (c[1] - s[1]) * t, z)
                }),
            ),
        );
    }
    rows.push(hole_row.to_vec());
    for pair in rows.windows(2) {
        // Rows run outside-in: a counter-clockwise row followed by the next one inwards faces up.
        if up {
            builder.strip(&pair[0], &pair[1], true);
        } else {
            builder.strip(&pair[1], &pair[0], true);
        }
    }
}

pub(super) fn build_sheet_with_hole(width: f64, hole_radius: f64, target: usize) -> TriMesh {
    let resolution = closest_resolution(
        target,
        (1usize..).map(|sides| {
            let r = PlateResolution::new(width, hole_radius, sides, target);
            (r, 2 * r.segments() * r.rings)
        }),
    );
    let (square, hole) = resolution.outlines(width, hole_radius);
    let mut builder = MeshBuilder::default();
    let at_zero = |o: &[f64; 2]| Point::new(o[0], o[1], 0.0);
    let square_row = builder.row(square.iter().map(at_zero));
    let hole_row = builder.row(hole.iter().map(at_zero));
    plate(
        &mut builder,
        (&square, &hole),
        (&square_row, &hole_row),
        0.0,
        resolution.rings,
        true,
    );
    builder.finish()
}

pub(super) fn build_box_with_hole(
    width: f64,
    height: f64,
    hole_radius: f64,
    target: usize,
) -> TriMesh {
    // Rows of the side walls (spacing of the square's edge) and of the bore (spacing of the hole).
    let wall_bands = |r: PlateResolution| {
        (
            steps(height, width / r.sides as f64, target),
            steps(height, TAU * hole_radius / r.segments() as f64, target),
        )
    };
    let resolution = closest_resolution(
        target,
        (1usize..).map(|sides| {
            let r = PlateResolution::new(width, hole_radius, sides, target);
            let (outer, bore) = wall_bands(r);
            (r, 2 * r.segments() * (2 * r.rings + outer + bore))
        }),
    );
    let (outer_bands, bore_bands) = wall_bands(resolution);
    let (square, hole) = resolution.outlines(width, hole_radius);
    let half = height / 2.0;
    let mut builder = MeshBuilder::default();
    let level = |builder: &mut MeshBuilder, outline: &[[f64; 2]], t: f64| {
        builder.row(
            outline
                .iter()
                .map(|o| Point::new(o[0], o[1], -half + height * t)),
        )
    };
    // Outer walls bottom-up (counter-clockwise outline going up faces outwards).
    let outer: Vec<Vec<u32>> = (0..=outer_bands)
        .map(|k| level(&mut builder, &square, k as f64 / outer_bands as f64))
        .collect();
    for pair in outer.windows(2) {
        builder.strip(&pair[0], &pair[1], true);
    }
    // The bore top-down, which faces into the hole.
    let bore: Vec<Vec<u32>> = (0..=bore_bands)
        .map(|k| level(&mut builder, &hole, 1.0 - k as f64 / bore_bands as f64))
        .collect();
    for pair in bore.windows(2) {
        builder.strip(&pair[0], &pair[1], true);
    }
    let outlines = (square.as_slice(), hole.as_slice());
    let top = (outer[outer_bands].as_slice(), bore[0].as_slice());
    plate(&mut builder, outlines, top, half, resolution.rings, true);
    let bottom = (outer[0].as_slice(), bore[bore_bands].as_slice());
    plate(
        &mut builder,
        outlines,
        bottom,
        -half,
        resolution.rings,
        false,
    );
    builder.finish()
}

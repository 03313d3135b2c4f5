//! Shapes of revolution about z: sphere, torus, hyperboloid, cylinder and pipe.

use std::f64::consts::{PI, TAU};

use super::mesh_builder::MeshBuilder;
use super::resolution::{closest_resolution, sphere_resolution, steps};
use crate::geometry::mesh::TriMesh;

pub(super) fn build_sphere(radius: f64, target: usize) -> TriMesh {
    let (segments, stacks) = sphere_resolution(target);
    let profile: Vec<[f64; 2]> = (0..=stacks)
        .map(|k| {
            let latitude = -PI / 2.0 + PI * k as f64 / stacks as f64;
            // The poles lie exactly on the axis, so that they become single vertices.
            let r = if k == 0 || k == stacks {
                0.0
            } else {
                radius * latitude.cos()
            };
            [r, radius * latitude.sin()]
        })
        .collect();
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, false, segments);
    builder.finish()
}

pub(super) fn build_torus(major_radius: f64, minor_radius: f64, nu: usize, nv: usize) -> TriMesh {
    let profile: Vec<[f64; 2]> = (0..nv)
        .map(|k| {
            let v = TAU * k as f64 / nv as f64;
            [
                major_radius + minor_radius * v.cos(),
                minor_radius * v.sin(),
            ]
        })
        .collect();
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, true, nu);
    builder.finish()
}

pub(super) fn build_hyperboloid(
    waist_radius: f64,
    end_radius: f64,
    height: f64,
    target: usize,
) -> TriMesh {
    let half = height / 2.0;
    // r(z) = w * sqrt(1 + (z / c)^2), with c chosen so that r(±h/2) is the end radius.
    let c = half / ((end_radius / waist_radius).powi(2) - 1.0).sqrt();
    let radius_at = |z: f64| waist_radius * (1.0 + (z / c).powi(2)).sqrt();
    // The profile's length, estimated by the polyline through the ends and the waist.
    let profile_length = 2.0 * half.hypot(end_radius - waist_radius);
    let mean_circumference = PI * (waist_radius + end_radius);
    let bands =
        |segments: usize| steps(profile_length, mean_circumference / segments as f64, target);
    let segments = closest_resolution(target, (3usize..).map(|n| (n, 2 * n * bands(n))));
    let rings = bands(segments);
    let profile: Vec<[f64; 2]> = (0..=rings)
        .map(|k| {
            let z = -half + height * k as f64 / rings as f64;
            [radius_at(z), z]
        })
        .collect();
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, false, segments);
    builder.finish()
}

pub(super) fn build_cylinder(radius: f64, height: f64, target: usize) -> TriMesh {
    let resolution = |segments: usize| {
        let spacing = TAU * radius / segments as f64;
        (
            steps(radius, spacing, target),
            steps(height, spacing, target),
        )
    };
    // Each cap: a fan and (rings - 1) bands; the side: `bands` bands.
    let count = |n: usize, (rings, bands): (usize, usize)| n * (2 * (2 * rings - 1) + 2 * bands);
    let segments = closest_resolution(target, (3usize..).map(|n| (n, count(n, resolution(n)))));
    let (rings, bands) = resolution(segments);
    let half = height / 2.0;
    let mut profile = Vec::with_capacity(2 * rings + bands + 1);
    profile.extend((0..=rings).map(|k| [radius * k as f64 / rings as f64, -half]));
    profile.extend((1..=bands).map(|k| [radius, -half + height * k as f64 / bands as f64]));
    profile.extend((1..=rings).map(|k| [radius * (rings - k) as f64 / rings as f64, half]));
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, false, segments);
    builder.finish()
}

pub(super) fn build_pipe(
    inner_radius: f64,
    outer_radius: f64,
    length: f64,
    target: usize,
) -> TriMesh {
    let resolution = |segments: usize| {
        let spacing = TAU * outer_radius / segments as f64;
        (
            steps(length, spacing, target),
            steps(outer_radius - inner_radius, spacing, target),
        )
    };
    let segments = closest_resolution(
        target,
        (3usize..).map(|n| {
            let (bands, rings) = resolution(n);
            (n, 4 * n * (bands + rings))
        }),
    );
    let (bands, rings) = resolution(segments);
    let half = length / 2.0;
    let wall = outer_radius - inner_radius;
    // A closed loop in the (r, z) half-plane, counter-clockwise so that normals point out of the
    // material: up the outer wall, in across the top, down the bore, out across the bottom.
    let mut profile = Vec::with_capacity(2 * (bands + rings));
    profile.extend((0..bands).map(|k| [outer_radius, -half + length * k as f64 / bands as f64]));
    profile.extend((0..rings).map(|k| [outer_radius - wall * k as f64 / rings as f64, half]));
    profile.extend((0..bands).map(|k| [inner_radius, half - length * k as f64 / bands as f64]));
    profile.extend((0..rings).map(|k| [inner_radius + wall * k as f64 / rings as f64, -half]));
    let mut builder = MeshBuilder::default();
    builder.revolve(&profile, true, segments);
    builder.finish()
}

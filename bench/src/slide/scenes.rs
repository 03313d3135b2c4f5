//! The scripted sliding scenes of B5 and of its tests: a grasped part, static obstacles, a start
//! pose and the ghost's path.

use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use nalgebra::{Translation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use vas_server::geometry::{TriMesh, shapes};
use vas_server::scene::Scene;
use vas_server::sliding::{Pose, SlideParams, SlidingMetaphor};

/// One obstacle of a scenario.
#[derive(Debug, Clone)]
pub struct ScenarioObstacle {
    /// The mesh, in its own frame.
    pub mesh: Arc<TriMesh>,
    /// Its pose in the world.
    pub pose: Pose,
    /// The slide-in allowance against the part, if the two form a slide-in unit.
    pub allowance: Option<f64>,
    /// What the penetration oracle tests instead of `mesh` (for slide-in units: the obstacle
    /// with the allowance taken away); `None` tests `mesh` itself.
    pub oracle_mesh: Option<Arc<TriMesh>>,
}

impl ScenarioObstacle {
    /// A plain obstacle at `pose`.
    pub fn new(mesh: TriMesh, pose: Pose) -> Self {
        ScenarioObstacle {
            mesh: Arc::new(mesh),
            pose,
            allowance: None,
            oracle_mesh: None,
        }
    }
}

/// A grasped part, its surroundings and the ghost's scripted path.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// Name in reports.
    pub name: String,
    /// The grasped part, in its own frame.
    pub part: Arc<TriMesh>,
    /// The static obstacles.
    pub obstacles: Vec<ScenarioObstacle>,
    /// The part's pose when grasped (free).
    pub start: Pose,
    /// The ghost's pose (of the part's mesh frame) at each frame.
    pub ghosts: Vec<Pose>,
    /// Sliding parameters.
    pub params: SlideParams,
}

/// A copy of `mesh` with the winding of a random half of its triangles reversed (fixed seed):
/// normals that cannot be trusted, as in CAD data.
pub fn scramble_winding(mesh: &TriMesh, seed: u64) -> TriMesh {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let triangles = mesh
        .triangles()
        .iter()
        .map(|&[a, b, c]| {
            if rng.random::<bool>() {
                [a, c, b]
            } else {
                [a, b, c]
            }
        })
        .collect();
    TriMesh::new(mesh.vertices().to_vec(), triangles)
        .expect("reversing winding keeps a valid mesh valid")
        .0
}

/// `count` ghost poses from `from` to `to` (excluded, included), translation linear, rotation
/// along the great arc.
pub fn straight_path(from: &Pose, to: &Pose, count: usize) -> Vec<Pose> {
    (1..=count)
        .map(|i| vas_server::sliding::motion::interpolate(from, to, i as f64 / count as f64))
        .collect()
}

fn at(x: f64, y: f64, z: f64) -> Pose {
    Pose::translation(x, y, z)
}

fn params(metaphor: SlidingMetaphor) -> SlideParams {
    SlideParams {
        metaphor,
        ..SlideParams::default()
    }
}

/// A 10 cm cube of about `triangles` triangles starting 5 cm above a floor slab (top at z = 0),
/// with optional walls at x = 0.3 and y = 0.3; the ghost is dragged diagonally to `ghost_end`.
pub fn block_scene(
    walls: usize,
    ghost_end: [f64; 3],
    metaphor: SlidingMetaphor,
    triangles: usize,
) -> Scenario {
    let slab = |size: [f64; 3]| shapes::cuboid(Vector3::from(size), 200);
    let mut obstacles = vec![ScenarioObstacle::new(
        slab([1.0, 1.0, 0.05]),
        at(0.0, 0.0, -0.025),
    )];
    if walls >= 1 {
        obstacles.push(ScenarioObstacle::new(
            slab([0.05, 1.0, 0.5]),
            at(0.325, 0.0, 0.2),
        ));
    }
    if walls >= 2 {
        obstacles.push(ScenarioObstacle::new(
            slab([1.0, 0.05, 0.5]),
            at(0.0, 0.325, 0.2),
        ));
    }
    // Off round numbers, so that no frame of the path lands the block exactly touching the floor
    // or a wall: an exact touch is a rounding-level tie between any two collision tests.
    let start = at(0.0011, 0.0007, 0.1013);
    let [x, y, z] = ghost_end;
    Scenario {
        name: format!("block_{}", ["plane", "crease", "corner"][walls.min(2)]),
        part: Arc::new(shapes::cuboid(Vector3::new(0.1, 0.1, 0.1), triangles)),
        obstacles,
        start,
        ghosts: straight_path(&start, &at(x, y, z), 60),
        params: params(metaphor),
    }
}

/// Dimensions of the peg-in-hole scene, metres.
pub mod peg {
    /// Radius of the hole.
    pub const HOLE_RADIUS: f64 = 0.02;
    /// Radius of the peg: 1% radial clearance.
    pub const PEG_RADIUS: f64 = 0.99 * HOLE_RADIUS;
    /// Length of the peg.
    pub const PEG_LENGTH: f64 = 0.08;
    /// Height of the block; its top is at z = BLOCK_HEIGHT / 2.
    pub const BLOCK_HEIGHT: f64 = 0.06;
    /// The hole's bottom: the top of the floor plate under the block.
    pub const BOTTOM: f64 = -BLOCK_HEIGHT / 2.0;
    /// How far the ghost is off the hole's axis: 30 times the clearance.
    pub const MISALIGNMENT: f64 = 0.3 * HOLE_RADIUS;
}

/// A peg of about `triangles` triangles with 1% radial clearance in a blind hole, starting 1 mm
/// inside the hole; the ghost is pushed down to 5 mm below the bottom while it is off the hole's
/// axis by [`peg::MISALIGNMENT`], so the peg must slide down the hole's wall.
pub fn peg_in_hole(triangles: usize) -> Scenario {
    use peg::*;
    let block = shapes::box_with_hole(0.1, BLOCK_HEIGHT, HOLE_RADIUS, 4_000);
    let floor = shapes::cuboid(Vector3::new(0.2, 0.2, 0.02), 200);
    let centre_above_bottom = PEG_LENGTH / 2.0;
    let start = at(0.0, 0.0, BLOCK_HEIGHT / 2.0 - 0.001 + centre_above_bottom);
    let end = at(MISALIGNMENT, 0.0, BOTTOM - 0.005 + centre_above_bottom);
    let first = at(MISALIGNMENT, 0.0, start.translation.z);
    let mut ghosts = vec![first];
    ghosts.extend(straight_path(&first, &end, 300));
    Scenario {
        name: "peg_in_hole".into(),
        part: Arc::new(shapes::cylinder(PEG_RADIUS, PEG_LENGTH, triangles)),
        obstacles: vec![
            ScenarioObstacle::new(block, Pose::identity()),
            ScenarioObstacle::new(floor, at(0.0, 0.0, BOTTOM - 0.01)),
        ],
        start,
        ghosts,
        params: params(SlidingMetaphor::RubberBand),
    }
}

/// Dimensions of the pipe-through-sheet scene, metres.
pub mod pipe {
    /// Radius of the hole in the sheet.
    pub const HOLE_RADIUS: f64 = 0.05;
    /// Outer radius of the pipe: 10% clearance.
    pub const OUTER_RADIUS: f64 = 0.045;
    /// Length of the pipe.
    pub const LENGTH: f64 = 0.1;
    /// How far the ghost drifts off the hole's axis over the path: three times the clearance.
    pub const DRIFT: f64 = 0.015;
}

/// A pipe of about `triangles` triangles passed through a hole in an open sheet (z = 0) whose
/// triangles, like the pipe's, have scrambled winding. The ghost starts on the hole's axis 2 cm
/// away from the sheet (above it, or below with `from_below`) and drifts off the axis by
/// [`pipe::DRIFT`] while it travels through, so the pipe must slide along the hole's rim.
pub fn pipe_through_sheet(triangles: usize, from_below: bool) -> Scenario {
    use pipe::*;
    let side = if from_below { -1.0 } else { 1.0 };
    let sheet = scramble_winding(&shapes::sheet_with_hole(0.4, HOLE_RADIUS, 4_000), 7);
    let part = scramble_winding(&shapes::pipe(0.035, OUTER_RADIUS, LENGTH, triangles), 11);
    let start = at(0.0, 0.0, side * (0.02 + LENGTH / 2.0));
    let end = at(DRIFT, 0.0, -side * (0.03 + LENGTH / 2.0));
    Scenario {
        name: if from_below {
            "pipe_through_sheet_from_below"
        } else {
            "pipe_through_sheet"
        }
        .into(),
        part: Arc::new(part),
        obstacles: vec![ScenarioObstacle::new(sheet, Pose::identity())],
        start,
        ghosts: straight_path(&start, &end, 200),
        params: params(SlidingMetaphor::RubberBand),
    }
}

/// A scenario from a scene config: the movable part named `grasped` is grasped at its configured
/// pose, every part of interest to it is an obstacle, and `path` gives the ghost's poses from
/// the start pose.
pub fn scene_scenario(
    scene: &Scene,
    grasped: &str,
    path: impl FnOnce(&Pose) -> Vec<Pose>,
) -> Result<Scenario> {
    let index = scene
        .parts
        .iter()
        .position(|p| p.name == grasped)
        .with_context(|| format!("{}: no part named {grasped}", scene.source.display()))?;
    let part = &scene.parts[index];
    let params = scene.params.sliding.clone();
    let obstacles = (0..scene.parts.len())
        .filter(|&other| scene.pair_of_interest(index, other))
        .map(|other| {
            let obstacle = &scene.parts[other];
            ScenarioObstacle {
                mesh: obstacle.mesh.clone(),
                pose: obstacle.pose,
                allowance: params.allowance_between(&part.name, &obstacle.name),
                oracle_mesh: None,
            }
        })
        .collect();
    Ok(Scenario {
        name: format!("{} (config)", scene.name),
        part: part.mesh.clone(),
        obstacles,
        start: part.pose,
        ghosts: path(&part.pose),
        params,
    })
}

/// The config scenes the benchmark also runs, with their scripted ghost paths: the peg pushed
/// 2 mm into its hole on the axis, then 3 cm further while drifting off the axis by 30 times the
/// clearance; the pipe pushed through the sheet while drifting off the axis by three times the
/// clearance.
pub fn config_scenarios(configs: &Path) -> Result<Vec<Scenario>> {
    let peg = Scene::load(&configs.join("peg_in_hole.toml"))?;
    let peg = scene_scenario(&peg, "peg", |start| {
        let inside = Translation3::new(0.0, 0.0, -0.004) * start;
        let deep = Translation3::new(0.003, 0.0, -0.034) * start;
        let mut ghosts = straight_path(start, &inside, 20);
        ghosts.extend(straight_path(&inside, &deep, 300));
        ghosts
    })?;
    let pipe = Scene::load(&configs.join("pipe_through_sheet.toml"))?;
    let pipe = scene_scenario(&pipe, "pipe", |start| {
        straight_path(start, &(Translation3::new(0.0075, 0.0, -0.33) * start), 300)
    })?;
    Ok(vec![peg, pipe])
}

/// A slide-in unit (a car radio) pushed along -y into a slot whose side walls interfere with it
/// by [`slide_in::INTERFERENCE`]; with `allowance` the pair has [`slide_in::ALLOWANCE`]. The
/// oracle tests the walls set back by the allowance when one is given.
#[cfg(test)]
pub fn slide_in_unit(allowance: bool) -> Scenario {
    use slide_in::*;
    let unit = shapes::cuboid(Vector3::new(UNIT_WIDTH, 0.15, 0.05), 600);
    let wall = || shapes::cuboid(Vector3::new(WALL, 0.2, 0.1), 400);
    let wall_centre = UNIT_WIDTH / 2.0 - INTERFERENCE + WALL / 2.0;
    let mut obstacles = Vec::new();
    for side in [-1.0, 1.0] {
        let mut obstacle = ScenarioObstacle::new(wall(), at(side * wall_centre, 0.0, 0.0));
        if allowance {
            obstacle.allowance = Some(ALLOWANCE);
            obstacle.oracle_mesh = Some(Arc::new(
                wall()
                    .map_vertices(|v| v + Vector3::new(side * ALLOWANCE, 0.0, 0.0))
                    .expect("a translated box stays valid"),
            ));
        }
        obstacles.push(obstacle);
    }
    let start = at(0.0, 0.2, 0.0);
    Scenario {
        name: format!(
            "slide_in_{}",
            if allowance {
                "with_allowance"
            } else {
                "without"
            }
        ),
        part: Arc::new(unit),
        obstacles,
        start,
        ghosts: straight_path(&start, &at(0.0, 0.0, 0.0), 100),
        params: params(SlidingMetaphor::RubberBand),
    }
}

/// Dimensions of the slide-in scene, metres.
#[cfg(test)]
pub mod slide_in {
    /// Width of the unit (along x).
    pub const UNIT_WIDTH: f64 = 0.18;
    /// How far each side wall of the slot reaches into the unit by design.
    pub const INTERFERENCE: f64 = 0.0005;
    /// The allowance configured for the pair (twice the interference).
    pub const ALLOWANCE: f64 = 0.001;
    /// Thickness of the slot's side walls.
    pub const WALL: f64 = 0.02;
}

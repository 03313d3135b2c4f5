//! Benchmark B5 (sliding) and the scripted sliding scenes its tests share.
//!
//! A [`Scenario`] is a grasped part, static obstacles, a start pose and a scripted ghost path. [`run`]
//! drives a [`SlideMachine`] along the path over DOP-trees and, after every step that moved the
//! visible part, checks the visible pose against every obstacle with parry3d's mesh intersection
//! test: an oracle independent of our own collision detection. The time spent in the machine's
//! steps is measured with collision detection counted apart, so that the report gives the time per
//! contact point with and without it, and the sliding frame rate.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use nalgebra::{Translation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

use crate::args::OutputArgs;
use crate::oracle::PenetrationOracle;
use crate::report::{LinePlot, Series, Table, format_number, median};
use vas_server::collision::DopTree;
use vas_server::geometry::{TriMesh, shapes};
use vas_server::scene::Scene;
use vas_server::sliding::world::{Obstacle, PairwiseWorld, SlideBody, WorldStats};
use vas_server::sliding::{
    Event, Pose, RestReason, SlideMachine, SlideParams, SlideState, SlideStats, SlidingMetaphor,
};

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

/// What a run did and how long it took.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// The visible part's pose at the end.
    pub end_pose: Pose,
    /// Why the machine rested after the last frame.
    pub rest: RestReason,
    /// Visible poses that parry found intersecting an obstacle.
    pub penetrations: usize,
    /// Visible poses checked by parry.
    pub checked_poses: usize,
    /// Steps of the machine.
    pub steps: u64,
    /// The machine's counters.
    pub machine: SlideStats,
    /// The world's counters and collision / classification times.
    pub world: WorldStats,
    /// Time inside the machine's steps (collision detection included).
    pub step_time: Duration,
    /// Time inside the steps that handle contacts: bisection, classification, lift, and every
    /// step taken while contacts are remembered (collision detection included).
    pub contact_time: Duration,
    /// The part of `contact_time` spent in collision detection.
    pub contact_collision_time: Duration,
    /// The contact tolerance used (the tests' measure of "near").
    #[cfg(test)]
    pub tolerance: f64,
}

/// Drives the machine along the scenario's ghost path over DOP-trees; with `check`, tests every
/// new visible pose against every obstacle with parry (outside the timed steps). With
/// `split_long_queries`, long first-hit queries are split across the current rayon pool.
pub fn run(scenario: &Scenario, check: bool, split_long_queries: bool) -> RunResult {
    let part = Arc::new(SlideBody::<DopTree>::new(scenario.part.clone()));
    let (pivot, radius) = part.pivot_and_radius();
    let obstacles = scenario
        .obstacles
        .iter()
        .map(|o| {
            Obstacle::new(
                Arc::new(SlideBody::new(o.mesh.clone())),
                o.pose,
                o.allowance,
            )
        })
        .collect();
    let mut world = PairwiseWorld::new(part, obstacles).split_long_queries(split_long_queries);
    let oracle = check.then(|| {
        let obstacles = scenario.obstacles.iter().map(|o| {
            let mesh = o.oracle_mesh.as_deref().unwrap_or(&o.mesh);
            (mesh, o.pose)
        });
        PenetrationOracle::new(&scenario.part, obstacles)
    });
    let mut machine = SlideMachine::new(
        &scenario.start,
        pivot.coords,
        radius,
        scenario.params.clone(),
    );

    let mut result = RunResult {
        end_pose: scenario.start,
        rest: RestReason::Grasped,
        penetrations: 0,
        checked_poses: 0,
        steps: 0,
        machine: SlideStats::default(),
        world: WorldStats::default(),
        step_time: Duration::ZERO,
        contact_time: Duration::ZERO,
        contact_collision_time: Duration::ZERO,
        #[cfg(test)]
        tolerance: machine.tolerance(),
    };
    if let Some(oracle) = &oracle {
        result.checked_poses += 1;
        result.penetrations += usize::from(oracle.penetrates(&scenario.start));
    }
    let mut last_checked = scenario.start;
    for ghost in &scenario.ghosts {
        machine.set_ghost(ghost);
        loop {
            let handles_contact = machine.contacts().next().is_some()
                || matches!(
                    machine.state(),
                    SlideState::Approximating(_)
                        | SlideState::Classifying { .. }
                        | SlideState::Lifting { .. }
                );
            let collision_time = world.stats().collision_time;
            let start = Instant::now();
            let event = machine.step(&mut world);
            let elapsed = start.elapsed();
            result.step_time += elapsed;
            result.steps += 1;
            if handles_contact {
                result.contact_time += elapsed;
                result.contact_collision_time += world.stats().collision_time - collision_time;
            }
            let visible = machine.visible_pose();
            if let Some(oracle) = oracle.as_ref().filter(|_| visible != last_checked) {
                result.checked_poses += 1;
                result.penetrations += usize::from(oracle.penetrates(&visible));
                last_checked = visible;
            }
            if let Event::Rested(reason) = event {
                result.rest = reason;
                break;
            }
        }
    }
    result.end_pose = machine.visible_pose();
    result.machine = *machine.stats();
    result.world = *world.stats();
    result
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

/// Options of `vas-bench slide`.
#[derive(Debug, Clone, clap::Args)]
pub struct SlideBenchArgs {
    /// Triangle counts of the grasped part in the peg-in-hole scene.
    #[arg(long, value_delimiter = ',', default_values_t = [1_000, 5_000, 10_000, 50_000],
          value_parser = crate::args::triangle_count())]
    pub triangles: Vec<usize>,
    /// Runs per scene; the table shows medians.
    #[arg(long, default_value_t = 5, value_parser = crate::args::pass_count())]
    pub runs: usize,
    /// Thread counts to run every scene with (comma-separated; 0 is rayon's default): on more
    /// than one, long collision queries are split across the threads.
    #[arg(long, value_delimiter = ',', default_values_t = [1usize, 2])]
    pub threads: Vec<usize>,
    #[command(flatten)]
    pub output: OutputArgs,
    /// The folder of the scene configs peg_in_hole.toml and pipe_through_sheet.toml, which are
    /// run too.
    #[arg(long, default_value = "configs")]
    pub configs: PathBuf,
}

/// One row of B5.
#[derive(Debug, Clone, Serialize)]
pub struct SlideRow {
    /// Scene name.
    pub scene: String,
    /// Threads the collision queries could use (long ones are split across them).
    pub threads: usize,
    /// Triangles of the grasped part.
    pub triangles: usize,
    /// Contact points handled in one run: classified ones, plus the remembered ones each new
    /// direction takes as constraints (the paper re-detects them every cycle; we remember them).
    pub contact_points: u64,
    /// Median time per contact point of the steps that handle contacts (see
    /// [`RunResult::contact_time`]), collision detection not counted, microseconds.
    pub us_per_contact_excl_cd: f64,
    /// The same with collision detection counted, microseconds.
    pub us_per_contact_incl_cd: f64,
    /// Median sliding frames (ghost samples) per second, collision detection included.
    pub steps_per_s: f64,
    /// Visible poses parry found penetrating, over all runs.
    pub penetrations: usize,
}

/// Runs `scenario` `runs` times (the first also checked by the oracle) and summarises it; with
/// more than one thread in the current rayon pool, long collision queries are split across it.
pub fn measure(scenario: &Scenario, runs: usize) -> SlideRow {
    let threads = rayon::current_num_threads();
    let mut excl = Vec::new();
    let mut incl = Vec::new();
    let mut rate = Vec::new();
    let mut penetrations = 0;
    let mut contact_points = 0;
    for i in 0..runs.max(1) {
        let result = run(scenario, i == 0, threads > 1);
        penetrations += result.penetrations;
        contact_points = result.machine.contacts_classified + result.machine.contacts_projected;
        let contact_us = result.contact_time.as_secs_f64() * 1e6;
        let without_cd = contact_us - result.contact_collision_time.as_secs_f64() * 1e6;
        let contacts = contact_points.max(1) as f64;
        excl.push(without_cd / contacts);
        incl.push(contact_us / contacts);
        rate.push(scenario.ghosts.len() as f64 / result.step_time.as_secs_f64());
    }
    SlideRow {
        scene: scenario.name.clone(),
        threads,
        triangles: scenario.part.triangles().len(),
        contact_points,
        us_per_contact_excl_cd: median(&mut excl),
        us_per_contact_incl_cd: median(&mut incl),
        steps_per_s: median(&mut rate),
        penetrations,
    }
}

/// `vas-bench slide`: B5 over the sliding scenes; prints the table, writes JSON and SVG.
pub fn run_bench(args: &SlideBenchArgs) -> Result<Vec<SlideRow>> {
    let mut scenarios: Vec<Scenario> = args.triangles.iter().map(|&t| peg_in_hole(t)).collect();
    scenarios.push(pipe_through_sheet(5_000, false));
    scenarios.push(pipe_through_sheet(5_000, true));
    scenarios.push(block_scene(
        1,
        [0.5, 0.2, -0.05],
        SlidingMetaphor::RubberBand,
        1_200,
    ));
    scenarios.extend(config_scenarios(&args.configs)?);
    let mut table = Table::new([
        "scene",
        "threads",
        "triangles",
        "contact_points",
        "us_per_contact_excl_cd",
        "us_per_contact_incl_cd",
        "steps_per_s",
        "penetrations",
    ]);
    let mut rows = Vec::new();
    for &threads in &args.threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        rows.extend(pool.install(|| {
            scenarios
                .iter()
                .map(|s| measure(s, args.runs))
                .collect::<Vec<_>>()
        }));
    }
    for row in &rows {
        table.push_row([
            row.scene.clone(),
            row.threads.to_string(),
            row.triangles.to_string(),
            row.contact_points.to_string(),
            format_number(row.us_per_contact_excl_cd),
            format_number(row.us_per_contact_incl_cd),
            format_number(row.steps_per_s),
            row.penetrations.to_string(),
        ]);
    }
    print!("{}", table.render());
    args.output.write(&rows, || {
        let series = |threads: usize| Series {
            name: format!("steps_per_s, {threads} thread(s)"),
            points: rows
                .iter()
                .filter(|r| r.scene == "peg_in_hole" && r.threads == threads)
                .map(|r| (r.triangles as f64, r.steps_per_s))
                .collect(),
        };
        LinePlot {
            title: "B5: peg in hole, sliding frames per second".into(),
            x_label: "triangles of the peg".into(),
            y_label: "frames per second (collision detection included)".into(),
            log_x: true,
            log_y: true,
            series: args.threads.iter().map(|&t| series(t)).collect(),
        }
    })?;
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs with the oracle and asserts that no visible pose penetrated (and that there were
    /// poses to check).
    fn run_clean(scenario: &Scenario) -> RunResult {
        let result = run(scenario, true, false);
        assert!(
            result.checked_poses > 1,
            "{}: the oracle saw no motion",
            scenario.name
        );
        assert_eq!(
            result.penetrations, 0,
            "{}: visible part penetrated",
            scenario.name
        );
        result
    }

    fn assert_ends_near(result: &RunResult, expected: [f64; 3], within: f64) {
        let end = result.end_pose.translation.vector;
        let error = (end - Vector3::from(expected)).norm();
        assert!(
            error <= within,
            "ended at {:?}, expected {expected:?} within {within} ({:?})",
            end.as_slice(),
            result.rest
        );
    }

    #[test]
    fn a_block_dragged_diagonally_into_a_plane_ends_above_the_ghost_under_every_metaphor() {
        for metaphor in [
            SlidingMetaphor::RubberBand,
            SlidingMetaphor::SpiralSpring,
            SlidingMetaphor::Incremental,
        ] {
            let result = run_clean(&block_scene(0, [0.2, 0.1, -0.05], metaphor, 1_200));
            assert_ends_near(&result, [0.2, 0.1, 0.05], 3.0 * result.tolerance);
        }
    }

    #[test]
    fn into_a_crease_the_block_slides_along_it() {
        let result = run_clean(&block_scene(
            1,
            [0.5, 0.2, -0.05],
            SlidingMetaphor::RubberBand,
            1_200,
        ));
        assert_ends_near(&result, [0.25, 0.2, 0.05], 4.0 * result.tolerance);
    }

    #[test]
    fn into_a_corner_the_block_stops() {
        let result = run_clean(&block_scene(
            2,
            [0.5, 0.5, -0.05],
            SlidingMetaphor::RubberBand,
            1_200,
        ));
        assert_ends_near(&result, [0.25, 0.25, 0.05], 5.0 * result.tolerance);
        assert!(
            matches!(result.rest, RestReason::Blocked | RestReason::Stalled),
            "{:?}",
            result.rest
        );
    }

    #[test]
    fn a_misaligned_peg_with_one_percent_clearance_reaches_the_bottom_of_its_hole() {
        use peg::*;
        let result = run_clean(&peg_in_hole(2_000));
        let end = result.end_pose.translation.vector;
        let bottom_gap = end.z - PEG_LENGTH / 2.0 - BOTTOM;
        assert!(
            (0.0..=3.0 * result.tolerance).contains(&bottom_gap),
            "{bottom_gap} above the bottom"
        );
        // Pressed against the wall on the ghost's side, within the clearance.
        let clearance = HOLE_RADIUS - PEG_RADIUS;
        assert!(
            (0.0..=clearance + 3.0 * result.tolerance).contains(&end.x),
            "x = {}",
            end.x
        );
    }

    #[test]
    fn a_pipe_passes_through_a_hole_in_an_open_sheet_with_scrambled_normals_from_either_side() {
        for from_below in [false, true] {
            let scenario = pipe_through_sheet(2_000, from_below);
            let result = run_clean(&scenario);
            let ghost = scenario.ghosts.last().unwrap().translation.vector;
            assert_eq!(result.rest, RestReason::Reached, "{}", scenario.name);
            assert_ends_near(&result, ghost.into(), 2.0 * result.tolerance);
            assert!(
                result.machine.contacts_classified > 0,
                "the pipe never touched the rim"
            );
        }
    }

    #[test]
    fn the_config_scenes_slide_without_penetrating() {
        let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs");
        for scenario in config_scenarios(&configs).unwrap() {
            let result = run_clean(&scenario);
            assert!(
                result.machine.contacts_classified > 0,
                "{}: no contact",
                scenario.name
            );
            // The part went as deep as the ghost, into the hole or through it, however far the
            // ghost drifted off the axis.
            let depth =
                |pose: &Pose| pose.translation.vector.z - scenario.start.translation.vector.z;
            let ghost_depth = depth(scenario.ghosts.last().unwrap());
            let error = depth(&result.end_pose) - ghost_depth;
            assert!(
                error.abs() <= 3.0 * result.tolerance,
                "{}: {error} off",
                scenario.name
            );
        }
    }

    #[test]
    fn a_slide_in_unit_goes_in_with_its_allowance_and_not_without() {
        let with = run_clean(&slide_in_unit(true));
        assert_eq!(with.rest, RestReason::Reached);
        assert_ends_near(&with, [0.0, 0.0, 0.0], 2.0 * with.tolerance);

        let without = run_clean(&slide_in_unit(false));
        // Stopped at the slot's mouth: the unit's leading face (y - 0.075) at the walls' front (0.1).
        let y = without.end_pose.translation.vector.y;
        assert!((0.175..0.176).contains(&y), "stopped at y = {y}");
    }
}

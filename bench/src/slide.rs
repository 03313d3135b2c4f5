//! Benchmark B5 (sliding), over the scripted sliding scenes of `scenes` that its tests share.
//!
//! A [`Scenario`] is a grasped part, static obstacles, a start pose and a scripted ghost path. [`run`]
//! drives a [`SlideMachine`] along the path over DOP-trees and, after every step that moved the
//! visible part, checks the visible pose against every obstacle with parry3d's mesh intersection
//! test: an oracle independent of our own collision detection. The time spent in the machine's
//! steps is measured with collision detection counted apart, so that the report gives the time per
//! contact point with and without it, and the sliding frame rate.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use serde::Serialize;

use crate::args::OutputArgs;
use crate::oracle::PenetrationOracle;
use crate::report::{LinePlot, Series, Table, format_number, median};
use vas_server::collision::DopTree;
use vas_server::sliding::world::{Obstacle, PairwiseWorld, SlideBody, WorldStats};
use vas_server::sliding::{
    Event, Pose, RestReason, SlideMachine, SlideState, SlideStats, SlidingMetaphor,
};

mod scenes;

pub use scenes::*;

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
    /// Whether contact approximation starts with conservative advancement, per pass
    /// (comma-separated; both by default, so that the two compare in one run).
    #[arg(long, value_delimiter = ',', default_values_t = [false, true])]
    pub advance: Vec<bool>,
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
    /// Whether contact approximation started with conservative advancement.
    pub advance: bool,
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
    /// Static collision tests the machine asked of its world per ghost frame (the same in
    /// every run).
    pub collision_tests_per_frame: f64,
    /// Distance queries the machine asked of its world per ghost frame (conservative
    /// advancement), counted apart from the collision tests.
    pub distance_queries_per_frame: f64,
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
    let (mut collision_tests, mut distance_queries) = (0, 0);
    for i in 0..runs.max(1) {
        let result = run(scenario, i == 0, threads > 1);
        penetrations += result.penetrations;
        contact_points = result.machine.contacts_classified + result.machine.contacts_projected;
        collision_tests = result.machine.collision_checks;
        distance_queries = result.machine.distance_queries;
        let contact_us = result.contact_time.as_secs_f64() * 1e6;
        let without_cd = contact_us - result.contact_collision_time.as_secs_f64() * 1e6;
        let contacts = contact_points.max(1) as f64;
        excl.push(without_cd / contacts);
        incl.push(contact_us / contacts);
        rate.push(scenario.ghosts.len() as f64 / result.step_time.as_secs_f64());
    }
    let frames = scenario.ghosts.len().max(1) as f64;
    SlideRow {
        scene: scenario.name.clone(),
        threads,
        advance: scenario.params.conservative_advancement,
        triangles: scenario.part.triangles().len(),
        contact_points,
        us_per_contact_excl_cd: median(&mut excl),
        us_per_contact_incl_cd: median(&mut incl),
        steps_per_s: median(&mut rate),
        collision_tests_per_frame: collision_tests as f64 / frames,
        distance_queries_per_frame: distance_queries as f64 / frames,
        penetrations,
    }
}

/// The scenario with conservative advancement on or off.
fn with_advance(scenario: &Scenario, advance: bool) -> Scenario {
    let mut scenario = scenario.clone();
    scenario.params.conservative_advancement = advance;
    scenario
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
        "advance",
        "triangles",
        "contact_points",
        "us_per_contact_excl_cd",
        "us_per_contact_incl_cd",
        "steps_per_s",
        "collision_tests_per_frame",
        "distance_queries_per_frame",
        "penetrations",
    ]);
    let mut rows = Vec::new();
    for &threads in &args.threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        for &advance in &args.advance {
            rows.extend(pool.install(|| {
                scenarios
                    .iter()
                    .map(|scenario| measure(&with_advance(scenario, advance), args.runs))
                    .collect::<Vec<_>>()
            }));
        }
    }
    for row in &rows {
        table.push_row([
            row.scene.clone(),
            row.threads.to_string(),
            if row.advance { "on" } else { "off" }.to_owned(),
            row.triangles.to_string(),
            row.contact_points.to_string(),
            format_number(row.us_per_contact_excl_cd),
            format_number(row.us_per_contact_incl_cd),
            format_number(row.steps_per_s),
            format_number(row.collision_tests_per_frame),
            format_number(row.distance_queries_per_frame),
            row.penetrations.to_string(),
        ]);
    }
    print!("{}", table.render());
    args.output.write(&rows, || {
        let series = |threads: usize| Series {
            name: format!("steps_per_s, {threads} thread(s)"),
            points: rows
                .iter()
                .filter(|r| r.scene == "peg_in_hole" && r.threads == threads && !r.advance)
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
    use nalgebra::Vector3;
    use std::path::Path;

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
    fn conservative_advancement_never_penetrates_and_ends_where_bisection_does() {
        let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs");
        let mut scenarios = vec![
            block_scene(0, [0.2, 0.1, -0.05], SlidingMetaphor::SpiralSpring, 1_200),
            block_scene(2, [0.5, 0.5, -0.05], SlidingMetaphor::RubberBand, 1_200),
            peg_in_hole(2_000),
            pipe_through_sheet(2_000, true),
            slide_in_unit(true),
        ];
        scenarios.extend(config_scenarios(&configs).unwrap());
        for scenario in &scenarios {
            let bisected = run_clean(scenario);
            let advanced = run_clean(&with_advance(scenario, true));
            // Every scene but the slide-in unit (which never collides) approaches a contact.
            assert_eq!(
                advanced.machine.distance_queries > 0,
                bisected.machine.contacts_classified > 0,
                "{}",
                scenario.name
            );
            assert_eq!(bisected.machine.distance_queries, 0);
            let apart = (advanced.end_pose.translation.vector
                - bisected.end_pose.translation.vector)
                .norm();
            assert!(
                apart <= 3.0 * advanced.tolerance,
                "{}: ends {apart} m apart",
                scenario.name
            );
            assert_eq!(advanced.rest, bisected.rest, "{}", scenario.name);
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
